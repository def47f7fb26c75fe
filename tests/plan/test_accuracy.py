"""The engine against the independent high-accuracy scipy reference (tests/reference.py) on the shared
table of cases (tests/cases.py): xi_inf within rtol, time-resolved observables, no-limit statuses."""

import math

import numpy as np
import pytest
from cases import NO_LIMIT_CASES, STOP_CASES, case_params
from reference import reference_stop

import sweep

RTOLS = (1e-4, 1e-6, 1e-8)


def engine_point(case, rtol, **kwargs):
    c = case_params(case)
    params = sweep.FrictionParams(A=c["A"], m1=c["m1"], m2=c["m2"], D0=c["D0"])
    return sweep.solve_point(params, K_over_M=c["K_over_M"], V=c["V"], rtol=rtol, **kwargs), c


@pytest.mark.parametrize("rtol", RTOLS)
@pytest.mark.parametrize("case", STOP_CASES, ids=lambda c: c.name)
def test_xi_inf_within_rtol_of_reference(case, rtol):
    pt, _ = engine_point(case, rtol, observables=("xi_inf",))
    ref = reference_stop(case.chi, case.A, case.mu1, case.m2)
    assert int(pt["status"]) == sweep.Status.OK
    err = abs(float(pt["xi_inf"]) - ref.xi_inf)
    atol = sweep.scene.scene.DEFAULT_ATOL["xi_inf"]
    assert err <= rtol * abs(ref.xi_inf) + atol, (err / ref.xi_inf, int(pt["steps"]))


@pytest.mark.parametrize("rtol", (1e-4, 1e-7))
@pytest.mark.parametrize("case", STOP_CASES, ids=lambda c: c.name)
def test_rosenbrock_forced_everywhere_is_right_or_says_so(case, rtol):
    """ros4's step rule is calibrated on the stiff points only; forced elsewhere it may miss rtol, but then its
    error estimate must say so (status error_above_tol) and must bound the true error."""
    pt, _ = engine_point(case, rtol, observables=("xi_inf",), method="ros4")
    ref = reference_stop(case.chi, case.A, case.mu1, case.m2)
    err = abs(float(pt["xi_inf"]) - ref.xi_inf)
    assert err <= float(pt["xi_inf_error"]) + sweep.scene.scene.DEFAULT_ATOL["xi_inf"], (err, float(pt["xi_inf_error"]))
    if int(pt["status"]) == sweep.Status.OK:
        assert err <= rtol * abs(ref.xi_inf) + sweep.scene.scene.DEFAULT_ATOL["xi_inf"]
    else:
        assert int(pt["status"]) == sweep.Status.ERROR_ABOVE_TOL


@pytest.mark.parametrize("case", STOP_CASES, ids=lambda c: c.name)
def test_time_resolved_observables_against_reference(case):
    rtol = 1e-6
    tau = (1e-3, 1e5, 9)
    pt, c = engine_point(case, rtol, observables=("trajectory", "slip_at", "t50", "t90"), trajectory_tau=tau,
                         t_obs=(0.5 * c_time(case), 2 * c_time(case)))
    ref = reference_stop(case.chi, case.A, case.mu1, case.m2)
    taus = np.logspace(math.log10(tau[0]), math.log10(tau[1]), tau[2])
    np.testing.assert_allclose(pt["xi"].values, ref.xi(taus), rtol=rtol, atol=1e-12)
    np.testing.assert_allclose(pt["psi"].values, ref.psi(taus), rtol=rtol)
    seconds_per_tau = c["D0"] / c["V"]
    for name, frac in (("t50", 0.5), ("t90", 0.9)):
        assert float(pt[name]) == pytest.approx(ref.tau_at_fraction(frac) * seconds_per_tau, rel=rtol), name
    slip_ref = c["D0"] * ref.xi(pt["t_obs"].values / seconds_per_tau)
    np.testing.assert_allclose(pt["slip_at"].values, slip_ref, rtol=rtol)


def c_time(case):
    """A time [s] near the case's t50, to place the slip_at samples where the slip is changing."""
    c = case_params(case)
    return reference_stop(case.chi, case.A, case.mu1, case.m2).tau_at_fraction(0.5) * c["D0"] / c["V"]


@pytest.mark.parametrize("case", NO_LIMIT_CASES, ids=lambda c: c.name)
def test_no_finite_limit_cases(case):
    pt, c = engine_point(case, 1e-6, observables=("xi_inf", "slip_at"), t_obs=(1.0, 10.0))
    assert int(pt["status"]) == sweep.Status.NO_FINITE_LIMIT
    assert math.isnan(float(pt["xi_inf"]))
    ref = reference_stop(case.chi, case.A, case.mu1, case.m2)
    assert not ref.finite
    tau_obs = pt["t_obs"].values * c["V"] / c["D0"]
    np.testing.assert_allclose(pt["slip_at"].values, c["D0"] * ref.xi(tau_obs), rtol=1e-5)


@pytest.mark.parametrize("name", ["g_chiA1_mA0.3_slowtail", "g_chiA1000_mA1_stiff", "s2_KM1e3_V100um_corner",
                                  "g_chiA0.1_mA-0.5_m2A0.2"])
def test_late_trajectory_to_astronomical_times(name):
    """Samples far beyond the transient (up to tau = 1e200) come from the closed-form continuation: cheap,
    status ok, and still within rtol of the reference (which integrates all the way)."""
    case = next(c for c in STOP_CASES if c.name == name)
    rtol, tau = 1e-6, (1e-3, 1e200, 41)
    pt, _ = engine_point(case, rtol, observables=("trajectory",), trajectory_tau=tau)
    assert int(pt["status"]) == sweep.Status.OK
    ref = reference_stop(case.chi, case.A, case.mu1, case.m2)
    taus = np.logspace(math.log10(tau[0]), math.log10(tau[1]), tau[2])
    np.testing.assert_allclose(pt["xi"].values, ref.xi(taus), rtol=rtol, atol=1e-12)
    np.testing.assert_allclose(pt["psi"].values, ref.psi(taus), rtol=rtol)
    short, _ = engine_point(case, rtol, observables=("trajectory",), trajectory_tau=(1e-3, 1e3, 41))
    # integrating to tau = 1e200 would take thousands of steps more; the continuation starts once E < 1e-5 rtol
    assert int(pt["steps"]) <= 3 * int(short["steps"]) + 200, "the late trajectory must not be integrated"
