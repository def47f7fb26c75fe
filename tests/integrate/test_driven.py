"""Driven scene, quasi-static model (sweep/integrate/models/driven.py) against the linear theory and the known
behaviour of
docs/physics.md 3b: growth rate and period of small oscillations vs the roots of A s^2 + (chi - mu1) s + chi, the
square-root law of the supercritical (m2 > 0) Hopf bifurcation, neutral orbits and runaway for m2 = 0."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sweep import physics
from sweep.integrate.driven import DrivenParams, DrivenSettings, Regime, point_kernel, simulate_driven
from sweep.status import Status

A, MU1 = 0.007, 0.0125  # sample2 at V0 (mu1 = m1): chi_c = mu1, omega_c = sqrt(mu1/A) = 1.336
M2 = 0.0033


def linear(chi, mu1=MU1):
    root = physics.characteristic_roots(chi, mu1, A)[0]
    return root.real, 2.0 * math.pi / abs(root.imag)


@pytest.mark.parametrize("chi_over_chi_c, m2", [(1.05, 0.0), (1.2, M2), (0.97, M2), (0.9, 0.0)])
def test_small_oscillations_follow_the_linear_theory(chi_over_chi_c, m2):
    """A perturbation of 1e-5: growth rate (either sign) and period of the first cycles = the leading root."""
    chi = chi_over_chi_c * MU1
    out = simulate_driven(chi, MU1, m2, A, perturbation=1e-5, rtol=1e-10, max_cycles=4)
    sigma, period = linear(chi)
    assert out["period"] == pytest.approx(period, rel=1e-4)
    assert out["growth_rate"] == pytest.approx(sigma, rel=1e-3, abs=1e-6)


def test_period_just_above_the_line_is_two_pi_over_omega_c():
    out = simulate_driven(1.005 * MU1, MU1, M2, A, perturbation=1e-4, rtol=1e-10)
    assert out["regime"] == "steady"
    assert out["period"] == pytest.approx(2.0 * math.pi / physics.omega_c(MU1, A), rel=1e-2)


def test_far_above_the_line_is_steady_with_zero_amplitude():
    out = simulate_driven(3.0 * MU1, MU1, M2, A, perturbation=1e-3)
    assert out["regime"] == "steady" and out["amplitude"] == 0.0 and out["growth_rate"] < 0.0


def test_supercritical_amplitude_grows_like_the_square_root_of_the_distance_to_the_line():
    """m2 > 0, quasi-static: stick-slip below the line with a stationary amplitude ~ sqrt(chi_c - chi); the slow
    approach near the line (thousands of cycles at 0.1 %) is followed to the end, not cut short."""
    amplitudes = []
    for eps in (0.001, 0.004, 0.016):
        out = simulate_driven((1.0 - eps) * MU1, MU1, M2, A, perturbation=1e-4, rtol=1e-10, max_cycles=10_000)
        assert out["regime"] == "stick_slip", out
        amplitudes.append(out["amplitude"])
    assert np.diff(np.log(amplitudes)) == pytest.approx([math.log(2.0)] * 2, rel=0.05)


def test_a_slow_transient_is_undecided_not_guessed():
    """0.1 % below the line the oscillation is still growing (3.7e-5 per unit tau) when 2000 cycles are up."""
    out = simulate_driven(0.999 * MU1, MU1, M2, A, perturbation=1e-4, rtol=1e-10, max_cycles=2000)
    assert out["regime"] == "undecided" and np.isnan(out["amplitude"]) and out["growth_rate"] > 0.0


def test_m2_zero_is_neutral_at_the_line_and_runs_away_below():
    amplitudes = []
    for size in (0.02, 0.6):  # orbits of any amplitude persist (docs/physics.md 3b)
        out = simulate_driven(MU1, MU1, 0.0, A, perturbation=size, rtol=1e-11)
        assert out["regime"] == "neutral", (size, out)
        assert abs(out["growth_rate"]) < 1e-8
        amplitudes.append(out["amplitude"])
    assert amplitudes[1] > 10.0 * amplitudes[0]
    out = simulate_driven(0.995 * MU1, MU1, 0.0, A, perturbation=1e-2)
    assert out["regime"] == "runaway" and np.isnan(out["amplitude"])
    assert out["peak_log_velocity"] > math.log(1e8)


def test_bad_input_names_the_parameter():
    with pytest.raises(ValueError, match="perturbation"):
        simulate_driven(0.02, MU1, M2, A, perturbation=0.0)
    with pytest.raises(ValueError, match="chi"):
        simulate_driven(-1.0, MU1, M2, A)


@pytest.mark.parametrize("gamma_over_A, chi_over_chi_c", [(0.01, 1.02), (1.0, 1.05), (10.0, 0.98)])
def test_inertial_oscillations_follow_the_cubic(gamma_over_A, chi_over_chi_c):
    """With inertia the small oscillations follow the complex pair of gamma s^3 + (gamma + A) s^2 + (chi - mu1) s
    + chi = 0 (the third, real root decays within the first cycles)."""
    gamma = gamma_over_A * A
    chi = chi_over_chi_c * physics.chi_c_inertial(MU1, A, gamma)
    out = simulate_driven(chi, MU1, 0.0, A, perturbation=1e-5, rtol=1e-10, max_cycles=6, gamma=gamma)
    roots = physics.characteristic_roots(chi, MU1, A, gamma)
    pair = roots[np.argmax(np.abs(roots.imag))]
    assert out["period"] == pytest.approx(2.0 * math.pi / abs(pair.imag), rel=1e-4)
    assert out["growth_rate"] == pytest.approx(pair.real, rel=2e-3, abs=1e-6)


def _radau_inertial(k: float, a: float, b: float, G: float, horizon: float):
    """Dense scipy Radau solution (analytic Jacobian, rtol 1e-9) of the inertial driven equations in (z, u, w = ln
    xi') from z = 1e-3 over [0, horizon] (tau): the independent reference of the inertial kernels."""
    from scipy.integrate import solve_ivp

    def rates(t, y):
        z, u, w = y
        return [1 - np.exp(w), np.exp(-u) - np.exp(w), (k * z - u * (a + b * u) - u - w) * np.exp(-w) / G]

    def jac(t, y):
        z, u, w = y
        c = np.exp(-w) / G
        return [[0, 0, -np.exp(w)], [0, -np.exp(-u), -np.exp(w)],
                [k * c, -(a + 2 * b * u + 1) * c, -(1 + k * z - u * (a + b * u) - u - w) * c]]

    return solve_ivp(rates, (0, horizon), [1e-3, 0, 0], method="Radau", jac=jac, rtol=1e-9, atol=1e-12,
                     dense_output=True)


@pytest.mark.slow
@pytest.mark.parametrize("slaved", [False, True])
def test_inertial_stick_slip_with_stiff_stick_phases_matches_scipy_radau(slaved):
    """Deep stick-slip with inertia at gamma/A = 1e-2 (chi = mu1/2, m2 > 0): the stick phases are stiff (rate
    A/(gamma xi'), xi' down to ~e^-10), where the kernel switches to RODAS3. The limit cycle's amplitude and period
    agree with scipy's Radau (analytic Jacobian, rtol 1e-9) on the same equations in tau; also where the kernel
    runs the stick phases on the slow manifold (``slaved``: w = ln xi' slaved to second order in the inertial term,
    sweep.accuracy.SLAVED_INERTIA).

    Reference tolerance: Radau at rtol 1e-9 (29k steps) gives the amplitude within 7e-13 relative of rtol 1e-10
    (50k steps, 1.6x the time) and the same last period on the sampling grid, against the 1e-6 (amplitude) and
    1e-4 (period) checked: a margin of > 1e6 on the amplitude; the period's resolution is the sampling grid's
    (3 periods / 3e5 samples = 1e-5 of a period), as before."""
    k, a, b, G = 0.75, 1.5, 0.5, 1e-2  # (A = 0.01: the reduced parameters are all the kernel needs)
    out = point_kernel("aging", True, slaved)(DrivenParams(k, a, b, G), DrivenSettings(1e-3, 1e-9, 2000, 5_000_000))
    r = {"regime": Regime(out.regime).name.lower(), "status": Status(out.status).name.lower(),
         "period": out.period, "amplitude": out.amplitude}
    assert r["regime"] == "stick_slip" and r["status"] == "ok"

    horizon = 20 * r["period"]  # the engine decided after 18 cycles
    sol = _radau_inertial(k, a, b, G, horizon)
    t = np.linspace(horizon - 3 * r["period"], horizon, 300_001)
    z = sol.sol(t)[0]
    assert (z.max() - z.min()) / 2 == pytest.approx(r["amplitude"], rel=1e-6)
    peaks = t[1:-1][(z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:])]
    assert np.diff(peaks)[-1] == pytest.approx(r["period"], rel=1e-4)


