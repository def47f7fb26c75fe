"""Checks of the slip-law reference (tests/reference_slip.py) itself, before the engine is compared to it.

* aging=True reproduces the aging-law reference (tests/reference.py), an independent formulation (tau-log time,
  two phases in S) of the same model: xi_inf, xi(tau), psi(tau), no-limit trajectories;
* DOP853 vs Radau; independence of the end of the integration (u_end) and of the phase hand-over (h_switch);
  the closed-form remainder against quadrature;
* exact results: the Airy closed form of xi_inf (every m2 > 0 case), the m2 = 0 Riccati solution
  u = (k/a^2)(e^(a xi) - 1 - a xi) (no finite limit), mu1 = 0 scaling xi_inf = x*/(b k)^(1/3), mu1 = -A with
  m2 = 0 where xi(tau) = ln(1 + k tau)/k for either law, the early stage; the comparison xi_inf(slip) >
  xi_inf(aging) (u_slip(xi) <= u_aging(xi)); the algebraic late tail xi_inf - xi ~ 1/(b u);
* driven: both laws linearise to A s^2 + (chi - mu1) s + chi = 0 (growth rate and period of small oscillations),
  the regimes on both sides of the Hopf line.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import reference_slip as rs
from cases import NO_LIMIT_CASES, STOP_CASES
from reference import reference_stop
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.special import airy

FINITE_SLIP = [c for c in STOP_CASES if c.m2 > 0.0]
M2_ZERO = [c for c in STOP_CASES if c.m2 == 0.0]


@functools.cache
def slip(name: str, method: str = "auto", **kw) -> rs.StopSolution:
    c = next(c for c in STOP_CASES + NO_LIMIT_CASES if c.name == name)
    return rs.stop(c.chi, c.A, c.mu1, c.m2, method=method, **kw)


@functools.cache
def aging(name: str) -> rs.StopSolution:
    c = next(c for c in STOP_CASES + NO_LIMIT_CASES if c.name == name)
    return rs.stop(c.chi, c.A, c.mu1, c.m2, aging=True)


# ---------------------------------------------------------------------------------------------------------
# the aging switch reproduces tests/reference.py


@pytest.mark.parametrize("case", STOP_CASES, ids=lambda c: c.name)
def test_aging_switch_reproduces_the_aging_reference(case):
    r = aging(case.name)
    ref = reference_stop(case.chi, case.A, case.mu1, case.m2)
    assert r.finite and r.remainder_bound <= 1e-16 * r.xi_inf
    assert abs(r.xi_inf - ref.xi_inf) <= 1e-12 * ref.xi_inf, (r.xi_inf, ref.xi_inf)


@pytest.mark.parametrize("name", ["g_chiA1_mA0.3_m2A0.05", "s2_KM1e3_V100um_corner", "g_chiA1000_mA3_m2A0.3_stiff",
                                  "g_chiA0.01_mA0.3_slowtail"])
def test_aging_switch_trajectory(name):
    case = next(c for c in STOP_CASES if c.name == name)
    r, ref = aging(name), reference_stop(case.chi, case.A, case.mu1, case.m2)
    taus = np.logspace(-4, 150, 12)
    np.testing.assert_allclose(r.xi(taus), ref.xi(taus), rtol=1e-11, atol=1e-15)
    np.testing.assert_allclose(r.psi(taus), ref.psi(taus), rtol=1e-11)


@pytest.mark.parametrize("name", ["g_chiA1_mA0.3_m2A0.05", "s2_KM1e3_V100um_corner", "g_chiA1000_mA3_m2A0.3_stiff"])
def test_fraction_times(name):
    """t50/t90: the aging switch matches tests/reference.py; for the slip law xi(t_f) = f xi_inf, and t90 may lie
    beyond any float time (reported as inf), e.g. t50 = 1.8e93 and t90 = inf for chi/A = 1000."""
    case = next(c for c in STOP_CASES if c.name == name)
    g, ref = aging(name), reference_stop(case.chi, case.A, case.mu1, case.m2)
    s = slip(name)
    for f in (0.5, 0.9):
        assert g.tau_at_fraction(f) == pytest.approx(ref.tau_at_fraction(f), rel=1e-9)
        t = s.tau_at_fraction(f)
        assert t > g.tau_at_fraction(f)
        if math.isfinite(t):
            assert float(s.xi(t)) == pytest.approx(f * s.xi_inf, rel=1e-10)
    if name == "g_chiA1000_mA3_m2A0.3_stiff":
        assert s.tau_at_fraction(0.5) == pytest.approx(1.82e93, rel=0.01) and s.tau_at_fraction(0.9) == math.inf


@pytest.mark.parametrize("case", NO_LIMIT_CASES, ids=lambda c: c.name)
def test_aging_switch_no_limit_trajectories(case):
    r, ref = aging(case.name), reference_stop(case.chi, case.A, case.mu1, case.m2)
    assert not r.finite and math.isnan(r.xi_inf)
    taus = np.logspace(-3, 12, 6)
    np.testing.assert_allclose(r.xi(taus), ref.xi(taus), rtol=1e-10)
    np.testing.assert_allclose(r.psi(taus), ref.psi(taus), rtol=1e-10)


# ---------------------------------------------------------------------------------------------------------
# the numerics of the slip-law stop


@pytest.mark.parametrize("name", ["g_chiA1000_mA3_m2A0.3_stiff", "s2_KM1e4_V100um_corner"])
def test_dop853_and_radau_agree(name):
    a, b = slip(name, "DOP853"), slip(name, "Radau")
    assert a.method == "DOP853" and b.method == "Radau"
    assert abs(a.xi_inf - b.xi_inf) <= 1e-12 * a.xi_inf
    taus = np.logspace(-4, 100, 9)
    np.testing.assert_allclose(a.xi(taus), b.xi(taus), rtol=1e-10)
    np.testing.assert_allclose(a.psi(taus), b.psi(taus), rtol=1e-10)


@pytest.mark.parametrize("name", ["g_chiA1000_mA3_m2A0.3_stiff", "s1_KM7.4e4_V10um"])
def test_end_of_integration_and_hand_over_do_not_matter(name):
    """The remainder replaces the integration beyond u_end (1e5, 1e6 by default, 1e7: the remainder itself goes
    from 1e-4 to 1e-6 of xi_inf) and the phase hand-over can be moved: xi_inf changes by < 1e-12 relative."""
    base = slip(name)
    assert base.u_end == pytest.approx(rs.U_END_SLIP, rel=1e-12) and base.remainder_bound <= 1e-16 * base.xi_inf
    for kw in ({"u_end": 1e5}, {"u_end": 1e7}, {"h_switch": 0.25}, {"h_switch": 4.0}):
        other = slip(name, **kw)
        assert abs(other.xi_inf - base.xi_inf) <= 1e-12 * base.xi_inf, (kw, other.xi_inf, base.xi_inf)
    assert slip(name, u_end=1e5).remainder / slip(name, u_end=1e7).remainder == pytest.approx(100.0, rel=1e-2)


@pytest.mark.parametrize("a, b, c", [(0.3, 0.05, 1.0), (-3.0, 0.47, 4.9), (1.0, 0.1, 2.5), (2.0, 1.0, 1.0),
                                     (0.0, 0.2, 1e-9)])
def test_tail_integral_against_quadrature(a, b, c):
    """F(c) = int_U^inf du/(b u^2 + a u + c) in closed form (atanh/arctan branches, D > 0, < 0, ~ 0)."""
    for U in (5.0, 50.0, 1e4):
        exact = quad(lambda u: 1.0 / (b * u * u + a * u + c), U, np.inf, epsabs=0.0, epsrel=1e-13, limit=200)[0]
        assert rs.tail_F(U, a, b, c) == pytest.approx(exact, rel=1e-11)


def test_remainder_brackets_the_integrated_tail():
    """xi(u = 1e7) - xi(u = 1e4), integrated, equals R(1e4) - R(1e7) within the stated bounds."""
    lo, hi = slip("s1_KM7.4e4_V10um", u_end=1e4), slip("s1_KM7.4e4_V10um", u_end=1e7)
    integrated = hi.xi_end - lo.xi_end
    assert abs(integrated - (lo.remainder - hi.remainder)) <= lo.remainder_bound + hi.remainder_bound + 1e-14


# ---------------------------------------------------------------------------------------------------------
# exact results for the slip law


def test_finite_limit_condition():
    """Slip law: finite iff m2 > 0, whatever mu1 (m2 = 0 included: the Riccati equation is then linear)."""
    for mu1 in (-1.0, 0.0, 1.0):
        assert rs.has_finite_limit(mu1, 0.1) and not rs.has_finite_limit(mu1, 0.0)
        assert not rs.has_finite_limit(mu1, -0.1)
        assert rs.has_finite_limit(mu1, 0.0, aging=True) == (mu1 > 0.0)


@pytest.mark.parametrize("name", [c.name for c in M2_ZERO[:4]] + [c.name for c in NO_LIMIT_CASES])
def test_no_finite_limit_for_the_slip_law(name):
    r = slip(name)
    assert not r.finite and math.isnan(r.xi_inf)
    assert r.S_end == pytest.approx(math.log1p(rs.TAU_HORIZON_NO_LIMIT), rel=1e-12)
    assert np.all(np.diff(r.xi(np.logspace(-2, 12, 8))) > 0.0)


@pytest.mark.parametrize("name", ["g_chiA0.01_mA1", "g_chiA1_mA0.3_slowtail", "g_chiA1000_mA1_stiff",
                                  "nolim_m2zero_mu0", "nolim_m2zero_muneg"])
def test_m2_zero_riccati_closed_form(name):
    """m2 = 0: du/dxi = k xi + a u is linear, u = (k/a^2)(e^(a xi) - 1 - a xi) (k xi^2/2 at a = 0), in both the
    xi-phase (u(xi)) and the u-phase (xi(u))."""
    c = next(c for c in STOP_CASES + NO_LIMIT_CASES if c.name == name)
    k, a = c.chi / c.A, c.mu1 / c.A
    r = slip(name)
    xs = np.linspace(0.0, r.p1.t[-1], 9)[1:]
    np.testing.assert_allclose(r.p1.sol(xs)[0], rs.riccati_m2zero_u(xs, k, a), rtol=1e-10)
    if r.p2 is not None:
        ts = np.linspace(r.p2.t[0], r.p2.t[-1], 9)
        np.testing.assert_allclose(rs.riccati_m2zero_u(r.p2.sol(ts)[0], k, a), np.exp(ts), rtol=1e-10)


@pytest.mark.parametrize("case", FINITE_SLIP, ids=lambda c: c.name)
def test_airy_closed_form(case):
    """m2 > 0: xi_inf is the first zero of an Airy combination (reference_slip.slip_xi_inf_airy)."""
    r = slip(case.name)
    assert r.finite and r.remainder_bound <= 1e-16 * r.xi_inf
    exact = rs.slip_xi_inf_airy(case.chi, case.A, case.mu1, case.m2)
    assert abs(r.xi_inf - exact) <= 1e-12 * exact, (r.xi_inf, exact)


def test_mu1_zero_scaling():
    """mu1 = 0: u' = k xi + b u^2 scales to U' = X + U^2 (X = (b k)^(1/3) xi), so xi_inf = x*/(b k)^(1/3) with
    x* the first zero of Ai(-x) + Bi(-x)/sqrt(3) (Ai'(0)/Bi'(0) = -1/sqrt(3)), whatever k and b."""
    x_star = brentq(lambda x: airy(-x)[0] + airy(-x)[2] / math.sqrt(3.0), 0.5, 2.5, xtol=1e-15)
    assert x_star == pytest.approx(1.98635270743, abs=1e-10)
    for k, b in ((0.1, 0.2), (10.0, 0.05)):
        r = rs.stop(k * 0.01, 0.01, 0.0, b * 0.01)
        assert r.xi_inf * (b * k) ** (1.0 / 3.0) == pytest.approx(x_star, rel=1e-12)


@pytest.mark.parametrize("case", [c for c in FINITE_SLIP if c.mu1 < 0.0], ids=lambda c: c.name)
def test_soft_spring_limit_is_the_fold_of_the_creep_manifold(case):
    """mu1 < 0: the slider creeps on L ~ 0 (u ~ k xi/|a|) up to the fold xi0 = a^2/(4 b k) of that manifold,
    then slips off through an Airy layer of width (b k)^(-1/3): xi_inf = xi0 + 2.33811/(b k)^(1/3) up to terms
    ~ exp(-4/3 X0^1.5), X0 = (b k)^(1/3) xi0 (the Airy form with r -> 0): exact to rounding for X0 >~ 10, i.e.
    soft springs (the costly corners); a correction of order one otherwise."""
    k, a, b = case.chi / case.A, case.mu1 / case.A, case.m2 / case.A
    c = (b * k) ** (1.0 / 3.0)
    fold = a * a / (4.0 * b * k) + 2.338107410459767 / c
    r = slip(case.name)
    if c * a * a / (4.0 * b * k) > 10.0:
        assert abs(r.xi_inf - fold) <= 1e-12 * r.xi_inf
    else:
        assert 1e-6 < abs(r.xi_inf - fold) / r.xi_inf < 1.0


def test_state_independent_case_mu1_equal_minus_A():
    """m2 = 0, mu1 = -A: A ln(xi' psi) = -chi xi + A ln psi, so xi' = e^(-k xi), xi = ln(1 + k tau)/k exactly
    for either state law (psi differs)."""
    c = next(c for c in NO_LIMIT_CASES if c.name == "nolim_m2zero_muneg_soft")
    assert c.mu1 == -c.A and c.m2 == 0.0
    k = c.chi / c.A
    taus = np.logspace(-3, 12, 7)
    for r in (slip(c.name), aging(c.name)):
        np.testing.assert_allclose(r.xi(taus), np.log1p(k * taus) / k, rtol=1e-11)
    assert not np.allclose(slip(c.name).psi(taus[3:]), aging(c.name).psi(taus[3:]), rtol=1e-3)


@pytest.mark.parametrize("name", ["g_chiA0.01_mA1_m2A0.1", "g_chiA1000_mA3_m2A0.3_stiff", "s2_KM2.8e5_V10um"])
def test_early_stage_is_the_same_for_both_laws(name):
    """tau << 1: psi ~ 1 and xi = ln(1 + k tau)/k (docs/physics.md eq. 12) for both laws."""
    c = next(c for c in STOP_CASES if c.name == name)
    k = c.chi / c.A
    tau = 1e-6 / k
    for r in (slip(name), aging(name)):
        assert float(r.xi(tau)) == pytest.approx(math.log1p(k * tau) / k, rel=1e-5)
        assert float(r.psi(tau)) == pytest.approx(1.0, abs=1e-9)
        assert float(r.xi(0.0)) == 0.0 and float(r.psi(0.0)) == 1.0


@pytest.mark.parametrize("case", FINITE_SLIP, ids=lambda c: c.name)
def test_slip_law_slides_further_than_aging(case):
    """expm1(L) >= L: u_aging(xi) >= u_slip(xi) (comparison theorem), so the aging solution blows up first:
    xi_inf(slip) > xi_inf(aging) (no healing at rest: the contacts strengthen only by slipping)."""
    s, g = slip(case.name), aging(case.name)
    assert s.xi_inf > g.xi_inf
    xs = np.linspace(0.0, min(s.p1.t[-1], g.p1.t[-1]), 20)[1:]
    assert np.all(s.p1.sol(xs)[0] <= g.p1.sol(xs)[0] * (1.0 + 1e-12))


@pytest.mark.parametrize("name", ["s1_KM7.4e4_V10um", "g_chiA1_mA0.3_m2A0.05"])
def test_slip_law_tail_is_algebraic_in_u(name):
    """Late on xi_inf - xi = 1/(b u) (1 + O(1/u)) and ln tau ~ L ~ b u^2: at tau = 1e200 the slip is still short
    of xi_inf by ~1/sqrt(b ln tau), 3-5 % here (7-11 % at tau = 1e50); the aging law is converged to 1e-15."""
    c = next(c for c in STOP_CASES if c.name == name)
    b = c.m2 / c.A
    k, a = c.chi / c.A, c.mu1 / c.A
    r = slip(name)
    for tau in (1e50, 1e200):
        u = math.log(float(r.psi(tau)))
        gap = r.xi_inf - float(r.xi(tau))
        # the remainder's bracket (reference_slip, section 3) with U = u(tau)
        lo, hi = rs.tail_F(u, a, b, k * r.xi_inf), rs.tail_F(u, a, b, k * float(r.xi(tau)))
        assert lo * (1 - 1e-9) <= gap <= hi * (1 + 1e-9)
        assert gap * b * u == pytest.approx(1.0, abs=0.15)
        # tau = int e^(u + L)/L du ~ e^(u + L)/(L (1 + dL/du)) (Laplace), L = k xi + a u + b u^2 ~ b u^2
        L = k * float(r.xi(tau)) + a * u + b * u * u
        assert u + L - math.log(L * (1.0 + a + 2.0 * b * u + k / L)) == pytest.approx(math.log(tau), abs=0.05)
        assert gap > 0.01 * r.xi_inf
    assert aging(name).xi_inf - float(aging(name).xi(1e200)) <= 1e-15 * aging(name).xi_inf


# ---------------------------------------------------------------------------------------------------------
# driven scene

A, MU1, M2 = 0.007, 0.0125, 0.0033  # sample2 at V0


def test_both_laws_have_the_same_linearisation():
    """Finite-difference Jacobian of both right-hand sides at z = u = 0 = [[-k, a + 1], [-k, a]]."""
    k, a, b = 1.3, 1.786, 0.47

    def rhs(z, u, law):
        w = k * z - u * (a + b * u) - u
        return np.array([1.0 - math.exp(w), math.exp(-u) - math.exp(w) if law == "aging" else
                         -math.exp(w) * (w + u)])

    h = 1e-7
    for law in ("aging", "slip"):
        J = np.column_stack([(rhs(h, 0.0, law) - rhs(-h, 0.0, law)) / (2 * h),
                             (rhs(0.0, h, law) - rhs(0.0, -h, law)) / (2 * h)])
        np.testing.assert_allclose(J, [[-k, a + 1.0], [-k, a]], rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("aging_law", [False, True], ids=["slip", "aging"])
@pytest.mark.parametrize("chi_over_chi_c, m2", [(1.05, 0.0), (1.2, M2), (0.97, M2), (0.9, 0.0)])
def test_small_oscillations_follow_the_linear_theory(chi_over_chi_c, m2, aging_law):
    """Perturbation 1e-5: growth rate and period of cycles 2-4 = the leading root of A s^2 + (chi - mu1) s + chi."""
    chi = chi_over_chi_c * MU1
    d = rs.driven(chi, A, MU1, m2, 1e-5, aging=aging_law, cycles=4)
    root = rs.linear_roots(chi, MU1, A)[0]
    np.testing.assert_allclose(d.growth[2:5], root.real, rtol=1e-4, atol=1e-7)
    np.testing.assert_allclose(d.period[1:5], 2.0 * math.pi / abs(root.imag), rtol=1e-5)


def test_regimes_on_both_sides_of_the_hopf_line():
    """Slip law: m2 > 0 supercritical (stick-slip limit cycle below the line, smaller than the aging law's), m2 = 0
    degenerate like the aging law (neutral orbits of any amplitude at the line, runaway below), steady above."""
    assert rs.driven(1.2 * MU1, A, MU1, M2, 1e-3, cycles=200).regime == "steady"
    below = rs.driven(0.9 * MU1, A, MU1, M2, 1e-3, cycles=200)
    assert below.regime == "stick_slip"
    assert below.amplitude[-1] < rs.driven(0.9 * MU1, A, MU1, M2, 1e-3, aging=True, cycles=200).amplitude[-1]
    for p in (0.02, 0.3):
        d = rs.driven(MU1, A, MU1, 0.0, p, cycles=50, rtol=1e-12)
        assert d.regime == "neutral" and np.all(np.abs(d.growth[2:]) < 1e-10), (p, d.growth)
    run = rs.driven(0.9 * MU1, A, MU1, 0.0, 1e-2, cycles=200)
    assert run.regime == "runaway" and run.peak_w >= math.log(1e8)


@pytest.mark.parametrize("case", NO_LIMIT_CASES, ids=lambda c: c.name)
def test_no_limit_trajectories_do_not_depend_on_the_hand_over(case):
    """Without a finite limit (m2 <= 0) the hand-over to the u-phase is optional: xi(tau), psi(tau) up to 1e12 are
    the same with the xi-phase alone (h_switch = 1e30)."""
    r, alone = slip(case.name), slip(case.name, h_switch=1e30)
    assert alone.p2 is None
    taus = np.logspace(-2, 12, 8)
    np.testing.assert_allclose(r.xi(taus), alone.xi(taus), rtol=1e-11)
    np.testing.assert_allclose(r.psi(taus), alone.psi(taus), rtol=1e-11)
