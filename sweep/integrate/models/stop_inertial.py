"""Stop scene with inertia (docs/physics.md 3a), and the first-order inertial correction of the quasi-static model.

The Newton equation gamma xi'' = -chi xi - dmu(psi) - A ln(xi' psi) (' = d/dtau) is written in the contact-age time
s = int dtau/psi of :mod:`sweep.integrate.models.stop`, where xi + u = s still holds exactly (u = ln psi), with
q = ln(xi' psi) = ln E as the second state (k = chi/A, a = mu1/A, b = m2/A, G = gamma/A):

    dxi/ds = e^q,    dq/ds = -P R + 1 - e^q,
    P = k xi + a u + b u^2 + q = (q - q_qs),    R = e^(2u - q)/G = A psi/(gamma xi'),

P being the inertial term: A P = -gamma xi'' exactly, q_qs the quasi-static ln E. R is the relaxation rate of P in
s: 1/G at the start, growing without bound late in every stop (as psi/xi').

Plunge-resolving time sigma. Where k G is large the slider swings inertially to xi ~ sqrt(G/k) and the swing ends in
a plunge: P ~ sqrt(k G) >> 1 relaxes at the rate R ~ e^(-q)/G while q falls to q_qs ~ -sqrt(k G), so q(s) has a
log singularity (steps in s shrink by e per unit fall of q, ~70 steps each at rtol 1e-7) and the span of s left
falls below the resolution of s once R > ~1e12/s (in s, the steps would underflow wherever k G > ~1e2).
:func:`inertial_system` integrates (s, xi, q) in sigma instead,

    ds/dsigma = w = 1/(1 + R (nu s + mu P^2)),    dxi/dsigma = w E,    dq/dsigma = w (1 - E) - w R P,

(mu = PLUNGE_WEIGHT, nu = S_WEIGHT): w = 1 up to rounding on the slow path (P ~ (k + |g| + 1)/R, so R mu P^2 << 1)
and in the swing, and w ~ 1/(R mu P^2) in the plunge, where q then falls at ~1/(mu P) per unit sigma, smoothly; the
nu s term takes over wherever R > ~1/(nu s), where a step in s could no longer resolve the last relaxation of P. The
map changes the time, not the solution. The system is integrated with the L-stable, stiffly accurate RODAS3
(:data:`sweep.integrate.solvers.RODAS3`) and the analytic 3x3 Jacobian, step size by the embedded error (controller
of sweep/integrate/stop_inertial.py), and handed over to the quasi-static form (state xi alone in s, as in
:mod:`sweep.integrate.models.stop`) once inertia is negligible now and later:

    |P| <= eps,   (k + |g| + 1)/R <= eps,   d ln R/ds = 2 (1 - E) - dq/ds > 0,    eps = HANDOVER_FRACTION rtol,

the second being a bound on the slaved inertial term -gamma xi''/A along the quasi-static solution, P_slaved =
(k E + (g + 1)(1 - E))/R with g = a + 2 b u, which keeps decreasing while R grows. After the hand-over the
neglected term shifts dxi/ds by a factor e^P, i.e. xi_inf by <= eps times the slip still to come. The quasi-static
phase ends in the closed-form tail of :mod:`sweep.integrate.models.stop` (``tail_slip``, with its own error test).

The same quasi-static phase, run from the start with G > 0, carries the first-order inertial correction
y = d xi (model error of the quasi-static model, to first order in G): perturbing q_qs by P_slaved,

    dy/ds = J y + S,    J = dE/dxi = E (g - k),    S = E P_slaved = G E^2 e^(-2u) (k E + (g + 1)(1 - E)),

(a singular-perturbation expansion; the initial layer, where P rises from 0 to P_slaved over s ~ G, adds O(G^2)).
:func:`relax` returns y at the end, propagated through the closed-form tail to first order in E. Measured against
the inertial model: the true gap is 0.80..1.17x |y|/xi_inf where G (1 + k + |a|) <= 1, 0.70..1.33x where <= 2,
and the expansion fails beyond a few (down to 1e-6 of it at k = 1e3, G = 1, where the slider rebounds and xi_inf ~
sqrt(G/k), the pure-inertia slip of eq. 15). ``model="auto"`` uses it where it holds
(sweep/protocols/stop/model_choice.py).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...jitcache import pin, pin_module
from ..solvers.fastmath import FAST
from ..solvers.vmath import EXP_MAX, exp_f32, exp_f64_coarse
from .stop import tail_integral

__all__ = ["LN_R_MAX", "PLUNGE_WEIGHT", "S_WEIGHT", "inertia_negligible", "inertial_system", "make_correction_rate",
           "quasistatic_system", "tail_correction", "time_rate"]

LN_R_MAX = 600.0
"""Cap of ln R in the right-hand side (comment there)."""
PLUNGE_WEIGHT = 1e-6
"""mu of the time map ds/dsigma = 1/(1 + R (nu s + mu P^2)) (module docstring): sigma takes over from s once the
inertial term relaxes at a rate R > ~1/(mu P^2), i.e. in the plunge at the end of a swing (P ~ 1..1e4), and not
on the slow path (P ~ (k + |g| + 1)/R)."""
S_WEIGHT = 1e-13
"""nu of the time map: sigma takes over from s wherever R > ~1e13/s, where a step in s that resolves a transient
at the rate R (~1e-3/R at rtol 1e-7) would fall below the resolution of s itself (~1e-15 s)."""


@njit(inline="always", fastmath=FAST, error_model="numpy")
def inertial_system(sigma, y, p, f, J, ft, jacobian):
    """The inertial system in the plunge-resolving time sigma (module docstring) for
    :func:`sweep.integrate.solvers.rosenbrock_step.make_rodas3_step`: y = (s, xi, q), p = (k, a, b, G, mu, nu);
    autonomous (ft = 0)."""
    k, a, b, G, mu, nu = p
    s, xi, q = y[0], y[1], y[2]
    u = s - xi
    g = a + 2.0 * b * u
    P = k * xi + u * (a + b * u) + q
    # R capped at e^LN_R_MAX: beyond that the inertial term relaxes in far less than any step in s, and w R stays
    # ~1/(nu s + mu P^2) whatever R, so the cap only stops R itself from overflowing
    ln_r = 2.0 * u - q - math.log(G)
    free = 1.0 if ln_r < LN_R_MAX else 0.0
    R = math.exp(min(ln_r, LN_R_MAX))
    v = R * (nu * s + mu * P * P)
    w = 1.0 / (1.0 + v)
    wR = w * R
    E = math.exp(q) if q < EXP_MAX else math.nan
    f[0], f[1], f[2] = w, w * E, w * (1.0 - E) - wR * P
    if jacobian:
        # d ln R/d(s, xi, q) = free (2, -2, -1), dP/d(s, xi, q) = (g, k - g, 1), dv = v d ln R + R (nu ds + 2 mu P dP)
        c = 2.0 * mu * R * P
        dv0, dv1, dv2 = 2.0 * free * v + R * nu + c * g, -2.0 * free * v + c * (k - g), -free * v + c
        ww = w * w
        J[0, 0], J[0, 1], J[0, 2] = -ww * dv0, -ww * dv1, -ww * dv2
        J[1, 0], J[1, 1], J[1, 2] = -ww * dv0 * E, -ww * dv1 * E, (w - ww * dv2) * E
        # d(w R) = w R (d ln R - w dv)
        J[2, 0] = -ww * dv0 * (1.0 - E) - wR * (2.0 * free - w * dv0) * P - wR * g
        J[2, 1] = -ww * dv1 * (1.0 - E) - wR * (-2.0 * free - w * dv1) * P - wR * (k - g)
        J[2, 2] = -ww * dv2 * (1.0 - E) - w * E - wR * (-free - w * dv2) * P - wR
        ft[0], ft[1], ft[2] = 0.0, 0.0, 0.0


@njit(cache=True, fastmath=FAST, error_model="numpy")
def time_rate(y, p):
    """ds/dsigma = w at the state y = (s, xi, q) of :func:`inertial_system` (same p)."""
    k, a, b, G, mu, nu = p
    s, xi, q = y[0], y[1], y[2]
    u = s - xi
    P = k * xi + u * (a + b * u) + q
    R = math.exp(min(2.0 * u - q - math.log(G), LN_R_MAX))
    return 1.0 / (1.0 + R * (nu * s + mu * P * P))


@njit(inline="always", fastmath=FAST, error_model="numpy")
def quasistatic_system(s, y, p, f, J, ft, jacobian):
    """The quasi-static model in s with the first-order inertial correction (module docstring): y = (xi, y),
    dxi/ds = E, dy/ds = J y + S; p = (k, a, b, G), G = 0 leaves y at 0."""
    k, a, b, G = p
    xi, corr = y[0], y[1]
    u = s - xi
    g = a + 2.0 * b * u
    expo = -(k * xi + u * (a + b * u))
    E = math.exp(expo) if expo < EXP_MAX else math.nan
    dE = E * (g - k)
    w = G * math.exp(2.0 * (expo - u)) if G > 0.0 else 0.0
    Q = k * E + (g + 1.0) * (1.0 - E)
    S = w * Q
    f[0], f[1] = E, dE * corr + S
    if jacobian:
        dQ_ds = -k * g * E + 2.0 * b * (1.0 - E) + g * (g + 1.0) * E
        dQ_dxi = k * (g - k) * E - 2.0 * b * (1.0 - E) - (g + 1.0) * (g - k) * E
        J[0, 0], J[0, 1] = dE, 0.0
        J[1, 0], J[1, 1] = corr * ((g - k) * dE - 2.0 * b * E) + 2.0 * (g - k + 1.0) * S + w * dQ_dxi, dE
        ft[0], ft[1] = -g * E, corr * (-g * dE + 2.0 * b * E) - 2.0 * (g + 1.0) * S + w * dQ_ds


def make_correction_rate(dtype):
    """The first-order correction's equation in the lanes' time sigma (:mod:`sweep.integrate.models.stop`'s time map,
    ds/dsigma
    = w), for one float type and vectorisable over lanes: correction_rate(xi, s, y, k, a, b, G, w, E, expo) ->
    dy/dsigma = w (E (g - k) y + S), S = G E^2 e^(-2u) (k E + (g + 1)(1 - E)) (module docstring), from the state
    (xi, s, y) and what the quasi-static rate already computed there (w, E and its exponent expo). E^2 e^(-2u) is
    one more exponential, exp(2 (expo - u)): exact, where a third state e^(-u) would add its own truncation error."""
    f = np.dtype(dtype).type
    exp = exp_f32 if f is np.float32 else exp_f64_coarse
    one, two = f(1.0), f(2.0)

    @njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
    def correction_rate(xi, s, y, k, a, b, G, w, E, expo):
        u = s - xi
        g = a + two * b * u
        source = G * exp(two * (expo - u)) * (k * E + (g + one) * (one - E))
        return w * (E * (g - k) * y + source)

    return pin(correction_rate, f.__name__)


@njit(cache=True, fastmath=FAST, error_model="numpy")
def inertia_negligible(s, xi, q, k, a, b, G, eps):
    """The hand-over test of the module docstring at an accepted state: eps = HANDOVER_FRACTION rtol."""
    u = s - xi
    g = a + 2.0 * b * u
    P = k * xi + u * (a + b * u) + q
    ln_r = 2.0 * u - q - math.log(G)
    if abs(P) > eps or ln_r < math.log((k + abs(g) + 1.0) / eps):
        return False
    E = math.exp(q)
    return 2.0 * (1.0 - E) > 1.0 - E - P * math.exp(min(ln_r, EXP_MAX))


@njit(cache=True, fastmath=FAST, error_model="numpy")
def tail_correction(k, a, b, G, u, E, y):
    """First-order correction at infinity from y at the end of the integration: y times d xi_inf/d xi_e of the
    closed-form tail (1 + E (1 - k T1)/(1 + k T), T1 = tail_integral) plus the source still to come (S decays at
    the rate 2 (g + 1))."""
    g = a + 2.0 * b * u
    t1 = tail_integral(a, b, u, 1.0)
    T = E * t1
    S = G * E * E * math.exp(-2.0 * u) * (k * E + (g + 1.0) * (1.0 - E))
    return y * (1.0 + E * (1.0 - k * t1) / (1.0 + k * T)) + S / (2.0 * (g + 1.0))


pin_module(__name__)
