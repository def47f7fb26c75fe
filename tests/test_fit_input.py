"""Bad input to sweep.fit: one clear error naming the field and the value, raised before any engine run."""

from __future__ import annotations

import numpy as np
import pytest

import sweep
from sweep.fit import Curve, RelaxedSlips, stack

T = np.array([0.1, 1.0, 10.0, 100.0])
X = np.array([1e-8, 5e-8, 1e-7, 1.2e-7])
KM, V = 2.8e5, 1e-6


@pytest.fixture(autouse=True)
def no_engine(monkeypatch):
    """Any engine run fails the test: the errors must come before any work."""
    def forbidden(*args, **kwargs):
        raise AssertionError("the engine ran before the input was checked")
    monkeypatch.setattr(stack, "forward", forbidden)


def _fit(data, **kw):
    return sweep.fit(data, **{"free": ("A", "m1", "m2"), "params": "sample2", **kw})


@pytest.mark.parametrize("make, words", [
    (lambda: Curve(np.array([0.1, 1.0, 0.5, 10.0]), X, KM, V), ["curve 'curve'", "t[2] = 0.5", "increasing"]),
    (lambda: Curve(T, np.array([1e-8, np.nan, 1e-7, 1.2e-7]), KM, V), ["curve 'curve'", "x[1] = nan", "finite"]),
    (lambda: Curve(T, np.array([1e-8, -5e-8, 1e-7, 1.2e-7]), KM, V), ["x[1] = -5e-08", ">= 0"]),
    (lambda: Curve(T, X, -1.0, V), ["K_over_M[0] = -1.0", "> 0"]),
    (lambda: Curve(T, X[:3], KM, V), ["x has 3 values", "expected 4"]),
    (lambda: RelaxedSlips([1e5], [1e-6], [np.inf]), ["dx_inf[0] = inf"]),
])
def test_bad_data_is_refused_naming_field_and_value(make, words):
    with pytest.raises(sweep.InputError) as exc:
        make()
    msg = str(exc.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, (w, msg)


@pytest.mark.parametrize("kw, words", [
    (dict(free=("A", "m3")), ["free parameter 'm3' does not exist", "allowed"]),
    (dict(free=("A", "m0")), ["'m0' does not exist"]),
    (dict(bounds={"A": (0.01, 0.1)}), ["start A = 0.007", "outside its bounds [0.01, 0.1]"]),
    (dict(bounds={"A": (0.0, 0.1)}), ["bounds A", "must stay > 0"]),
    (dict(bounds={"m2": (0.1, 0.0)}), ["bounds m2", "lower bound must be below"]),
    (dict(bounds={"D0": (1e-7, 1e-5)}), ["bounds name 'D0'", "not free"]),
    (dict(params="sample9"), ["params", "sample9"]),
    (dict(rtol=0.1), ["rtol must be in"]),
])
def test_bad_settings_are_refused_naming_field_and_value(kw, words):
    with pytest.raises(sweep.InputError) as exc:
        _fit(Curve(T, X, KM, V), **kw)
    msg = str(exc.value)
    for w in words:
        assert w in msg, (w, msg)


def test_a_curve_on_the_stick_slip_side_for_every_parameter_set_in_the_bounds_is_refused():
    """K/M = 1e3 s^-2 (chi = 7e-5 for sample2's D0) against mu1 >= 0.01 everywhere in the bounds."""
    with pytest.raises(sweep.InputError) as exc:
        _fit(Curve(T, X, 1e3, V, name="soft"), bounds={"m1": (0.01, 0.02), "m2": (0.0, 0.01)})
    msg = str(exc.value)
    for w in ("curve 'soft'", "K_over_M = 1000", "V = 1e-06", "stick-slip side"):
        assert w in msg, (w, msg)


def test_the_same_curve_is_accepted_when_the_bounds_allow_steady_sliding():
    """Where some parameter set in the bounds has chi > mu1, the check passes (and the engine is reached)."""
    with pytest.raises(AssertionError, match="engine ran"):
        _fit(Curve(T, X, 1e3, V, name="soft"), bounds={"m1": (-0.02, 0.02), "m2": (0.0, 0.01)})


def test_noise_given_for_some_data_sets_only_is_refused():
    with pytest.raises(sweep.InputError, match="noise for every data set or for none"):
        _fit([Curve(T, X, KM, V, noise=1e-9), Curve(T, X, KM, 2e-6)])
