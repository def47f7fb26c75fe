"""Tests of sweep.physics against hand values (docs/physics.md section 4) and independent numerical references.

The references here (scipy integration of the stop equations, finite-difference Jacobians of the driven
equations) are written from docs/physics.md, not from sweep.physics.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sweep import physics as ph

# ---------------------------------------------------------------------------------------------------------
# independent references


def solve_stop_m2zero(chi, A, m1, S_end=300.0, dense=False):
    """Quasi-static stop (docs/physics.md 3a), m2 = 0, in log time S = ln(1 + tau); state (xi, u, I).

    xi' = exp(-(chi xi + m1 u)/A - u), u' = exp(-u) - xi', I' = psi^-(1 + m1/A), and d/dS = e^S d/dtau.
    The factors e^S are folded into the exponents so nothing overflows at large S.
    """
    beta = 1.0 + m1 / A

    def rhs(S, y):
        xi, u, _ = y
        ds_xi = math.exp(S - (chi * xi + m1 * u) / A - u)  # e^S xi'
        return [ds_xi, math.exp(S - u) - ds_xi, math.exp(S - beta * u)]

    sol = solve_ivp(rhs, (0.0, S_end), [0.0, 0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    dense_output=dense)
    assert sol.success, sol.message
    return sol


def jacobian_fd(f, y0, h=1e-6):
    """Central finite-difference Jacobian of f at y0."""
    y0 = np.asarray(y0, dtype=float)
    J = np.empty((y0.size, y0.size))
    for j in range(y0.size):
        e = np.zeros_like(y0)
        e[j] = h
        J[:, j] = (np.asarray(f(y0 + e)) - np.asarray(f(y0 - e))) / (2.0 * h)
    return J


def driven_rhs(chi, mu1, A, gamma, m2=0.0):
    """Driven scene (docs/physics.md 3b) in reduced variables around steady sliding at V.

    gamma == 0: state (z, u), xi' = exp((chi z - dmu(u))/A - u).
    gamma > 0: state (z, w = ln xi', u), w' = (chi z - dmu(u) - A (w + u))/(gamma e^w).
    """
    def dmu(u):
        return mu1 * u + m2 * u * u

    if gamma == 0:
        def f(y):
            z, u = y
            v = math.exp((chi * z - dmu(u)) / A - u)
            return [1.0 - v, math.exp(-u) - v]
        return f, [0.0, 0.0]

    def f(y):
        z, w, u = y
        v = math.exp(w)
        return [1.0 - v, (chi * z - dmu(u) - A * (w + u)) / (gamma * v), math.exp(-u) - v]
    return f, [0.0, 0.0, 0.0]


def fd_eigenvalues(chi, mu1, A, gamma):
    f, y0 = driven_rhs(chi, mu1, A, gamma, m2=0.004)  # m2 must not matter at linear order
    return np.linalg.eigvals(jacobian_fd(f, y0))


def bisect_hopf(mu1, A, gamma):
    """chi where the largest real part of the FD-Jacobian eigenvalues crosses zero."""
    def rate(chi):
        return fd_eigenvalues(chi, mu1, A, gamma).real.max()

    lo, hi = 0.2 * mu1, 20.0 * mu1 * (1.0 + gamma / A)
    assert rate(lo) > 0 > rate(hi)
    while hi - lo > 1e-11 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if rate(mid) > 0 else (lo, mid)
    return 0.5 * (lo + hi)


def match_roots(a, b):
    """Max distance between two root sets, over the best pairing."""
    return min(max(abs(x - y) for x, y in zip(a, p)) for p in itertools.permutations(b))


# ---------------------------------------------------------------------------------------------------------
# hand-checked values (docs/physics.md section 4)


def test_xi_inf_m2zero_hand_value():
    assert ph.xi_inf_m2zero(0.02, 0.007, 0.0125) == pytest.approx(0.4387, abs=5e-5)
    # A ln(chi/m1)/(chi - m1) written out
    assert ph.xi_inf_m2zero(0.02, 0.007, 0.0125) == pytest.approx(0.007 * math.log(1.6) / 0.0075, rel=1e-14)


@pytest.mark.parametrize("eps", [0.0, 1e-12, -1e-12, 1e-9, -1e-9, 1e-6, -1e-6, 1e-3, -1e-3])
def test_xi_inf_m2zero_continuous_at_chi_equal_m1(eps):
    A, m1 = 0.007, 0.0125
    x = ph.xi_inf_m2zero(m1 * (1 + eps), A, m1)
    # Taylor series of ln(1 + eps)/eps: the limit A/m1 is approached smoothly
    assert x == pytest.approx(A / m1 * (1 - eps / 2 + eps**2 / 3 - eps**3 / 4 + eps**4 / 5), rel=1e-13)
    if abs(eps) >= 1e-6:  # direct formula, where it has no cancellation trouble
        assert x == pytest.approx(A * math.log1p(eps) / (m1 * eps), rel=1e-9)


def test_crude_estimate_hand_value():
    assert ph.xi_inf_crude(0.02, 0.007, 0.0125) == pytest.approx(0.594, abs=5e-4)


def test_other_hand_values():
    assert ph.stress_relaxation_near_hopf(0.0125, 0.007) == pytest.approx(0.007 * math.log(2 + 0.0125 / 0.007))
    assert ph.xi_inertial(0.04, 0.01) == pytest.approx(2.0)
    assert ph.xi_early(0.5, 0.02, 0.007) == pytest.approx(0.35 * math.log(1 + 0.02 * 0.5 / 0.007))
    assert ph.xi_late_deficit(100.0, 0.02, 0.007, 0.0125, 0.4) == pytest.approx(
        0.56 * math.exp(-0.02 * 0.4 / 0.007) * 100.0 ** (-0.0125 / 0.007))
    assert ph.omega_c(0.0125, 0.007) == pytest.approx(math.sqrt(0.0125 / 0.007))
    assert ph.Omega_c(1e-5, 0.0125, 0.007, 0.7e-6) == pytest.approx(1e-5 / 0.7e-6 * math.sqrt(0.0125 / 0.007))


def test_friction_law_identities():
    m0, m1, m2, V0 = 0.3, 0.0125, 0.0033, 1e-6
    V = np.array([1e-7, 1e-6, 3e-6, 5e-5])
    # mu1 = -d mu_d / d ln V (central difference in ln V)
    h = 1e-5
    slope = -(ph.mu_d(V * math.exp(h), m0, m1, m2, V0) - ph.mu_d(V * math.exp(-h), m0, m1, m2, V0)) / (2 * h)
    np.testing.assert_allclose(ph.mu1(V, m1, m2, V0), slope, rtol=1e-8)
    # delta_mu(psi) = mu_d(V/psi) - mu_d(V), exactly for the quadratic law
    psi = np.array([[0.1], [1.0], [7.0], [1e4]])
    np.testing.assert_allclose(ph.delta_mu(psi, ph.mu1(V, m1, m2, V0), m2),
                               ph.mu_d(V / psi, m0, m1, m2, V0) - ph.mu_d(V, m0, m1, m2, V0), atol=1e-15)
    assert ph.mu_d(V0, m0, m1, m2, V0) == m0


def test_unit_conversions_round_trip():
    K_over_M = np.logspace(3, 6, 7)
    chi = ph.reduced_stiffness(K_over_M, 0.7e-6)
    assert ph.reduced_stiffness(7.4e4, 1e-6) == pytest.approx(7.54e-3, rel=1e-3)  # Fig. 3b chi ~ 7.5e-3
    np.testing.assert_allclose(ph.K_over_M_from_chi(chi, 0.7e-6), K_over_M, rtol=1e-15)
    t = np.array([0.0, 1e-3, 10.0])
    np.testing.assert_allclose(ph.physical_time(ph.reduced_time(t, 1e-5, 1e-6), 1e-5, 1e-6), t, rtol=1e-15)
    assert ph.inertia_number(1e-4, 1e-6, 9.81) == pytest.approx(1e-8 / 9.81e-6)


# ---------------------------------------------------------------------------------------------------------
# relaxed slip vs independent integration of the stop equations

STOP_POINTS = [  # (chi, A, m1): m1/A in 0.5..3, chi/A in 0.1..10
    (0.02, 0.007, 0.0125),    # docs/physics.md section 4 point: m1/A = 1.79, chi/A = 2.86
    (0.001, 0.01, 0.005),     # m1/A = 0.5, chi/A = 0.1
    (0.1, 0.01, 0.03),        # m1/A = 3, chi/A = 10
    (0.012, 0.012, 0.012),    # chi = m1 exactly: the removable singularity
]


@pytest.fixture(scope="module")
def stop_solutions():
    return {pt: solve_stop_m2zero(*pt, S_end=300.0 if pt[2] / pt[1] >= 1 else 460.0, dense=True)
            for pt in STOP_POINTS}


@pytest.mark.parametrize("pt", STOP_POINTS)
def test_xi_inf_m2zero_vs_integration(pt, stop_solutions):
    sol = stop_solutions[pt]
    xi_end, u_end, _ = sol.y[:, -1]
    assert u_end == pytest.approx(sol.t[-1], rel=0.1)  # psi ~ tau late on (Fig. 4b)
    assert ph.xi_inf_m2zero(*pt) == pytest.approx(xi_end, rel=1e-8)


@pytest.mark.parametrize("pt", STOP_POINTS)
def test_eq9_integral_identity(pt, stop_solutions):
    chi, A, _ = pt
    I_end = stop_solutions[pt].y[2, -1]
    assert ph.xi_inf_from_integral(chi, A, I_end) == pytest.approx(ph.xi_inf_m2zero(*pt), rel=1e-9)


def test_early_and_late_asymptotics(stop_solutions):
    chi, A, m1 = pt = STOP_POINTS[0]
    sol = stop_solutions[pt]
    xi_inf = ph.xi_inf_m2zero(chi, A, m1)
    tau = 1e-6
    assert ph.xi_early(tau, chi, A) == pytest.approx(sol.sol(math.log1p(tau))[0], rel=1e-9)  # eq. 12
    # eq. 13: (true deficit)/(eq. 13) ~0.94 at tau = 10 and ~0.9994 at tau = 1e3 (docs/physics.md section 4)
    ratios = [(xi_inf - sol.sol(math.log1p(tau))[0]) / ph.xi_late_deficit(tau, chi, A, m1, xi_inf)
              for tau in (10.0, 1e3)]
    assert ratios[0] == pytest.approx(0.94, abs=0.01)
    assert ratios[1] == pytest.approx(0.9994, abs=2e-4)


def test_crude_estimate_is_not_a_bound():
    # docs/physics.md 4: eq. 10 overestimates at the sample2-like point, underestimates at small mu1/A
    assert ph.xi_inf_crude(0.02, 0.007, 0.0125) > ph.xi_inf_m2zero(0.02, 0.007, 0.0125)
    A, m1 = 0.01, 0.001
    assert ph.xi_inf_crude(1.01 * m1, A, m1) / ph.xi_inf_m2zero(1.01 * m1, A, m1) == pytest.approx(0.74, abs=0.01)


# ---------------------------------------------------------------------------------------------------------
# linear stability of steady sliding vs finite-difference Jacobians

HOPF_POINTS = [  # (mu1, A, gamma)
    (0.0125, 0.007, 0.0),
    (0.003, 0.012, 0.0),
    (0.0125, 0.007, 0.0014),   # gamma/A = 0.2
    (0.005, 0.01, 0.08),       # gamma/A = 8
    (0.02, 0.005, 1e-5),       # gamma/A << 1: stiff third root
]


@pytest.mark.parametrize("mu1, A, gamma", HOPF_POINTS)
def test_hopf_line_matches_jacobian(mu1, A, gamma):
    chi_fd = bisect_hopf(mu1, A, gamma)
    if gamma == 0:
        assert ph.chi_c_quasistatic(mu1) == pytest.approx(chi_fd, rel=1e-8)
        # the crossing pair is +-i omega_c
        lam = fd_eigenvalues(chi_fd, mu1, A, gamma)
        assert np.abs(lam.imag).max() == pytest.approx(ph.omega_c(mu1, A), rel=1e-8)
    assert ph.chi_c_inertial(mu1, A, gamma) == pytest.approx(chi_fd, rel=1e-8)
    chi_c = ph.chi_c_inertial(mu1, A, gamma)
    assert ph.growth_rate_linear(chi_c, mu1, A, gamma) == pytest.approx(0.0, abs=1e-10)
    assert not ph.stable_sliding(0.999 * chi_c, mu1, A, gamma)
    assert ph.stable_sliding(1.001 * chi_c, mu1, A, gamma)


@pytest.mark.parametrize("chi", [0.001, 0.01, 0.05])
@pytest.mark.parametrize("mu1, A, gamma", HOPF_POINTS + [(-0.004, 0.007, 0.0), (-0.004, 0.007, 0.02)])
def test_characteristic_roots_match_jacobian(chi, mu1, A, gamma):
    lam = fd_eigenvalues(chi, mu1, A, gamma)
    roots = ph.characteristic_roots(chi, mu1, A, gamma)
    assert roots.shape == (3,)
    if gamma == 0:
        assert np.isnan(roots[2])
        roots = roots[:2]
    scale = np.abs(lam).max()
    assert match_roots(list(roots), list(lam)) < 1e-7 * scale
    assert ph.growth_rate_linear(chi, mu1, A, gamma) == pytest.approx(lam.real.max(), abs=1e-7 * scale)
    assert np.all(np.diff(roots.real) <= 0)  # documented order: decreasing real part


# ---------------------------------------------------------------------------------------------------------
# vectorisation and NaN conventions


def test_broadcasting_shapes_and_scalars():
    chi = np.logspace(-3, -1, 5)[:, None]
    mu1 = np.linspace(-0.01, 0.02, 4)[None, :]
    A, gamma = 0.007, np.array([0.0, 0.0, 0.01, 0.1])
    assert ph.characteristic_roots(chi, mu1, A, gamma).shape == (5, 4, 3)
    assert ph.growth_rate_linear(chi, mu1, A, gamma).shape == (5, 4)
    assert ph.stable_sliding(chi, mu1, A, gamma).dtype == bool
    for f, args in [(ph.xi_inf_m2zero, (chi, A, mu1)), (ph.xi_inf_crude, (chi, A, mu1)),
                    (ph.chi_c_inertial, (mu1, A, chi)), (ph.xi_late_deficit, (chi * 1e4, chi, A, mu1, 0.3)),
                    (ph.xi_early, (mu1 + 0.02, chi, A)), (ph.xi_inertial, (gamma, chi))]:
        assert np.shape(f(*args)) == (5, 4), f.__name__
    for value in (ph.mu1(1e-5, 0.01, 0.001), ph.xi_inf_m2zero(0.02, 0.007, 0.0125), ph.omega_c(-1.0, 1.0),
                  ph.growth_rate_linear(0.02, 0.0125, 0.007)):
        assert isinstance(value, float)


def test_nan_where_no_hopf_line():
    mu1 = np.array([-0.01, 0.0, 0.01])
    with np.errstate(all="raise"):  # no warnings either
        for value in (ph.chi_c_quasistatic(mu1), ph.chi_c_inertial(mu1, 0.007, 0.01), ph.omega_c(mu1, 0.007),
                      ph.Omega_c(1e-5, mu1, 0.007, 1e-6), ph.xi_inf_crude(0.02, 0.007, mu1),
                      ph.xi_inf_m2zero(0.02, 0.007, mu1)):
            assert np.isnan(value[:2]).all() and np.isfinite(value[2])
        assert ph.stable_sliding(1e-9, mu1, 0.007).tolist() == [True, True, False]


def test_stable_sliding_agrees_with_growth_rate():
    rng = np.random.default_rng(0)
    chi = 10 ** rng.uniform(-4, -1, 2000)
    mu1 = rng.uniform(-0.02, 0.03, 2000)
    A = rng.uniform(0.002, 0.02, 2000)
    gamma = np.where(rng.random(2000) < 0.5, 0.0, 10 ** rng.uniform(-5, 0, 2000))
    rate = ph.growth_rate_linear(chi, mu1, A, gamma)
    away = np.abs(chi / ph.chi_c_inertial(mu1, A, gamma) - 1) > 1e-6
    away |= mu1 <= 0
    np.testing.assert_array_equal(ph.stable_sliding(chi, mu1, A, gamma)[away], (rate < 0)[away])
    assert (rate[mu1 <= 0] < 0).all()


def test_nonfinite_inputs_give_nan_roots():
    roots = ph.characteristic_roots([np.nan, 0.02], 0.0125, 0.007, 0.01)
    assert np.isnan(roots[0]).all() and np.isfinite(roots[1]).all()
    assert np.isnan(ph.growth_rate_linear(np.nan, 0.0125, 0.007))


@pytest.mark.parametrize("inertial", [False, True])
def test_hopf_K_over_M_consistency(inertial):
    A, m1, m2, D0, V0, g = 0.007, 0.0125, 0.0033, 0.7e-6, 1e-6, 9.81
    V = np.logspace(-7, -4, 13)
    slope = ph.mu1(V, m1, m2, V0)
    gamma = ph.inertia_number(V, D0, g) if inertial else 0.0
    expected = ph.K_over_M_from_chi(ph.chi_c_inertial(slope, A, gamma), D0, g)
    got = ph.hopf_K_over_M(V, A, m1, m2, D0, V0, g, inertial=inertial)
    np.testing.assert_allclose(got, expected, rtol=1e-15)
    # written out: (g/D0) mu1 (1 + V^2/(g D0 A)), NaN where mu1 <= 0
    formula = g / D0 * slope * (1 + V**2 / (g * D0 * A) if inertial else 1.0)
    np.testing.assert_allclose(got[slope > 0], formula[slope > 0], rtol=1e-14)
    assert np.isnan(got[slope <= 0]).all() and (slope <= 0).any()


def test_scaled_erfc_of_the_closed_form_tail_matches_scipy():
    """exp(z^2) erfc(z) of the Gaussian tail integral (m2 > 0) against scipy.special.erfcx, across the switch to the
    asymptotic series at z = 25: cut after its z^-6 term, as before, it was 4e-11 off there, a step-independent
    error of every relaxed slip whose tail starts near it. Below 25 the product exp(z^2) erfc(z) carries the rounding
    of z^2, up to 5e-14 relative near 23."""
    from scipy.special import erfcx as reference

    from sweep.integrate.models.stop import erfcx

    for z in np.concatenate((np.linspace(0.0, 30.0, 301), [24.999, 25.0, 25.001, 1e2, 1e4, 1e8])):
        assert erfcx(float(z)) == pytest.approx(reference(z), rel=1e-13, abs=0.0), z
