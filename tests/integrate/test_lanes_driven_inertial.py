"""Inertial driven points in lanes (sweep/integrate/lanes_driven_inertial.py): the limit cycles of scipy's Radau on
the full inertial equations (stiff stick phases, a rebound inside the slip, the slow manifold at small gamma), the
small oscillations of the linear theory (the cubic), the one-point driver's regimes on a grid, a point's numbers
independent of its lane and neighbours, and the budgets."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sweep import physics
from sweep.integrate.batch import driven_batch
from sweep.integrate.driven import DrivenOutputs, DrivenSettings, Regime
from sweep.integrate.lanes_driven import LANES, DrivenJob
from sweep.integrate.lanes_driven_inertial import InertialPoints, inertial_lanes
from sweep.status import Status
from tests.integrate.test_driven import _radau_inertial

SETTINGS = DrivenSettings(1e-3, 1e-9, 2000, 1_000_000)


def run_lanes(k, a, b, g, settings=SETTINGS, groups=1, order=None):
    k, a, b, g = (np.asarray(v, float) for v in (k, a, b, g))
    out = DrivenOutputs.empty(k.size)
    points = np.arange(k.size) if order is None else np.asarray(order)
    inertial_lanes()[1](InertialPoints(k, a, b, g), DrivenJob(points, *settings), groups, out)
    return out


@pytest.mark.parametrize("k, a, b, G, periods, rtol_period", [
    # issue 35's grid (gamma/A 2.1e-7): a rebound of ~6.5e-6 in z after each slip, not a cycle (sweep.accuracy.REBOUND)
    (1.3461091409855348, 3.9567230876801, 0.4714285714285714, 2.080342840500114e-07, 6, 1e-5),
    # issue 35's grid: most of the cycle on the slow manifold (gamma/A 2.9e-5)
    (0.1343, 1.6272, 0.4714, 2.91e-5, 6, 1e-5),
    # deep stick-slip at gamma/A = 1e-2: stiff stick phases (RODAS3 steps in the scalar loop, then the manifold)
    pytest.param(0.75, 1.5, 0.5, 1e-2, 20, 1e-4, marks=pytest.mark.slow),
])
def test_lanes_match_scipy_radau(k, a, b, G, periods, rtol_period):
    """The limit cycle's half peak-to-peak stretch agrees with scipy's Radau (analytic Jacobian, rtol 1e-9, on the
    full inertial equations; tests/integrate/test_driven.py) to 1e-6, its period to the peaks' sampling grid. The
    point runs in a full batch of lanes beside the other cases."""
    cases = [(1.3461091409855348, 3.9567230876801, 0.4714285714285714, 2.080342840500114e-07),
             (0.1343, 1.6272, 0.4714, 2.91e-5), (k, a, b, G)] * (LANES // 2)
    out = run_lanes(*zip(*cases))
    j = len(cases) - 1
    assert out.regime[j] == Regime.STICK_SLIP and out.status[j] == Status.OK
    period = out.period[j]
    horizon = periods * period
    sol = _radau_inertial(k, a, b, G, horizon)
    t = np.linspace(horizon - 2 * period, horizon, 400_001)
    z = sol.sol(t)[0]
    assert (z.max() - z.min()) / 2 == pytest.approx(out.amplitude[j], rel=1e-6)
    peaks = t[1:-1][(z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:]) & (z[1:-1] > 0.0)]
    assert np.diff(peaks)[-1] == pytest.approx(period, rel=rtol_period)


def test_small_oscillations_follow_the_cubic():
    """Near the inertial Hopf line the small oscillations follow the complex pair of gamma s^3 + (gamma + A) s^2 +
    (chi - mu1) s + chi = 0 (docs/physics.md 3b; reduced by A): period to 1e-4, growth rate to 2e-3 (the third,
    real root decays within the first cycles), for gamma/A 0.01 (decaying), 1 (decaying) and 10 (growing)."""
    A, mu1 = 0.007, 0.0125
    cases = [(0.01, 1.02), (1.0, 1.05), (10.0, 0.98)]
    chi = np.array([r * physics.chi_c_inertial(mu1, A, G * A) for G, r in cases])
    G = np.array([c[0] for c in cases])
    out = run_lanes(chi / A, np.full(3, mu1 / A), np.zeros(3), G, DrivenSettings(1e-5, 1e-10, 6, 1_000_000))
    for j, (gamma_over_A, _) in enumerate(cases):
        roots = physics.characteristic_roots(chi[j], mu1, A, gamma_over_A * A)
        pair = roots[np.argmax(np.abs(roots.imag))]
        assert out.period[j] == pytest.approx(2.0 * math.pi / abs(pair.imag), rel=1e-4)
        assert out.growth_rate[j] == pytest.approx(pair.real, rel=2e-3, abs=1e-6)


def test_lanes_keep_the_one_point_drivers_regimes_on_a_grid():
    """A grid across the Hopf line (chi/mu1 0.1..3, m2/A 0.5, gamma/A 1e-7..1e-2): every point has the one-point
    driver's regime and status (on the slow manifold where inertia is small, as the lanes); stick-slip amplitudes and
    periods agree to 1e-6, decided points' growth rates to 1e-5 per cycle (the drivers take steps that differ at the
    tolerance's level; an undecided point's last growth rate is a transient's)."""
    rng = np.random.default_rng(3)
    n = 64
    a = rng.uniform(0.5, 4.0, n)
    k = a * np.geomspace(0.1, 3.0, n)
    b = np.full(n, 0.5)
    g = 10.0 ** rng.uniform(-7.0, -2.0, n)
    lanes = run_lanes(k, a, b, g)
    one = DrivenOutputs.empty(n)
    driven_batch("aging", True, True)(np.arange(n), k, a, b, g, SETTINGS, one)
    np.testing.assert_array_equal(lanes.regime, one.regime)
    np.testing.assert_array_equal(lanes.status, one.status)
    slip = one.regime == Regime.STICK_SLIP
    assert slip.sum() > 10 and (one.regime == Regime.STEADY).sum() > 10
    np.testing.assert_allclose(lanes.amplitude[slip], one.amplitude[slip], rtol=1e-6)
    np.testing.assert_allclose(lanes.period[slip], one.period[slip], rtol=1e-6)
    both = (lanes.cycles >= 2) & (one.cycles >= 2) & np.isfinite(one.growth_rate) & (one.regime != Regime.UNDECIDED)
    assert np.max(np.abs(lanes.growth_rate[both] - one.growth_rate[both]) * one.period[both]) < 1e-5


