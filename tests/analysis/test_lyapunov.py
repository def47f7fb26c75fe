"""sweep.analysis.lyapunov: the first Lyapunov coefficient against textbook systems with known l1 (normal form,
Lienard, Brusselator), the model's exact derivatives against finite differences, the model's l1 against the known
behaviour (quasi-static m2 > 0 direct, m2 = 0 degenerate, inertial m2 = 0 changing type) and against the driven
simulation (square-root law with the normal form's coefficient; the bistable band on the inverted side), and the
Bautin point (converged, accepted only where l1 exceeds its error). docs/hopf-type.md."""

from __future__ import annotations

import math

import numpy as np
import pytest

import sweep
from sweep.analysis.bistable import bistable_band
from sweep.analysis.lyapunov import (
    TYPES,
    Forms,
    bautin_points,
    first_lyapunov,
    first_lyapunov_with_error,
    lyapunov_line,
    model_forms,
    reduced_l1,
)
from sweep.errors import InputError
from sweep.integrate.driven import DrivenParams, DrivenSettings, Regime, simulate_point

M2_ZERO = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)
A_RED = M2_ZERO.m1 / M2_ZERO.A  # a = mu1/A at every V when m2 = 0


def polynomial_forms(J, quadratic, cubic, f=None) -> Forms:
    """Forms of a field with linear part J and homogeneous quadratic / cubic parts (functions of (N, n) arrays),
    B and C by polarisation (exact for polynomials): B(x, y) = [q(x + y) - q(x - y)] / 2 for q = quadratic (its
    second derivative is 2 q), C(x, x, y) = [c(x + y) - c(x - y) - 2 c(y)] for c = cubic (third derivative 6 c)."""
    J = np.asarray(J, dtype=float)[None]

    def B(x, y):
        return 0.5 * (quadratic(x + y) - quadratic(x - y))

    def C(x, x2, y):
        return cubic(x + y) - cubic(x - y) - 2.0 * cubic(y)

    def field(y):
        return np.einsum("nij,nj->ni", J, y) + quadratic(y) + cubic(y)

    return Forms(J, None, B, C, f or field, np.zeros((1, J.shape[1])))


def two(a, b):
    return np.stack([a, b], axis=1)


@pytest.mark.parametrize("omega, c", [(1.0, -0.3 + 0.7j), (2.5, 0.4 - 1.1j), (0.3, -2.0 + 0.0j)])
def test_normal_form_gives_its_own_coefficient(omega, c):
    """z' = i omega z + c z |z|^2 in z = x + i y: l1 = Re c / omega (stretch: |q_x| = 1/2, so |w| = |z|), twice that
    with <q, q> = 1."""
    def cubic(v):
        r2 = v[:, 0] ** 2 + v[:, 1] ** 2
        return two((c.real * v[:, 0] - c.imag * v[:, 1]) * r2, (c.imag * v[:, 0] + c.real * v[:, 1]) * r2)

    forms = polynomial_forms([[0.0, -omega], [omega, 0.0]], lambda v: 0.0 * v, cubic)
    nf, err = first_lyapunov_with_error(forms)
    assert nf.l1[0] == pytest.approx(c.real / omega, rel=1e-12, abs=1e-14)
    assert nf.omega[0] == pytest.approx(omega, rel=1e-14)
    assert err[0] < 1e-6 * abs(c.real / omega)
    assert first_lyapunov(forms, "unit").l1[0] == pytest.approx(2 * c.real / omega, rel=1e-12)


def lienard(mu: float = 0.0) -> Forms:
    """x'' + (x^2 - mu) x' + x = 0 as x' = y, y' = -x + mu y - x^2 y; d J / d mu = [[0, 0], [0, 1]]."""
    forms = polynomial_forms([[0.0, 1.0], [-1.0, mu]], lambda v: 0.0 * v,
                             lambda v: two(0.0 * v[:, 0], -v[:, 0] ** 2 * v[:, 1]))
    return forms._replace(dJ=np.array([[[0.0, 0.0], [0.0, 1.0]]]))


