"""Runge-Kutta methods are data that check themselves.

The checks here are independent of the module's own output: tree counts and densities against known
combinatorics, published error coefficients, and the empirical order of a small numpy stepper.
"""

import dataclasses
from collections import Counter
from math import factorial, prod

import numpy as np
import pytest

from sweep.integrate.solvers import DOP853, DP5, METHODS, RK4, ButcherTableau
from sweep.integrate.solvers.rosenbrock import rosenbrock_conditions
from sweep.integrate.solvers.tableau import DOP853_ER3, rooted_trees, tree_density, tree_name


def test_rk4_is_a_valid_fourth_order_tableau():
    assert RK4.order == 4 and len(RK4.b) == 4
    np.testing.assert_allclose(np.sum(RK4.a, axis=1), RK4.c)


@pytest.mark.parametrize("change, words", [
    ({"b": (1 / 6, 1 / 3, 1 / 3, 1 / 5)}, "order condition"),
    ({"c": (0.0, 0.5, 0.4, 1.0)}, "row sums"),
    ({"a": ((0.0, 0.1, 0.0, 0.0), (0.5, 0.0, 0.0, 0.0), (0.0, 0.5, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0))}, "lower"),
    ({"b": (0.5, 0.5)}, "shapes"),
    ({"b_hat": (0.25, 0.25, 0.25)}, "shapes"),
    ({"order": 0}, "order of b must be in 1..8"),
    ({"order": 9}, "order of b must be in 1..8"),
    ({"order_hat": 3}, "order_hat=3 given without b_hat"),
    ({"b_hat": RK4.b, "order_hat": 4}, "b_hat equals b"),
    ({"b_hat": (0.0, 0.0, 1.0, 0.0), "order_hat": 0}, "order of b_hat must be in 1..8"),
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


def test_sequences_are_stored_as_float_tuples():
    euler = ButcherTableau(name="euler", c=[0], a=[[0]], b=[1], order=1)
    assert euler.c == (0.0,) and euler.a == ((0.0,),) and euler.b == (1.0,)
    assert isinstance(euler.b[0], float) and hash(euler) == hash(dataclasses.replace(euler))


# --- rooted trees ---------------------------------------------------------------------------------------


def _symmetry(tree) -> int:
    """sigma(t): order of the automorphism group (product over the root's distinct subtrees u of sigma(u)^m m!)."""
    return prod(_symmetry(u) ** m * factorial(m) for u, m in Counter(tree).items())


def test_number_of_rooted_trees_per_order():
    assert [len(rooted_trees(n)) for n in range(1, 9)] == [1, 1, 2, 4, 9, 20, 48, 115]  # OEIS A000081
    assert sum(len(rooted_trees(n)) for n in range(1, 9)) == 200


@pytest.mark.parametrize("n", range(1, 9))
def test_tree_densities_count_monotone_labellings(n):
    """alpha(t) = n!/(sigma(t) gamma(t)) labellings of t with increasing labels; summed over |t| = n: (n-1)!."""
    trees = rooted_trees(n)
    assert len(set(trees)) == len(trees) == len({tree_name(t) for t in trees})
    assert sum(factorial(n) // (_symmetry(t) * tree_density(t)) for t in trees) == factorial(n - 1)


def test_fourth_order_trees_and_densities():
    assert {tree_name(t): tree_density(t) for t in rooted_trees(4)} == {
        "[τ,τ,τ]": 4, "[τ,[τ]]": 8, "[[τ,τ]]": 12, "[[[τ]]]": 24}


# --- built-in methods -----------------------------------------------------------------------------------


@pytest.mark.parametrize("method, order, order_hat, fsal, adaptive, stages", [
    (RK4, 4, 0, False, False, 4),
    (DP5, 5, 4, True, True, 7),
    (DOP853, 8, 5, False, True, 12),
])
def test_registered_methods_report_their_properties(method, order, order_hat, fsal, adaptive, stages):
    assert METHODS[method.name] is method
    assert (method.order, method.order_hat, method.fsal, method.adaptive, method.stages) == (
        order, order_hat, fsal, adaptive, stages)
    assert method.error_order == (min(order, order_hat) if adaptive else 0)
    c, a, b, e = method.arrays()
    assert all(x.dtype == np.float64 and x.flags.c_contiguous for x in (c, a, b, e))
    assert c.shape == b.shape == e.shape == (stages,) and a.shape == (stages, stages)
    np.testing.assert_array_equal(e, np.subtract(b, method.b_hat) if adaptive else 0.0)
    assert dataclasses.replace(method) == method  # the published coefficients pass their own checks


def test_registry_is_read_only():
    assert list(METHODS) == ["rk4", "dp5", "dop853", "ros4"]
    with pytest.raises(TypeError):
        METHODS["euler"] = RK4  # type: ignore[index]


def test_dp5_error_weights_are_the_published_ones():
    """Dormand & Prince (1980): b - b_hat = (71/57600, 0, -71/16695, 71/1920, -17253/339200, 22/525, -1/40)."""
    published = (71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40)
    np.testing.assert_allclose(DP5.arrays()[3], published, rtol=1e-14, atol=1e-17)


def test_dop853_third_order_estimate_is_of_order_three():
    """b - er3 (dop853.f's bhh: weights on stages 1, 9 and 12 only) is a third-order solution and no more, so that
    err3 = h er3.k is an O(h^4) estimate; the tableau's order conditions check it, not the weights' source."""
    bhh = tuple(b - e for b, e in zip(DOP853.b, DOP853_ER3))
    assert [i for i, w in enumerate(bhh) if w != 0.0] == [0, 8, 11]
    dataclasses.replace(DOP853, b_hat=bhh, order_hat=3)
    with pytest.raises(ValueError, match="order condition .* of order 4 fails"):
        dataclasses.replace(DOP853, b_hat=bhh, order_hat=4)


@pytest.mark.parametrize("method, i, j", [(RK4, 2, 1), (DP5, 4, 2), (DOP853, 5, 2), (DOP853, 11, 10)])
def test_one_perturbed_coefficient_breaks_an_order_condition(method, i, j):
    a = [list(row) for row in method.a]
    a[i][j] += 1e-6
    c = [ci + (1e-6 if k == i else 0.0) for k, ci in enumerate(method.c)]  # keep a . 1 = c
    with pytest.raises(ValueError, match=rf"^{method.name}: order condition for b .* tree \[.*1/gamma = 1/\d+"):
        dataclasses.replace(method, a=a, c=c)


@pytest.mark.parametrize("method", [DP5, DOP853])
def test_one_perturbed_embedded_weight_breaks_an_order_condition(method):
    b_hat = (method.b_hat[0] + 1e-6, *method.b_hat[1:])
    with pytest.raises(ValueError, match=rf"^{method.name}: order condition for b_hat of order .* tree τ "):
        dataclasses.replace(method, b_hat=b_hat)


@pytest.mark.parametrize("method, claim", [
    (RK4, {"order": 5}), (DP5, {"order": 6}), (DP5, {"order_hat": 5}), (DOP853, {"order_hat": 6}),
])
def test_claiming_one_order_too_many_fails(method, claim):
    order = next(iter(claim.values()))
    with pytest.raises(ValueError, match=rf"order condition .* of order {order} fails at tree .*\(\|t\|={order}\)"):
        dataclasses.replace(method, **claim)


# --- empirical order with an independent stepper --------------------------------------------------------


def _rhs(t: float, y: float) -> float:
    return y * np.cos(t)  # y(0) = 1: y = exp(sin t)


def _stages(method: ButcherTableau, t: float, y: float, h: float) -> np.ndarray:
    c, a = np.array(method.c), np.array(method.a)
    k = np.zeros(len(c))
    for i in range(len(c)):
        k[i] = _rhs(t + c[i] * h, y + h * (a[i, :i] @ k[:i]))
    return k


def _max_error(method: ButcherTableau, weights: np.ndarray, n: int) -> float:
    """Largest global error on the grid of n fixed steps over [0, 1]."""
    h, y, error = 1.0 / n, 1.0, 0.0
    for m in range(n):
        y += h * (weights @ _stages(method, m * h, y, h))
        error = max(error, abs(y - np.exp(np.sin((m + 1) * h))))
    return error


@pytest.mark.parametrize("method, embedded, steps", [
    (RK4, False, (16, 20, 24, 32, 40, 48, 64)),
    (DP5, False, (16, 20, 24, 32, 40, 48, 64)),
    (DP5, True, (16, 20, 24, 32, 40, 48, 64)),
    (DOP853, False, (5, 6, 7, 8, 10)),  # h = 0.2 .. 0.1: errors 3e-12 .. 2e-14, above roundoff
    (DOP853, True, (16, 20, 24, 32, 40, 48, 64)),
])
def test_empirical_convergence_order(method, embedded, steps):
    """Slope of log(max global error) against log h on y' = y cos t; the embedded weights converge at order_hat.

    Steps are in the asymptotic range: coarser steps bend the fit of the embedded 4th-order DP5 weights
    (whose h^4 error constant is small on this problem) and finer ones reach roundoff for DOP853."""
    weights = np.array(method.b_hat if embedded else method.b)
    errors = [_max_error(method, weights, n) for n in steps]
    slope = np.polyfit(np.log(1.0 / np.array(steps)), np.log(errors), 1)[0]
    claimed = method.order_hat if embedded else method.order
    assert abs(slope - claimed) < 0.3, (method.name, embedded, slope, errors)


def test_fsal_stage_is_the_derivative_at_the_step_end():
    t, y, h = 0.3, np.exp(np.sin(0.3)), 0.1
    k = _stages(DP5, t, y, h)
    y1 = y + h * (np.array(DP5.b) @ k)
    assert k[-1] == pytest.approx(_rhs(t + h, y1), rel=1e-15)


# ---------------------------------------------------------------------------------------------- Rosenbrock

@pytest.mark.parametrize("name, order, r_inf", [("ROS4", 4, 1.0 / 3.0), ("RODAS3", 3, 0.0)])
def test_rosenbrock_methods_pass_their_order_conditions_and_are_stable_for_decaying_modes(name, order, r_inf):
    import sweep.integrate.solvers

    tab = getattr(sweep.integrate.solvers, name)
    alpha, gam, b = tab.standard_form()
    n_conditions = {3: 4, 4: 8}[order]
    for cond, value, want in rosenbrock_conditions(alpha, gam, b, tab.gamma)[:n_conditions]:
        assert value == pytest.approx(want, abs=1e-13), cond
    if order == 3:  # and not order 4: the fourth-order conditions fail
        assert any(abs(v - w) > 1e-3 for _, v, w in rosenbrock_conditions(alpha, gam, b, tab.gamma)[4:])
    assert abs(tab.stability_at_infinity()) == pytest.approx(r_inf, abs=1e-12)  # RODAS3: L-stable
    # A-stability on the imaginary axis and in the left half-plane: |R(z)| <= 1 (HW IV.7.14)
    B = alpha + gam + tab.gamma * np.eye(4)
    z = np.concatenate([1j * np.geomspace(1e-3, 1e4, 200), -np.geomspace(1e-3, 1e4, 200),
                        np.geomspace(1e-3, 1e4, 200) * np.exp(1j * 0.75 * np.pi)])
    R = np.array([1.0 + zz * b @ np.linalg.solve(np.eye(4) - zz * B, np.ones(4)) for zz in z])
    assert np.all(np.abs(R) <= 1.0 + 1e-12)


def test_rosenbrock_tableau_catches_a_wrong_coefficient():
    from sweep.integrate.solvers import ROS4, RosenbrockTableau

    m = list(ROS4.m)
    m[1] *= 1.0 + 1e-9
    with pytest.raises(ValueError, match="order condition"):
        RosenbrockTableau(**{**vars(ROS4), "m": tuple(m)})
