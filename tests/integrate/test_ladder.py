"""The step ladder of the relaxed-slip lanes (sweep/integrate/ladder.py) on synthetic runs with a known error e(h).

The runner stands in for the lane kernel: run at step h returns X + e(h) (and a status), so the true error of
every returned value is known exactly, independently of the ladder's own arithmetic.
"""

from __future__ import annotations

import numpy as np
import pytest

from sweep.integrate import ladder
from sweep.status import Status

OK, NONFINITE, MAX_STEPS = int(Status.OK), int(Status.NONFINITE), int(Status.MAX_STEPS)
X = 3.0
P = 4


def runner(error, status=None, log=None):
    """run(points, steps) for the error model ``error(point, h)`` (and ``status(point, h)``, default ok)."""

    def run(points, steps):
        x = np.array([X + error(int(p), float(h)) for p, h in zip(points, steps)])
        s = np.array([OK if status is None else status(int(p), float(h)) for p, h in zip(points, steps)], np.int8)
        x[s != OK] = np.nan
        if log is not None:
            log.extend(zip(points.tolist(), steps.tolist()))
        n = np.ceil(10.0 / steps).astype(np.int32)
        return x, np.zeros(points.size), s, n

    return run


def climb(run, n, h0=0.3, rtol=1e-6, atol=1e-12, fixed=False):
    return ladder.climb(run, np.arange(n), np.full(n, h0), P, rtol, atol, 0.0, fixed)


def test_asymptotic_errors_give_sharp_estimates_and_per_point_steps():
    """e = C h^4 over four decades of C, both signs: every point meets the tolerance with an estimate of about
    SHARP_GAIN x its true error, and lands near TARGET x tolerance instead of far below it (C >= 1e-3: the
    tolerance needs rungs finer than the pilot step 0.3 / MIN_RATIO)."""
    C = np.array([1e-3, -1e-2, 1e-1, -1.0, 10.0])
    rtol = 1e-6
    res = climb(runner(lambda p, h: C[p] * h**P), C.size, rtol=rtol)
    true = np.abs(res.xi - X)
    tol = rtol * np.abs(res.xi) + 1e-12
    assert np.all(res.status == OK)
    assert np.all(true <= tol)
    assert np.all(res.error >= true) and np.all(res.error <= 1.1 * ladder.SHARP_GAIN * true)
    assert np.all(res.error <= tol) and np.all(true >= tol / 20), "landed far below the tolerance"
    assert np.all(np.diff(res.step) < 0), "harder points get finer steps"


def test_stagnating_pair_is_not_trusted():
    """Two error parts of opposite sign, e = C (h^4 - 7.2 h^8): e(0.6) and e(0.3) nearly equal (the pair's
    difference is ~0.1x the error); the ladder sees successive differences off the h^4 ratio and goes on until
    it can vouch for the value."""
    def error(p, h):
        return 1e-4 * (h**P - 7.2 * h ** (2 * P))
    res = climb(runner(error), 1, rtol=1e-7)
    e06, e03 = error(0, 0.6), error(0, 0.3)
    assert abs(e06 - e03) < 0.2 * abs(e03), "the model must stagnate at the pilot pair"
    assert res.status[0] == OK and res.runs[0] > 3
    assert abs(res.xi[0] - X) <= res.error[0] <= 100 * abs(res.xi[0] - X)


def test_non_finite_pilot_goes_on_down():
    """Runs beyond a stability limit (h > 0.5) go non-finite: no estimate from them, the point takes finer rungs
    and ends ok with a bounding estimate."""
    res = climb(runner(lambda p, h: 1e-3 * h**P, lambda p, h: NONFINITE if h > 0.5 else OK), 1, h0=0.4)
    assert res.status[0] == OK and res.runs[0] >= 4
    assert abs(res.xi[0] - X) <= res.error[0] <= 1e-6 * X


def test_max_steps_ends_the_point():
    log = []
    res = climb(runner(lambda p, h: 1e-3 * h**P, lambda p, h: MAX_STEPS if h < 0.35 else OK, log), 1)
    assert res.status[0] == MAX_STEPS and np.isnan(res.error[0]) and len(log) == 2


def test_fixed_ladder_returns_the_users_step():
    log = []
    res = climb(runner(lambda p, h: 1e-3 * h**P, log=log), 2, h0=0.1, fixed=True)
    assert sorted(h for _, h in log) == pytest.approx([0.1, 0.1, 0.2, 0.2, 0.4, 0.4])
    assert np.all(res.step == 0.1) and np.all(res.xi - X == pytest.approx(1e-3 * 0.1**P))


def test_an_error_that_never_shrinks_is_reported_over_tolerance():
    """Noise-like errors (no h dependence to extrapolate): the ladder stops after MAX_RUNS runs with an estimate
    above the tolerance (the engine then marks the point error_above_tol), never a small one."""
    rng = np.random.default_rng(1)
    noise = {}
    res = climb(runner(lambda p, h: noise.setdefault(h, 1e-3 * rng.standard_normal())), 1)
    assert res.runs[0] == ladder.MAX_RUNS
    assert res.error[0] > 1e-6 * abs(res.xi[0])


def test_rounding_over_tolerance_ends_the_ladder():
    """Where amplified rounding alone exceeds the tolerance, finer rungs cannot help: the point stops after the
    first rung with that rounding in its estimate (over tolerance: the engine marks it error_above_tol)."""
    growth = np.array([0.0, 50.0])  # exp(50 * 3) * 2e-16 * 3 >> 1e-6 * 3
    res = ladder.climb(runner(lambda p, h: 1e-3 * h**P), np.arange(2), np.full(2, 0.3), P, 1e-6, 1e-12, 2e-16,
                       False, growth=growth)
    assert res.runs[1] == 3 and res.error[1] >= ladder.rounding_error(2e-16, 0, X, 50.0) > 1e-6 * X
    assert res.error[0] <= 1e-6 * X and res.runs[0] >= 3


@pytest.mark.parametrize("q", [3.2, 4.0, 4.9])
def test_observed_order_of_a_power_law(q):
    """eq. (1) solved for q recovers the order of e = C h^q on uneven ladders; orders farther than ORDER_WINDOW
    from p are not asymptotic (NaN)."""
    h = np.array([[0.8, 0.4, 0.1], [2.0, 1.0, 0.6], [0.3, 0.15, 0.02]])
    x = -2.5 * h**q
    d_ab, d_bc = x[:, 1] - x[:, 0], x[:, 2] - x[:, 1]
    np.testing.assert_allclose(ladder.observed_order(d_ab, d_bc, *h.T, P), q, rtol=1e-9)
    far = -2.5 * h ** (P + 1.5)
    assert np.all(np.isnan(ladder.observed_order(far[:, 1] - far[:, 0], far[:, 2] - far[:, 1], *h.T, P)))