def test_lienard_l1_is_minus_one_eighth_and_predicts_the_van_der_pol_amplitude():
    """l1 = -1/8 in the z = x + i y scaling (stretch normalisation on x), -1/4 with <q, q> = 1; with Re dlambda/dmu
    = 1/2 the cycle r^2 = Re(dlambda) mu / (-omega l1) = 4 mu: amplitude 2 sqrt(mu), the classical van der Pol
    result."""
    nf, err = first_lyapunov_with_error(lienard())
    assert nf.l1[0] == pytest.approx(-0.125, rel=1e-13)
    assert err[0] < 1e-7
    assert first_lyapunov(lienard(), "unit").l1[0] == pytest.approx(-0.25, rel=1e-13)
    assert nf.dlambda[0].real == pytest.approx(0.5, rel=1e-13)
    mu = 1e-3
    assert math.sqrt(nf.dlambda[0].real * mu / (-nf.omega[0] * nf.l1[0])) == pytest.approx(2 * math.sqrt(mu))


@pytest.mark.parametrize("A", [0.5, 1.0, 2.0])
def test_brusselator(A):
    """x' = A - (B + 1) x + x^2 y, y' = B x - x^2 y at its Hopf point B = 1 + A^2, omega = A. Reference: the
    Guckenheimer-Holmes formula in the canonical coordinates (u, v) of the eigenvector (derived by hand and checked
    with sympy), Re c1 = -(A^2 + 2) / (8 (A^2 + 1)), and x = (A / sqrt(1 + A^2)) x the radius in (u, v), so in the
    stretch normalisation on x: l1 = -(A^2 + 2) / (8 A^3)."""
    b = 1.0 + A * A
    y0 = b / A

    def quadratic(v):  # (x0 + x)^2 (y0 + y) - x0^2 y0 - linear part = 2 x0 x y + y0 x^2 (+ x^2 y, cubic)
        q = 2.0 * A * v[:, 0] * v[:, 1] + y0 * v[:, 0] ** 2
        return two(q, -q)

    def cubic(v):
        c = v[:, 0] ** 2 * v[:, 1]
        return two(c, -c)

    J = [[b - 1.0, A * A], [-b, -A * A]]  # at (A, B/A): d/dx = -(B + 1) + 2 x y = B - 1, d/dy = x^2; g: -B, -x^2
    nf, err = first_lyapunov_with_error(polynomial_forms(J, quadratic, cubic))
    assert nf.omega[0] == pytest.approx(A, rel=1e-12)
    assert nf.l1[0] == pytest.approx(-(A * A + 2) / (8 * A**3), rel=1e-10)
    assert err[0] < 1e-6 * abs(nf.l1[0])


# --- the model -----------------------------------------------------------------------------------------------------

MODEL_CASES = [(1.8, 0.47, 0.0, "aging"), (1.8, 0.47, 0.0, "slip"), (0.7, -0.2, 0.0, "aging"),
               (1.8, 0.3, 0.1, "aging"), (1.8, 0.0, 3.0, "aging"), (0.5, 0.2, 0.01, "aging")]


@pytest.mark.parametrize("a, b, g, law", MODEL_CASES)
def test_exact_derivatives_match_finite_differences_in_every_direction(a, b, g, law):
    """B and C written out in model_forms against central differences of the right-hand side itself at two steps
    (random complex directions): the gap falls like h^2 (ratio ~4), so a wrong term would show as a constant gap."""
    rng = np.random.default_rng(7)
    forms = model_forms(a * (1 + g), a, b, g, law)
    n = forms.J.shape[1]
    v, w, x = (rng.normal(size=(1, n)) + 1j * rng.normal(size=(1, n)) for _ in range(3))
    f0 = forms.f(forms.y0.astype(complex))
    jac = np.stack([(forms.f(forms.y0 + 1e-7 * e[None]) - forms.f(forms.y0 - 1e-7 * e[None]))[0] / 2e-7
                    for e in np.eye(n)], axis=1)
    np.testing.assert_allclose(jac, forms.J[0], rtol=1e-6, atol=1e-6)
    def d2(u, h):
        return (forms.f(h * u) - 2 * f0 + forms.f(-h * u)) / h**2

    def d3(u, h):
        return (forms.f(2 * h * u) - 2 * forms.f(h * u) + 2 * forms.f(-h * u) - forms.f(-2 * h * u)) / (2 * h**3)

    gaps = []
    for h in (2e-3, 1e-3):
        b_fd = 0.25 * (d2(v + w, h) - d2(v - w, h))
        c_fd = (d3(v + x, h) - d3(v - x, h) - 2 * d3(x, h)) / 6
        gaps.append((np.abs(b_fd - forms.B(v, w)).max(), np.abs(c_fd - forms.C(v, v, x)).max()))
    for k in range(2):
        assert gaps[1][k] < 1e-4 * (1 + np.abs(forms.C(v, v, x)).max())
        assert gaps[0][k] / gaps[1][k] == pytest.approx(4.0, rel=0.2)


