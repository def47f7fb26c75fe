"""Quasi-static stop scene (docs/physics.md 3a; paper eqs. 7-9), compiled with numba.

The paper's equations in reduced time tau (' = d/dtau, u = ln psi),

    A ln(xi' psi) = -chi xi - dmu(psi),    psi' = 1 - xi' psi,    xi(0) = 0, psi(0) = 1,

are integrated in the *contact-age time* s = int_0^tau dtau'/psi. There they read

    dxi/ds = E,    du/ds = 1 - E,    E = xi' psi = exp(-(chi xi + mu1 u + m2 u^2)/A),

so that xi + u = s exactly: the state is the single number xi (u = s - xi), and tau = int e^u ds is a
quadrature carried only when a time-resolved observable is asked for. In s the costly corner of the tau
form (psi << tau, small chi/A with mu1 < 0; docs/physics.md 6) is only mildly stiff: its rate is |mu1 + 2 m2 u|/A.

Fixed-step RK4 runs in a scaled log time sigma, ds/dsigma = w = 1/(1/(s + s_c) + r(u)): logarithmic early
(resolving the stiff start, rate (chi - mu1)/A, with s_c = 1/(1 + (chi + |mu1|)/A)) and with step h/r late, where
r(u) = sqrt(g^2 + |m2|/(4A)) + 0.1 follows the local rate g = (mu1 + 2 m2 u)/A: the decay rate of E in the tail
and the stiffness |g| along the slow creep manifold of the costly corner, which flattens near its fold (g -> 0),
so the steps grow there (a third fewer steps on the default grid than a fixed late step 1/max|g|). s is a
state of the autonomous system (xi, s[, tau]) so no transcendental call is spent on the map.

The integration stops once the remaining slip can be written in closed form (:func:`tail_slip`): from
dxi/du = E/(1 - E) and E = exp(-chi xi/A) exp(-(mu1 u + m2 u^2)/A),

    (A/chi) [exp(chi xi_inf/A) - exp(chi xi_e/A)] = int_{u_e}^inf exp(-(mu1 u + m2 u^2)/A) (1 + E + ...) du,

whose first two terms are exponential (m2 = 0) or Gaussian (m2 > 0, via erfcx) integrals. This generalises the
paper's eq. 13 to m2 != 0; the neglected E^3 term and the frozen-xi error are bounded by the stopping test.
Every function here is written for one point; the batch loop lives in :mod:`sweep.protocols.stop.engine`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ...accuracy import E_TAIL_MAX, RATE_FLOOR, TAIL_SAFETY
from ...jitcache import pin, pin_module
from ...status import Status
from ..solvers.fastmath import FAST
from ..solvers.vmath import EXP_MAX, exp_f32, exp_f64

OK = int(Status.OK)
MAX_STEPS = int(Status.MAX_STEPS)
NONFINITE = int(Status.NONFINITE)
NO_FINITE_LIMIT = int(Status.NO_FINITE_LIMIT)

SQRT_PI = math.sqrt(math.pi)


@njit(cache=True, fastmath=FAST)
def erfcx(z: float) -> float:
    """Scaled complementary error function exp(z^2) erfc(z) for z >= 0 (asymptotic series beyond 25, to z^-14: its
    first omitted term is 2e-17 relative at z = 25; cut after z^-6, as before, it was 4e-11, an error of the closed-form
    tail that no step size changes and that showed as a 3.6e-11 relative offset of xi_inf from the scipy reference)."""
    if z < 25.0:
        return math.exp(z * z) * math.erfc(z)
    iz2 = 1.0 / (z * z)
    series = 1.0 - 5.5 * iz2 * (1.0 - 6.5 * iz2)
    for k in (4.5, 3.5, 2.5, 1.5, 0.5):  # 1 - (2k-1)!!/(2z^2)^k ... in nested form
        series = 1.0 - k * iz2 * series
    return series / (z * SQRT_PI)


@njit(cache=True, fastmath=FAST)
def tail_integral(a: float, b: float, u: float, order: float) -> float:
    """exp(order (a u + b u^2)) int_u^inf exp(-order (a v + b v^2)) dv, for b >= 0 and a + 2 b u > 0 [1]."""
    if b == 0.0:
        return 1.0 / (order * a)
    kb = order * b
    return 0.5 * SQRT_PI / math.sqrt(kb) * erfcx(math.sqrt(kb) * (u + 0.5 * a / b))


@njit(cache=True, fastmath=FAST)
def tail_slip(k: float, a: float, b: float, u: float, E: float) -> float:
    """Reduced slip remaining after the horizon, xi_inf - xi_e, from the state (u_e, E_e) [1].

    k = chi/A, a = mu1/A, b = m2/A. Two terms of the series in E (module docstring); exact as E -> 0.
    """
    T = E * tail_integral(a, b, u, 1.0) + E * E * tail_integral(a, b, u, 2.0)
    return math.log1p(k * T) / k


@njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
def tail_bound(k: float, g: float, E: float) -> float:
    """The bound of :func:`tail_error` where the tail applies (g = a + 2 b u > 0, E <= E_TAIL_MAX), without those
    checks: straight-line code for the vectorised lane loops (sweep/integrate/lanes_adaptive.py), which test them
    as selects."""
    return E * E * E * (1.0 / (3.0 * g) + k / (2.0 * g * g))


@njit(cache=True, fastmath=FAST)
def tail_error(k: float, a: float, b: float, u: float, E: float) -> float:
    """Bound on the closed-form tail's own error (absolute, reduced); inf where it does not apply yet.

    Requires E to decrease from here on (mu1 + 2 m2 u > 0) and E <= E_TAIL_MAX. The neglected E^3 term
    contributes ~E^3/(3 g) and freezing xi in the E^2 term ~E^3 k/(2 g^2), g = a + 2 b u the decay rate of E.
    """
    g = a + 2.0 * b * u
    if g <= 0.0 or E > E_TAIL_MAX:
        return math.inf
    return tail_bound(k, g, E)


@njit(cache=True, fastmath=FAST)
def tail_is_accurate(k: float, a: float, b: float, u: float, E: float, tol: float) -> bool:
    """True once the closed-form tail's own error is below TAIL_SAFETY * tol (absolute, reduced)."""
    return tail_error(k, a, b, u, E) <= TAIL_SAFETY * tol