def test_a_points_numbers_do_not_depend_on_its_lane_or_neighbours():
    """The same points in another order, in several groups, and alone give the same bits."""
    rng = np.random.default_rng(7)
    base = np.array([(0.1343, 1.6272, 0.4714, 2.91e-5), (2.0, 1.5, 0.5, 1e-3), (0.75, 1.5, 0.5, 1e-4)] * LANES)
    k, a, b, g = (base[:, i] * rng.uniform(0.9, 1.1, len(base)) for i in range(4))
    first = run_lanes(k, a, b, g)
    again = run_lanes(k, a, b, g, groups=3, order=rng.permutation(k.size))
    alone = run_lanes(k[:1], a[:1], b[:1], g[:1])
    for name in DrivenOutputs._fields:
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name), err_msg=name)
        np.testing.assert_array_equal(getattr(first, name)[:1], getattr(alone, name), err_msg=name)


def test_budgets_end_as_undecided():
    """A step budget ends the point as undecided with status max_steps, a cycle budget as undecided with ok."""
    point = ([0.1343], [1.6272], [0.4714], [2.91e-5])
    steps = run_lanes(*point, settings=DrivenSettings(1e-3, 1e-9, 2000, 500))
    assert steps.regime[0] == Regime.UNDECIDED and steps.status[0] == Status.MAX_STEPS and steps.steps[0] == 500
    cycles = run_lanes(*point, settings=DrivenSettings(1e-3, 1e-9, 2, 1_000_000))
    assert cycles.regime[0] == Regime.UNDECIDED and cycles.status[0] == Status.OK and cycles.cycles[0] == 2