def test_a_wrong_derivative_shows_in_the_error_estimate():
    """The error estimate compares the exact forms with finite differences: a derivative off by 1 % in one term gives
    an l1_error of the order of that change, far above the correct forms' error."""
    forms = model_forms(1.8 * 1.1, 1.8, 0.3, 0.1)
    good_nf, good_err = first_lyapunov_with_error(forms)
    broken = forms._replace(C=lambda v, w, x: forms.C(v, w, x) * np.array([[1.0, 1.0, 1.01]]))
    bad_nf, bad_err = first_lyapunov_with_error(broken)
    assert good_err[0] < 1e-6
    assert bad_err[0] > 0.5 * abs(bad_nf.l1[0] - good_nf.l1[0]) > 100 * good_err[0]


def test_quasistatic_m2_positive_is_direct_and_m2_zero_degenerate_for_both_state_laws():
    """docs/physics.md 3b: with m2 > 0 the quasi-static bifurcation is direct; with m2 = 0 the aging law's
    quasi-static Hopf is a nonlinear centre (l1 = 0 identically, within its error at every V); the slip law shares
    the linearisation, not the nonlinear terms."""
    v = np.geomspace(1e-7, 6e-6, 50)
    for law in ("aging", "slip"):
        line = lyapunov_line(sweep.presets["sample2"], v, model="quasistatic", state_law=law)
        assert np.all(line.l1 < -100 * line.l1_error)
        assert np.all(line.kind == TYPES.index("supercritical"))
    flat = lyapunov_line(M2_ZERO, v, model="quasistatic")
    assert np.all(np.abs(flat.l1) <= flat.l1_error) and np.all(flat.l1_error < 1e-6)
    assert np.all(flat.kind == TYPES.index("degenerate"))


def test_no_line_where_mu1_is_not_positive():
    line = lyapunov_line(sweep.presets["sample2"], [1e-6, 1e-4], model="quasistatic")
    assert line.kind.tolist() == [TYPES.index("supercritical"), TYPES.index("none")]
    assert np.isnan(line.l1[1]) and np.isnan(line.l1_error[1])


def test_inertial_m2_zero_line_changes_type_and_tends_to_zero_without_inertia():
    """Inverted (l1 > 0) at small gamma/A, direct at large, l1 -> 0 like gamma/A as gamma/A -> 0 (the quasi-static
    centre): the sign the simulations of tests/analysis/test_hopf.py found at gamma/A = 0.01 and 1."""
    g = np.array([1e-4, 1e-3, 1e-2, 1.0])
    l1, err, _ = reduced_l1(A_RED, 0.0, g)
    assert np.all(l1[:3] > 1e3 * err[:3]) and l1[3] < -1e3 * err[3]
    assert l1[0] / g[0] == pytest.approx(l1[1] / g[1], rel=0.05)


def _stationary_amplitude(a, b, g, d, law="aging"):
    r = simulate_point(DrivenParams(a * (1 + g) * (1 - d), a, b, g), DrivenSettings(1e-4, 1e-10, 10_000, 20_000_000),
                       law)
    assert r.regime == Regime.STICK_SLIP
    return r.amplitude


@pytest.mark.parametrize("a, b, g, law", [(1.7, 0.4, 0.0, "aging"), (1.7, 0.4, 0.0, "slip"),
                                          (A_RED, 0.0, 1.0, "inertial")])