def make_rate(dtype):
    """The stop equations in sigma for one float type (float64 or float32), vectorisable over lanes:
    rate(xi, s, k, a, b, s_c) -> (dxi/dsigma, ds/dsigma, E, exponent of E). Every constant has the given type
    so that float32 lanes never widen to float64; the exponent is returned so that callers can flag values
    beyond EXP_MAX (exp itself is clamped, :mod:`sweep.integrate.solvers.vmath`)."""
    f = np.dtype(dtype).type
    exp = exp_f32 if f is np.float32 else exp_f64
    one, two, quarter, floor = f(1.0), f(2.0), f(0.25), f(RATE_FLOOR)

    @njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
    def rate(xi, s, k, a, b, s_c):
        u = s - xi
        g = a + two * b * u
        r = math.sqrt(g * g + quarter * abs(b)) + floor
        w = (s + s_c) / (one + r * (s + s_c))  # = 1/(1/(s + s_c) + r), one division
        expo = -(k * xi + u * (a + b * u))
        E = exp(expo)
        return w * E, w, E, expo

    return pin(rate, f.__name__)


rate_f64 = make_rate(np.float64)
rate_f32 = make_rate(np.float32)


class StopParams(NamedTuple):
    """Reduced parameters of one quasi-static stop point, for the right-hand side in sigma."""

    k: float
    """chi/A."""
    a: float
    """mu1(V)/A."""
    b: float
    """m2/A."""
    s_c: float
    """Scale of the early log time (sweep/plan/plan.py time_scale)."""
    with_tau: bool
    """Whether the quadrature tau = int e^u ds is carried (time-resolved observables)."""


@njit(cache=True, fastmath=FAST, error_model="numpy")
def derivatives(xi, s, p):
    """d(xi, s, tau)/dsigma and E at one state (float64); NaN derivatives flag an exponent beyond EXP_MAX."""
    dxi, w, E, expo = rate_f64(xi, s, p.k, p.a, p.b, p.s_c)
    u = s - xi
    if expo > EXP_MAX or (p.with_tau and u > EXP_MAX):
        return math.nan, w, math.nan, math.nan
    return dxi, w, w * exp_f64(u) if p.with_tau else 0.0, E


@njit(cache=True, fastmath=FAST)
def continue_in_closed_form(k, a, b, xi_inf, u_e, tau_e, tau_targets, xi_at, u_at):
    """xi and u = ln psi at reduced times beyond a state (u_e, tau_e) where E is already negligible.

    With E -> 0, ds = du/(1 - E) -> du and dtau = e^u ds, so tau = tau_e + e^u - e^u_e; the slip still to come
    at u is the closed-form tail (:func:`tail_slip`) with E evaluated at xi_inf. The neglected terms are bounded
    in u by :func:`continuation_error` and are O(E^2) in xi; called once E_e is far below rtol, this replaces the
    integration of the long, featureless late trajectory (e.g. tau up to 1e250) by a formula.
    """
    for j in range(tau_targets.size):
        u = u_e + math.log1p((tau_targets[j] - tau_e) * math.exp(-u_e))
        u_at[j] = u
        xi_at[j] = xi_inf - tail_slip(k, a, b, u, math.exp(-(k * xi_inf + u * (a + b * u))))


@njit(cache=True, fastmath=FAST)
def continuation_error(E_e: float, g_e: float, du: float) -> float:
    """Bound on the error in u = ln psi (i.e. the relative error of psi) of :func:`continue_in_closed_form` at
    du = u - u_e >= 0 past its start (E_e = E there, g_e = (mu1 + 2 m2 u_e)/A > 0).

    Exactly dtau/du = e^u/(1 - E), while the closed form takes e^u: at a given tau the true u is lower by
    delta <= e^-u int_{u_e}^u e^v E/(1 - E) dv. As long as m2 >= 0, d ln E/du = -(k dxi/du + a + 2 b u) <= -g_e, so
    E(v) <= E_e e^(-g_e (v - u_e)) and

        delta <= E_e/(1 - E_e) (e^(-g_e du) - e^(-du))/(1 - g_e)        (du e^-du at g_e = 1)

    (to first order in E_e, which also shifts du). It vanishes at the start, peaks at du ~ ln(g_e)/(g_e - 1) and
    then decays like e^(-min(g_e, 1) du): the bound E_e/g_e used before, the whole slip rate integral, held at
    every later sample and overstated late psi errors up to ~400x.
    """
    c = 1.0 - g_e  # written with expm1 of a negative argument: exact near g_e = 1, no overflow at large du
    if c == 0.0:
        shape = du * math.exp(-du)
    elif c > 0.0:
        shape = -math.exp(-g_e * du) * math.expm1(-c * du) / c
    else:
        shape = math.exp(-du) * math.expm1(c * du) / c
    return E_e / (1.0 - E_e) * shape


pin_module(__name__)
