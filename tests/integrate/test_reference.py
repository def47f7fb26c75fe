"""Validation of the independent reference (tests/reference.py) itself, before the engine is compared to it.

* m2 = 0: the exact closed form. With s = int dtau/psi the stop equations give xi + ln psi = s and
  dxi/ds = exp(-((chi - m1) xi + m1 s)/A), which separates:
      xi_inf = A ln(chi/m1)/(chi - m1)      (limit A/m1 at chi = m1).
  Written inline here on purpose (not imported from the package).
* m2 != 0: the same s-time form, integrated here as a 1-D ODE (an independent formulation), and DOP853 vs
  Radau on the tau-form.
* Early stage (docs/physics.md eq. 12), late stage psi ~ tau, monotone xi, horizons and no-limit cases, and the
  consistency of the shared case table (tests/cases.py).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import reference as ref_mod
from cases import ALL_CASES, EXTREME_CASES, NO_LIMIT_CASES, STOP_CASES, V0, G, case_params
from reference import reference_stop
from scipy.integrate import solve_ivp


def closed_form_m2zero(chi, A, m1):
    if chi == m1:
        return A / m1
    return A * math.log(chi / m1) / (chi - m1)


def s_form_xi_inf(chi, A, mu1, m2):
    """xi_inf from the contact-age time form: dxi/ds = exp(-(chi xi + mu1 u + m2 u^2)/A), u = s - xi (m2 > 0).
    Integrated until u = s - xi >= u_end (event), 10 beyond where dmu(u)/A = 50: the remaining slip is then
    below exp(-50) relative."""
    u_end = 10.0 + (-mu1 + math.sqrt(mu1 * mu1 + 200.0 * m2 * A)) / (2.0 * m2)

    def f(s, y):
        u = s - y[0]
        return [math.exp(-(chi * y[0] + mu1 * u + m2 * u * u) / A)]

    def jac(s, y):
        u = s - y[0]
        return [[-(chi - mu1 - 2.0 * m2 * u) / A * f(s, y)[0]]]

    def reached(s, y):
        return s - y[0] - u_end

    reached.terminal = True
    res = solve_ivp(f, (0.0, 1e7), [0.0], method="Radau", jac=jac, rtol=1e-13, atol=1e-16 * min(1.0, A / chi),
                    events=reached)
    assert res.status == 1, res.message
    return float(res.y[0, -1])


FINITE_M2ZERO = [c for c in STOP_CASES if c.m2 == 0.0]
FINITE_M2POS = [c for c in STOP_CASES + EXTREME_CASES if c.m2 > 0.0]
GRID = list(itertools.product((0.01, 0.1, 1.0, 10.0, 100.0, 1000.0), (0.3, 1.0, 3.0)))


# ---------------------------------------------------------------------------------------------------------
# xi_inf against exact results


@pytest.mark.parametrize("chi_over_A,m1_over_A", GRID)
def test_closed_form_m2zero_grid(chi_over_A, m1_over_A):
    A = 0.01
    chi, m1 = chi_over_A * A, m1_over_A * A
    r = reference_stop(chi, A, m1, 0.0)
    exact = closed_form_m2zero(chi, A, m1)
    assert r.finite
    assert abs(r.xi_inf - exact) < 1e-10 * exact, (r.xi_inf, exact, r.method)


@pytest.mark.parametrize("case", FINITE_M2ZERO, ids=lambda c: c.name)
def test_closed_form_m2zero_table(case):
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    exact = closed_form_m2zero(case.chi, case.A, case.mu1)
    assert abs(r.xi_inf - exact) < 1e-10 * exact


@pytest.mark.slow
@pytest.mark.parametrize("case", FINITE_M2POS, ids=lambda c: c.name)
def test_m2_positive_against_contact_age_time_form(case):
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    other = s_form_xi_inf(case.chi, case.A, case.mu1, case.m2)
    assert abs(r.xi_inf - other) < 1e-10 * r.xi_inf, (r.xi_inf, other)


@pytest.mark.parametrize("name", ["g_chiA1000_mA3_m2A0.3_stiff", "s2_KM1e3_V100um_corner", "s1_KM7.4e4_V10um",
                                  "g_chiA0.01_mA0.3_slowtail"])
def test_dop853_and_radau_agree(name):
    case = next(c for c in STOP_CASES if c.name == name)
    a = reference_stop(case.chi, case.A, case.mu1, case.m2, method="DOP853")
    b = reference_stop(case.chi, case.A, case.mu1, case.m2, method="Radau")
    assert abs(a.xi_inf - b.xi_inf) < 1e-10 * a.xi_inf
    taus = np.logspace(-4, 8, 25)
    np.testing.assert_allclose(a.xi(taus), b.xi(taus), rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(a.psi(taus), b.psi(taus), rtol=1e-9)


@pytest.mark.parametrize("case", EXTREME_CASES, ids=lambda c: c.name)
def test_extreme_cases_use_radau(case):
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    assert r.method == "Radau" and r.finite and r.tail < 1e-14 * r.xi_inf


def test_budget_fallback_to_radau(monkeypatch):
    monkeypatch.setattr(ref_mod, "DOP853_MAX_NFEV", 500)
    chi, A, m1 = 0.02, 0.007, 0.0125
    r = reference_stop.__wrapped__(chi, A, m1, 0.0)  # uncached
    assert r.method == "Radau"
    exact = closed_form_m2zero(chi, A, m1)
    assert abs(r.xi_inf - exact) < 1e-10 * exact


# ---------------------------------------------------------------------------------------------------------
# the transient


@pytest.mark.parametrize("case", ALL_CASES, ids=lambda c: c.name)
def test_early_stage_log_law(case):
    """docs/physics.md eq. 12: xi -> (A/chi) ln(1 + chi tau/A) as tau -> 0 (psi ~ 1)."""
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    a = case.A / case.chi
    tau = 1e-6 * a
    early = a * math.log1p(tau / a)
    assert abs(float(r.xi(tau)) - early) < 1e-5 * early
    assert float(r.xi(0.0)) == 0.0 and float(r.psi(0.0)) == 1.0
    assert abs(float(r.psi(tau)) - 1.0) < 1e-9


@pytest.mark.parametrize("case", FINITE_M2ZERO, ids=lambda c: c.name)
def test_late_stage_psi_like_tau(case):
    """Contact age psi ~ tau for tau >> 1 (paper Fig. 4b); psi <= 1 + tau always (psi' <= 1)."""
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    taus = np.logspace(6, 40, 8)
    ratio = r.psi(taus) / (1.0 + taus)
    assert np.all(ratio <= 1.0 + 1e-12)
    assert np.all(np.diff(ratio) > -1e-12)  # settles monotonically toward its constant (1)
    assert abs(ratio[-1] - 1.0) < 1e-6
    taus = np.logspace(-3, 30, 200)
    assert np.all(r.psi(taus) <= (1.0 + taus) * (1.0 + 1e-12))


@pytest.mark.parametrize("case", [c for c in FINITE_M2ZERO if c.mu1 <= c.A], ids=lambda c: c.name)
def test_late_stage_tail_eq13(case):
    """docs/physics.md eq. 13: xi_inf - xi(tau) ~ (A/m1) exp(-chi xi_inf/A) tau^(-m1/A), ratio -> 1."""
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    A, m1, chi = case.A, case.mu1, case.chi
    tau = max(1e6, 10.0 ** (6.0 / (m1 / A)))  # remaining slip ~ 1e-6; formula's own error <~ 1e-5 there
    remaining = r.xi_inf - float(r.xi(tau))
    predicted = (A / m1) * math.exp(-chi * r.xi_inf / A) * tau ** (-m1 / A)
    assert remaining / predicted == pytest.approx(1.0, abs=1e-3)


@pytest.mark.parametrize("case", ALL_CASES, ids=lambda c: c.name)
def test_xi_monotone(case):
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    top = 1e200 if r.finite else r.tau_horizon
    taus = np.concatenate([[0.0], np.logspace(-8, math.log10(top), 2000)])
    xi = r.xi(taus)
    scale = r.xi_inf if r.finite else xi[-1]
    assert np.all(np.diff(xi) >= -1e-14 * scale)
    assert np.all(np.isfinite(xi))
    if r.finite:
        assert float(r.xi(taus[-1])) == pytest.approx(r.xi_inf, rel=1e-13)
    else:
        assert xi[-1] > xi[len(xi) // 2] > 0.0  # still growing at the horizon


@pytest.mark.parametrize("case", STOP_CASES + EXTREME_CASES, ids=lambda c: c.name)
def test_fractions_and_tail(case):
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    assert r.finite and np.isfinite(r.xi_inf) and r.xi_inf > 0.0
    assert 0.0 <= r.tail < 1e-14 * r.xi_inf  # slip beyond the horizon is negligible (and added)
    t50, t90 = r.tau_at_fraction(0.5), r.tau_at_fraction(0.9)
    assert 0.0 < t50 < t90
    for f, t in ((0.5, t50), (0.9, t90)):
        assert float(r.xi(t)) == pytest.approx(f * r.xi_inf, rel=1e-12)
    assert float(r.slip_at_tau(t50)) == float(r.xi(t50))
    # vectorised evaluation
    taus = np.array([[0.0, 1.0], [10.0, 1e300]])
    assert r.xi(taus).shape == (2, 2) and r.psi(taus).shape == (2, 2)


@pytest.mark.parametrize("case", NO_LIMIT_CASES, ids=lambda c: c.name)
def test_no_limit_cases(case):
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    assert not r.finite and math.isnan(r.xi_inf)
    assert r.tau_horizon == pytest.approx(1e12, rel=1e-9)
    assert np.all(np.isfinite(r.xi(np.logspace(-3, 12, 50))))
    with pytest.raises(ValueError):
        r.xi(1e13)
    with pytest.raises(ValueError):
        r.tau_at_fraction(0.5)


def test_no_limit_m2zero_mu1neg_growth():
    """m2 = 0, mu1 < 0: late on chi xi + mu1 ln psi ~ const, so xi grows like (|mu1|/chi) ln tau."""
    case = next(c for c in NO_LIMIT_CASES if c.name == "nolim_m2zero_muneg")
    r = reference_stop(case.chi, case.A, case.mu1, case.m2)
    slope = (float(r.xi(1e12)) - float(r.xi(1e10))) / math.log(100.0)
    assert slope == pytest.approx(-case.mu1 / case.chi, rel=2e-2)


# ---------------------------------------------------------------------------------------------------------
# the case table


def test_case_table_coverage():
    finite = STOP_CASES
    assert len(finite) >= 18
    chiA = [c.chi / c.A for c in finite]
    assert min(chiA) <= 0.0101 and max(chiA) >= 1000.0
    assert any(c.m2 == 0 for c in finite) and any(c.m2 > 0 for c in finite)
    assert any(c.mu1 < 0 and c.m2 > 0 and c.chi / c.A <= 0.02 for c in finite)  # costly corner
    assert any(c.m2 == 0 and c.mu1 / c.A <= 0.3 for c in finite)  # slow tail
    assert {c.hopf_side for c in finite} >= {"stable", "stick-slip", "hopf"}
    assert {c.preset for c in finite} >= {"sample1", "sample2"}
    no_limit = {(np.sign(c.m2), np.sign(c.mu1)) for c in NO_LIMIT_CASES}
    assert no_limit >= {(-1, 1), (-1, -1), (0, 0), (0, -1)}


@pytest.mark.parametrize("case", ALL_CASES, ids=lambda c: c.name)
def test_case_params_reproduce_reduced_parameters(case):
    c = case_params(case)
    assert c["V0"] == V0 and c["g"] == G
    assert c["K_over_M"] * c["D0"] / c["g"] == pytest.approx(case.chi, rel=1e-14)
    assert c["m1"] - 2.0 * c["m2"] * math.log(c["V"] / c["V0"]) == pytest.approx(case.mu1, rel=1e-13, abs=1e-17)
    assert c["A"] == case.A and c["m2"] == case.m2
    if case.preset is not None:
        assert 1e3 <= c["K_over_M"] <= 1e6 and 0.1e-6 <= c["V"] <= 100e-6