@pytest.mark.slow
def test_limit_cycle_amplitude_follows_the_normal_form_on_the_direct_side(a, b, g, law):
    """Just below a direct line the driven simulation's stationary stretch amplitude is sqrt(c d), c the normal
    form's coefficient (lyapunov_line.amplitude_coefficient), within 10 % at d = 1e-3 and 4e-3."""
    law = "aging" if law == "inertial" else law
    _, _, nf = reduced_l1(a, b, g, law)
    l1 = reduced_l1(a, b, g, law)[0][0]
    assert l1 < 0
    coefficient = nf.dlambda[0].real * a * (1 + g) / (nf.omega[0] * l1)
    for d in (1e-3, 4e-3):
        assert _stationary_amplitude(a, b, g, d, law) == pytest.approx(math.sqrt(coefficient * d), rel=0.1)


def test_bistable_band_on_the_inverted_side_only():
    """gamma/A = 0.1 (l1 > 0): a large start keeps stick-slip above the line while a small one decays, up to a
    relative distance of order 1e-3; gamma/A = 0.3 (l1 < 0): no band, the large start decays right above the
    line."""
    band = bistable_band(A_RED, 0.0, 0.1)
    assert band.bistable and band.undecided == 0
    assert 3e-4 < band.d_lo < band.d_hi < 1e-2 and band.d_hi / band.d_lo - 1 <= 1e-2
    direct = bistable_band(A_RED, 0.0, 0.3)
    assert direct.d_lo == 0.0 and not direct.bistable


def test_band_shrinks_like_l1_squared_towards_the_bautin_point():
    """Near the Bautin point the fold of cycles sits at d ~ omega l1^2 / (4 |l2| |Re dlambda/dk| k_c): the band's
    width over l1^2 is the same at two gamma/A on the inverted side (within 10 %), and the fold is on the inverted
    side, so l2 < 0 there."""
    widths = []
    for g in (0.1, 0.115):
        l1 = reduced_l1(A_RED, 0.0, g)[0][0]
        widths.append(bistable_band(A_RED, 0.0, g).d_hi / l1**2)
    assert widths[0] == pytest.approx(widths[1], rel=0.1)


def test_bautin_point_converged_and_between_the_simulated_types():
    """Inertial m2 = 0: one Bautin point, between gamma/A = 0.1 (still hysteretic in simulation) and 0.167
    (supercritical in simulation); halving the tolerance moves it by < 1e-4 relative; l1 exceeds its error at the
    bracket's ends with opposite signs."""
    v_range = tuple(math.sqrt(r * M2_ZERO.g * M2_ZERO.D0 * M2_ZERO.A) for r in (1e-3, 10.0))
    points = bautin_points(M2_ZERO, v_range, rtol=1e-3)
    finer = bautin_points(M2_ZERO, v_range, rtol=5e-4)
    assert len(points) == len(finer) == 1
    b, f = points[0], finer[0]
    assert 0.1 < b.gamma_over_A < 0.167 and b.direct_above
    assert abs(f.V / b.V - 1) < 1e-4 and abs(f.gamma_over_A / b.gamma_over_A - 1) < 1e-4
    assert b.bracket[1] / b.bracket[0] - 1 <= 0.5e-3
    line = lyapunov_line(M2_ZERO, list(b.bracket), model="inertial")
    assert line.l1[0] > line.l1_error[0] and line.l1[1] < -line.l1_error[1]


def test_no_bautin_point_on_the_quasistatic_m2_zero_centre():
    """l1 = 0 identically there: numerical noise changes sign, but never beyond l1_error, so no root is accepted."""
    assert bautin_points(M2_ZERO, (1e-7, 1e-4), model="quasistatic") == []


@pytest.mark.parametrize("call, name", [
    (lambda: model_forms(1.0, 1.0, 0.0, 0.1, "slip"), "slip"),
    (lambda: lyapunov_line(M2_ZERO, [-1e-6]), "V"),
    (lambda: lyapunov_line(M2_ZERO, [1e-6], model="newtonian"), "model"),
    (lambda: bautin_points(M2_ZERO, (1e-5, 1e-6)), "V_range"),
    (lambda: bautin_points(M2_ZERO, (1e-6, 1e-5), rtol=0.0), "rtol"),
    (lambda: bistable_band(-1.0, 0.0, 0.1), "mu1"),
])
def test_bad_input_names_the_parameter(call, name):
    with pytest.raises(InputError, match=name):
        call()
