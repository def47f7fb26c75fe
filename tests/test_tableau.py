"""Runge-Kutta methods are data that check themselves."""

import numpy as np
import pytest

from sweep.solvers import RK4, ButcherTableau


def test_rk4_is_a_valid_fourth_order_tableau():
    assert RK4.order == 4 and len(RK4.b) == 4
    np.testing.assert_allclose(np.sum(RK4.a, axis=1), RK4.c)


@pytest.mark.parametrize("change, words", [
    ({"b": (1 / 6, 1 / 3, 1 / 3, 1 / 5)}, "order condition"),
    ({"c": (0.0, 0.5, 0.4, 1.0)}, "row sums"),
    ({"a": ((0.0, 0.1, 0.0, 0.0), (0.5, 0.0, 0.0, 0.0), (0.0, 0.5, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0))}, "lower"),
])
def test_broken_tableaux_are_refused(change, words):
    fields = {"name": "x", "c": RK4.c, "a": RK4.a, "b": RK4.b, "order": RK4.order, **change}
    with pytest.raises(ValueError, match=words):
        ButcherTableau(**fields)


def test_third_order_method_is_not_fourth_order():
    kutta3 = {"name": "kutta3", "c": (0.0, 0.5, 1.0), "a": ((0, 0, 0), (0.5, 0, 0), (-1.0, 2.0, 0)),
              "b": (1 / 6, 2 / 3, 1 / 6)}
    ButcherTableau(**kutta3, order=3)
    with pytest.raises(ValueError, match="order condition"):
        ButcherTableau(**kutta3, order=4)