def test_slaved_inertia_keeps_the_regimes_and_limit_cycles_of_the_full_system_at_small_gamma():
    """At gamma/A ~ 1e-7..1e-5 (the quasi-static model runs away there: model "auto"'s reruns), the slow-manifold
    form must give the full inertial system's regime, period and amplitude to the integration's accuracy (full
    system at rtol 1e-9 against 1e-10: ~2e-7 on both), in far fewer steps: the stick phases are its explicit
    steps instead of RODAS3 ones at h A/(gamma xi') up to 1e14."""
    settings = DrivenSettings(1e-3, 1e-9, 2000, 1_000_000)
    for k, a, G in [(0.0805, 3.9567, 2.08e-7), (0.1343, 1.6272, 2.91e-5), (1.1843, 3.5685, 4.74e-7)]:  # issue 35 grid
        p = DrivenParams(k, a, 0.4714, G)
        full, slaved = point_kernel("aging", True, False)(p, settings), point_kernel("aging", True, True)(p, settings)
        assert full.regime == slaved.regime == Regime.STICK_SLIP
        assert slaved.period == pytest.approx(full.period, rel=1e-6)
        assert slaved.amplitude == pytest.approx(full.amplitude, rel=1e-6)
        assert slaved.steps < 0.5 * full.steps


