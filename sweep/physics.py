"""Closed-form physics of the Baumberger & Gauthier (1996) spring-block model.

Paper: T. Baumberger & L. Gauthier, "Creeplike relaxation at the interface between rough solids under
shear", J. Phys. I France 6 (1996) 1021-1030, doi:10.1051/jp1:1996113. Equation numbers below are the
paper's; see also docs/physics.md.

Reduced variables (paper section 4), for a slider of mass M pulled through a spring K at velocity V::

    xi  = x/D0                 reduced slip
    tau = V t/D0               reduced time
    psi = V phi/D0             reduced contact age (u = ln psi)
    chi = K D0/(M g)           reduced stiffness
    gamma = V^2/(g D0)         inertia number
    mu1(V) = m1 - 2 m2 ln(V/V0)                     local velocity-weakening slope
    delta_mu(psi) = mu1 ln psi + m2 (ln psi)^2      = mu_d(V/psi) - mu_d(V)

Every function is numpy-vectorised: arguments broadcast against each other, a scalar result is returned
as a numpy float (a ``float`` subclass), otherwise an ndarray. Quantities that do not exist (no Hopf line
when mu1 <= 0, no finite relaxed slip when m1 <= 0) are NaN, never an exception.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "K_over_M_from_chi", "Omega_c", "characteristic_roots", "chi_c_inertial", "chi_c_quasistatic",
    "delta_mu", "growth_rate_linear", "hopf_K_over_M", "inertia_number", "mu1", "mu_d", "omega_c",
    "physical_time", "reduced_stiffness", "reduced_time", "stable_sliding", "stress_relaxation_near_hopf",
    "xi_early", "xi_inertial", "xi_inf_crude", "xi_inf_from_integral", "xi_inf_m2zero", "xi_late_deficit",
]


def _out(x):
    """0-d arrays become numpy floats/complexes/bools; other arrays are returned unchanged."""
    x = np.asarray(x)
    return x[()] if x.ndim == 0 else x


def _nan_unless_positive(slope, value):
    """``value`` where ``slope > 0``, NaN elsewhere (no Hopf line / no finite limit when slope <= 0)."""
    return _out(np.where(np.asarray(slope) > 0, value, np.nan))


# --- friction law -------------------------------------------------------------------------------------

def mu_d(v, m0, m1, m2, V0=1e-6):
    """Steady-state friction coefficient mu_d(v) = m0 - m1 ln(v/V0) + m2 [ln(v/V0)]^2 [1] (eq. 6).

    v, V0 : sliding and reference velocity [m s-1]; m0, m1, m2 [1].
    """
    L = np.log(np.asarray(v, dtype=float) / V0)
    return _out(m0 - m1 * L + m2 * L**2)


def mu1(V, m1, m2, V0=1e-6):
    """Local velocity-weakening slope mu1(V) = -d mu_d/d ln V = m1 - 2 m2 ln(V/V0) [1] (from eq. 6).

    V, V0 : driving and reference velocity [m s-1]; m1, m2 [1].
    """
    return _out(m1 - 2.0 * m2 * np.log(np.asarray(V, dtype=float) / V0))


def delta_mu(psi, mu1, m2):
    """Age-dependent friction delta_mu(psi) = mu_d(V/psi) - mu_d(V) = mu1 ln psi + m2 (ln psi)^2 [1].

    psi : reduced contact age [1]; mu1 = mu1(V), m2 [1]. (eq. 6 with v = V/psi.)
    """
    u = np.log(np.asarray(psi, dtype=float))
    return _out(mu1 * u + m2 * u**2)


# --- reduced variables ------------------------------------------------------------------------------

def reduced_stiffness(K_over_M, D0, g=9.81):
    """Reduced stiffness chi = (K/M) D0/g [1]. K_over_M [s-2], D0 [m], g [m s-2]. (Paper section 4.)"""
    return _out(np.asarray(K_over_M, dtype=float) * D0 / g)


def K_over_M_from_chi(chi, D0, g=9.81):
    """Inverse of :func:`reduced_stiffness`: K/M = chi g/D0 [s-2]. chi [1], D0 [m], g [m s-2]."""
    return _out(np.asarray(chi, dtype=float) * g / D0)


def inertia_number(V, D0, g=9.81):
    """Inertia number gamma = V^2/(g D0) [1]. V [m s-1], D0 [m], g [m s-2]. (Paper section 5.)"""
    return _out(np.asarray(V, dtype=float) ** 2 / (g * D0))


def reduced_time(t, V, D0):
    """Reduced time tau = V t/D0 [1]. t [s], V [m s-1], D0 [m]."""
    return _out(np.asarray(V, dtype=float) * t / D0)


def physical_time(tau, V, D0):
    """Inverse of :func:`reduced_time`: t = tau D0/V [s]. tau [1], V [m s-1], D0 [m]."""
    return _out(np.asarray(tau, dtype=float) * D0 / V)


# --- stability of steady sliding (driven scene) ----------------------------------------------------

def perturbation_growth(chi, mu1, A):
    """Rate at which a perturbation of the slip grows per unit of slip during a quasi-static stop [1].

    In contact-age time s (models/stop.py) dxi/ds = E, and dE/dxi = ((mu1 + 2 m2 u) - chi) E/A at fixed s, so a
    perturbation grows by exp(int (mu1 - chi)/A dxi) = exp((mu1 - chi) xi_inf/A) over the stop for m2 = 0: by
    mu1/chi exactly (eq. 10 with m2 = 0), e.g. 1e10 at chi/A = 1e-4, mu1/A = 1e6, where rounding then shows as
    scatter of 2e-7 relative. Returns max(0, (mu1 - chi)/A), the m2 = 0 part (m2 > 0 adds 2 m2 u/A late in the
    stop, where E and the slip still to come are small).
    """
    return _out(np.maximum(0.0, (np.asarray(mu1, dtype=float) - np.asarray(chi, dtype=float)) / np.asarray(A)))


def chi_c_quasistatic(mu1):
    """Critical reduced stiffness of the quasi-static model, chi_c = mu1 [1] (eq. 3); NaN where mu1 <= 0."""
    return chi_c_inertial(mu1, 1.0, 0.0)


def chi_c_inertial(mu1, A, gamma):
    """Critical reduced stiffness with inertia, chi_c = mu1 (1 + gamma/A) [1] (eq. 3 generalised).

    From the Routh-Hurwitz condition on :func:`characteristic_roots`. mu1, A, gamma [1]; NaN where mu1 <= 0
    (steady sliding is then stable at every chi > 0: no Hopf line).
    """
    mu1 = np.asarray(mu1, dtype=float)
    return _nan_unless_positive(mu1, mu1 * (1.0 + np.asarray(gamma, dtype=float) / A))


def hopf_K_over_M(V, A, m1, m2, D0, V0=1e-6, g=9.81, inertial=False):
    """Hopf line in the (K/M, V) plane, (K/M)_c = (g/D0) chi_c(V) [s-2] (eq. 3).

    V, V0 [m s-1]; A, m1, m2 [1]; D0 [m]; g [m s-2]. ``inertial=False`` uses chi_c = mu1(V) (quasi-static),
    ``inertial=True`` chi_c = mu1(V) (1 + V^2/(g D0 A)). NaN where mu1(V) <= 0.
    """
    slope = mu1(V, m1, m2, V0)
    gamma = inertia_number(V, D0, g) if inertial else 0.0
    return K_over_M_from_chi(chi_c_inertial(slope, A, gamma), D0, g)


def omega_c(mu1, A):
    """Reduced critical pulsation omega_c = sqrt(mu1/A) [1] (eq. 4, quasi-static); NaN where mu1 <= 0."""
    mu1 = np.asarray(mu1, dtype=float)
    return _nan_unless_positive(mu1, np.sqrt(np.abs(mu1) / A))


def Omega_c(V, mu1, A, D0):
    """Critical pulsation Omega_c = (V/D0) sqrt(mu1/A) [s-1] (eq. 4). V [m s-1], D0 [m]; NaN where mu1 <= 0."""
    return _out(np.asarray(V, dtype=float) / D0 * omega_c(mu1, A))


def characteristic_roots(chi, mu1, A, gamma=0.0):
    """Roots sigma [1] of gamma s^3 + (gamma + A) s^2 + (chi - mu1) s + chi = 0 (linearised driven scene).

    sigma is the reduced growth rate (per unit tau) of perturbations of steady sliding. Inputs broadcast to a
    shape ``S``; the result is complex with shape ``S + (3,)``. Roots are sorted by decreasing real part (ties:
    decreasing imaginary part). Where ``gamma == 0`` the polynomial is the quadratic
    A s^2 + (chi - mu1) s + chi (quasi-static, eq. 3-4) and the last slot holds NaN+0j (the third root has
    gone to -infinity). Where any input is not finite, all three slots are NaN+0j.
    """
    chi, mu1, A, gamma = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (chi, mu1, A, gamma)))
    roots = np.full(chi.shape + (3,), np.nan + 0j)
    ok = np.isfinite(chi) & np.isfinite(mu1) & np.isfinite(A) & np.isfinite(gamma)
    for n, sel in ((3, ok & (gamma != 0)), (2, ok & (gamma == 0))):
        if not sel.any():
            continue
        g, a, c, m = gamma[sel], A[sel], chi[sel], mu1[sel]
        # monic coefficients [c_{n-1}, ..., c_0]; companion matrix eigenvalues (LAPACK, backward stable)
        coeffs = [(g + a) / g, (c - m) / g, c / g] if n == 3 else [(c - m) / a, c / a]
        comp = np.zeros(g.shape + (n, n))
        comp[..., 0, :] = -np.stack(coeffs, axis=-1)
        comp[..., np.arange(1, n), np.arange(n - 1)] = 1.0
        r = np.linalg.eigvals(comp).astype(complex)
        order = np.lexsort((-r.imag, -r.real), axis=-1)
        roots[sel, :n] = np.take_along_axis(r, order, axis=-1)
    return roots


def growth_rate_linear(chi, mu1, A, gamma=0.0):
    """Largest real part of :func:`characteristic_roots` [1] (growth rate per unit tau; < 0: stable)."""
    return _out(np.fmax.reduce(characteristic_roots(chi, mu1, A, gamma).real, axis=-1))


def stable_sliding(chi, mu1, A, gamma=0.0):
    """True where steady sliding is linearly stable, chi > chi_c(mu1, A, gamma); always True where mu1 <= 0.

    chi, mu1, A, gamma [1]; chi > 0 assumed (physical stiffness). (eq. 3.)
    """
    chi_c = chi_c_inertial(mu1, A, gamma)
    with np.errstate(invalid="ignore"):
        return _out((np.asarray(mu1) <= 0) | (np.asarray(chi) > chi_c))


# --- stop scene: relaxed slip (quasi-static, eqs. 7-13) ------------------------------------------------

def xi_inf_m2zero(chi, A, m1):
    """Exact quasi-static relaxed slip for m2 = 0: xi_inf = A ln(chi/m1)/(chi - m1) [1]; A/m1 at chi = m1.

    Derivation. With s = int_0^tau dtau'/psi the stop equations A ln(xi' psi) = -chi xi - delta_mu(psi),
    psi' = 1 - xi' psi (docs/physics.md 3a, eqs. 7-8) become

        dxi/ds = E,   d(ln psi)/ds = 1 - E,   E = exp(-(chi xi + delta_mu)/A),

    so xi + ln psi = s. For m2 = 0, delta_mu = m1 (s - xi) and dxi/ds = exp(-((chi - m1) xi + m1 s)/A)
    separates: (A/(chi - m1)) (exp((chi - m1) xi/A) - 1) = (A/m1) (1 - exp(-m1 s/A)). As s -> inf
    (needs m1 > 0), exp((chi - m1) xi_inf/A) = chi/m1.

    chi, A, m1 [1]. Evaluated as (A/m1) log1p(x)/x with x = chi/m1 - 1 (series for abs(x) < 1e-4), so it is
    smooth through chi = m1. NaN where m1 <= 0 (xi grows without bound) or chi <= 0.
    """
    chi, m1 = np.asarray(chi, dtype=float), np.asarray(m1, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (chi - m1) / m1
        series = 1.0 - x / 2.0 + x**2 / 3.0 - x**3 / 4.0
        ratio = np.where(np.abs(x) < 1e-4, series, np.log1p(x) / np.where(x == 0, 1.0, x))
        value = np.where(chi > 0, A / m1 * ratio, np.nan)
    return _nan_unless_positive(m1, value)


def xi_inf_from_integral(chi, A, I):
    """Relaxed slip from the integral I = int_0^inf psi^-(1 + m1/A) dtau (m2 = 0) [1] (eq. 9).

    xi_inf = (A/chi) ln(1 + chi I/A). chi, A, I [1]. Follows from exp(chi xi/A) dxi = psi^-(1+m1/A) dtau.
    """
    chi = np.asarray(chi, dtype=float)
    return _out(A / chi * np.log1p(chi * np.asarray(I, dtype=float) / A))


def xi_inf_crude(chi, A, mu1):
    """Crude estimate of the relaxed slip, (A/chi) ln(1 + (chi/A)(1 + A/mu1)) [1] (eq. 10).

    Eq. 9 with I ~ 1 + A/mu1. chi, A, mu1 [1]; NaN where mu1 <= 0. Not a bound: a trend (docs/physics.md 4).
    """
    mu1 = np.asarray(mu1, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        value = xi_inf_from_integral(chi, A, 1.0 + A / mu1)
    return _nan_unless_positive(mu1, value)


def stress_relaxation_near_hopf(chi_c, A):
    """Reduced stress relaxation near the Hopf line, chi xi_inf ~ A ln(2 + chi_c/A) [1] (eq. 11)."""
    return _out(A * np.log(2.0 + np.asarray(chi_c, dtype=float) / A))


def xi_early(tau, chi, A):
    """Early-stage slip, tau << 1 (psi ~ 1): xi = (A/chi) ln(1 + chi tau/A) [1] (eq. 12).

    The exact limit as tau -> 0; it is eq. 9 with the integral truncated to I(tau) = tau.
    """
    return xi_inf_from_integral(chi, A, tau)


def xi_late_deficit(tau, chi, A, m1, xi_inf):
    """Late-stage deficit, tau >> 1 (psi ~ tau), m2 = 0: xi_inf - xi(tau) ~ (A/m1) e^(-chi xi_inf/A) tau^(-m1/A).

    [1] (eq. 13). tau, chi, A, m1, xi_inf [1]. Its relative error decays only like tau^(-m1/A). NaN where
    m1 <= 0.
    """
    m1 = np.asarray(m1, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        value = A / m1 * np.exp(-chi * np.asarray(xi_inf, dtype=float) / A) * np.asarray(tau, float) ** (-m1 / A)
    return _nan_unless_positive(m1, value)


def xi_inertial(gamma, chi):
    """Pure inertial stop (constant friction), xi_in = Dx_in/D0 = sqrt(gamma/chi) [1] (eqs. 14-15)."""
    return _out(np.sqrt(np.asarray(gamma, dtype=float) / chi))