@pytest.mark.parametrize("slaved", [False, True])
def test_a_rebound_inside_the_slip_is_not_a_cycle(slaved):
    """Issue 35's grid point (K/M index 22, V 0.1 um/s; gamma/A = 2.1e-7): after each slip the slider rebounds by
    ~6.5e-6 in z, an extra maximum of z. Skipped as a rebound (sweep.accuracy.REBOUND), the cycle is the whole
    period: stick_slip, its half peak-to-peak stretch that of scipy's Radau (analytic Jacobian, rtol 1e-9) to 1e-6
    and its period to 1e-5 (the peaks' sampling grid: 1e-4 tau, 5e-6 of the period); as two cycles of
    alternating amplitude 9.9 / 6e-6 it never became stationary (undecided after 1e6 steps)."""
    k, a, b, G = 1.3461091409855348, 3.9567230876801, 0.4714285714285714, 2.080342840500114e-07
    r = point_kernel("aging", True, slaved)(DrivenParams(k, a, b, G), DrivenSettings(1e-3, 1e-9, 2000, 1_000_000))
    assert r.regime == Regime.STICK_SLIP and r.status == Status.OK

    horizon = 6 * r.period
    sol = _radau_inertial(k, a, b, G, horizon)
    t = np.linspace(horizon - 2 * r.period, horizon, 400_001)
    z = sol.sol(t)[0]
    assert (z.max() - z.min()) / 2 == pytest.approx(r.amplitude, rel=1e-6)
    peaks = t[1:-1][(z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:]) & (z[1:-1] > 0.0)]
    assert np.diff(peaks)[-1] == pytest.approx(r.period, rel=1e-5)


@pytest.mark.parametrize("root, others", [(0.37, (-0.5, 2.0)), (0.02, (1.5, -3.0)), (0.93, (-0.2, 1.4))])
def test_extremum_first_guess_is_the_root_of_a_cubic_slope(root, others):
    """Where z' is itself a cubic in the step fraction s, the first guess from z' and z'' at both ends (Hermite
    data) is its root in [0, 1] to rounding (the Newton on exact partial steps then starts converged)."""
    from sweep.integrate.driven import _first_guess

    poly = np.polynomial.Polynomial.fromroots([root, *others])
    slope = poly.deriv()
    guess = _first_guess(poly(0.0), poly(1.0), slope(0.0), slope(1.0))
    assert guess == pytest.approx(root, abs=1e-12)


def test_extremum_first_guess_stays_in_the_step():
    """Random end data with z' changing sign: the guess lies in [0, 1] whatever the z'' given (a vanishing slope or
    a root outside the step leaves the previous stage's guess)."""
    from sweep.integrate.driven import _first_guess

    rng = np.random.default_rng(3)
    for _ in range(2000):
        dz0, dz1 = rng.uniform(0.0, 1.0), -rng.uniform(0.0, 1.0)
        if rng.random() < 0.5:
            dz0, dz1 = -dz0, -dz1
        guess = _first_guess(dz0, dz1, *rng.normal(0.0, 5.0, 2))
        assert 0.0 <= guess <= 1.0
