"""Quasi-static stop scene (PHYSICS.md 3a; paper eqs. 7-9), compiled with numba.

The paper's equations in reduced time tau (' = d/dtau, u = ln psi),

    A ln(xi' psi) = -chi xi - dmu(psi),    psi' = 1 - xi' psi,    xi(0) = 0, psi(0) = 1,

are integrated in the *contact-age time* s = int_0^tau dtau'/psi. There they read

    dxi/ds = E,    du/ds = 1 - E,    E = xi' psi = exp(-(chi xi + mu1 u + m2 u^2)/A),

so that xi + u = s exactly: the state is the single number xi (u = s - xi), and tau = int e^u ds is a
quadrature carried only when a time-resolved observable is asked for. In s the costly corner of the tau
form (psi << tau, small chi/A with mu1 < 0; PHYSICS.md 6) is only mildly stiff: its rate is |mu1 + 2 m2 u|/A.

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
Every function here is written for one point; the batch loop lives in :mod:`sweep.engine`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..status import Status

OK = int(Status.OK)
MAX_STEPS = int(Status.MAX_STEPS)
NONFINITE = int(Status.NONFINITE)
NO_FINITE_LIMIT = int(Status.NO_FINITE_LIMIT)

EXP_MAX = 700.0
"""Largest exponent passed to exp (exp(709.8) overflows float64); beyond it the point is flagged nonfinite."""
E_TAIL_MAX = 0.05
"""The closed-form tail is used only once E = xi' psi has fallen below this."""
TAIL_SAFETY = 0.1
"""Fraction of the tolerance allowed for the truncation of the tail series."""
RATE_FLOOR = 0.1
"""Floor of the late rate r(u) of the time map (bounds the step in s by h/RATE_FLOOR)."""
SQRT_PI = math.sqrt(math.pi)
FAST = {"nsz", "arcp", "contract", "afn"}
"""fastmath flags of every kernel here (~9 % faster): FMA contraction and reciprocal division, but no "nnan" or
"ninf" (the status codes rely on isfinite) and no "reassoc" (results stay reproducible on one instruction set)."""


@njit(cache=True, fastmath=FAST)
def erfcx(z: float) -> float:
    """Scaled complementary error function exp(z^2) erfc(z) for z >= 0 (asymptotic series beyond 25)."""
    if z < 25.0:
        return math.exp(z * z) * math.erfc(z)
    iz2 = 1.0 / (z * z)
    return (1.0 - 0.5 * iz2 * (1.0 - 1.5 * iz2 * (1.0 - 2.5 * iz2))) / (z * SQRT_PI)


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


@njit(cache=True, fastmath=FAST)
def tail_is_accurate(k: float, a: float, b: float, u: float, E: float, tol: float) -> bool:
    """True once the closed-form tail's own error is below TAIL_SAFETY * tol (absolute, reduced).

    Requires E to decrease from here on (mu1 + 2 m2 u > 0). The neglected E^3 term contributes
    ~E^3/(3 g) and freezing xi in the E^2 term ~E^3 k/(2 g^2), g = a + 2 b u the decay rate of E.
    """
    g = a + 2.0 * b * u
    if g <= 0.0 or E > E_TAIL_MAX:
        return False
    return E * E * E * (1.0 / (3.0 * g) + k / (2.0 * g * g)) <= TAIL_SAFETY * tol


@njit(cache=True, fastmath=FAST)
def derivatives(xi, s, k, a, b, s_c, with_tau):
    """d(xi, s, tau)/dsigma and E at one state; NaN derivatives flag an exponent beyond EXP_MAX."""
    u = s - xi
    g = a + 2.0 * b * u
    r = math.sqrt(g * g + 0.25 * abs(b)) + RATE_FLOOR
    w = (s + s_c) / (1.0 + r * (s + s_c))  # = 1/(1/(s + s_c) + r), one division
    expo = -(k * xi + u * (a + b * u))
    if expo > EXP_MAX or (with_tau and u > EXP_MAX):
        return math.nan, w, math.nan, math.nan
    E = math.exp(expo)
    dtau = w * math.exp(u) if with_tau else 0.0
    return w * E, w, dtau, E


@njit(cache=True, fastmath=FAST)
def hermite(y0, y1, m0, m1, t):
    """Cubic Hermite interpolant on [0, 1] with end slopes m0, m1 (already scaled by the step)."""
    t2 = t * t
    t3 = t2 * t
    return (2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * m1


@njit(cache=True, fastmath=FAST)
def hermite_crossing(y0, y1, m0, m1, target):
    """theta in [0, 1] where the increasing Hermite interpolant equals target (safeguarded Newton)."""
    lo, hi = 0.0, 1.0
    t = (target - y0) / (y1 - y0) if y1 > y0 else 0.5
    for _ in range(60):
        t2 = t * t
        f = hermite(y0, y1, m0, m1, t) - target
        if f > 0.0:
            hi = t
        else:
            lo = t
        df = (6 * t2 - 6 * t) * y0 + (3 * t2 - 4 * t + 1) * m0 + (-6 * t2 + 6 * t) * y1 + (3 * t2 - 2 * t) * m1
        tn = t - f / df if df > 0.0 else 0.5 * (lo + hi)
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= 1e-15:
            return tn
        t = tn
    return t


@njit(cache=True, fastmath=FAST)
def rk4_step(xi, s, tau, dxi, ds, dtau, h, k, a, b, s_c, with_tau):
    """One classical RK4 step (solvers.tableau.RK4) of size h in sigma from a state and its derivative."""
    k2x, k2s, k2t, _ = derivatives(xi + 0.5 * h * dxi, s + 0.5 * h * ds, k, a, b, s_c, with_tau)
    k3x, k3s, k3t, _ = derivatives(xi + 0.5 * h * k2x, s + 0.5 * h * k2s, k, a, b, s_c, with_tau)
    k4x, k4s, k4t, _ = derivatives(xi + h * k3x, s + h * k3s, k, a, b, s_c, with_tau)
    return (xi + h / 6.0 * (dxi + 2.0 * (k2x + k3x) + k4x),
            s + h / 6.0 * (ds + 2.0 * (k2s + k3s) + k4s),
            tau + h / 6.0 * (dtau + 2.0 * (k2t + k3t) + k4t))


@njit(cache=True, fastmath=FAST)
def state_where(component, target, theta, xi, s, tau, dxi, ds, dtau, h, k, a, b, s_c):
    """State (xi, s, tau) and slip rate dxi/dtau inside a step where ``component`` (0: xi, 2: tau) equals
    ``target``.

    Newton on theta in [0, 1] with exact partial RK4 steps of size theta*h from the step's start (fifth-order
    local error, like the step itself), started from the Hermite estimate ``theta``.
    """
    for _ in range(8):
        x1, s1, t1 = rk4_step(xi, s, tau, dxi, ds, dtau, theta * h, k, a, b, s_c, True)
        value = x1 if component == 0 else t1
        dx1, _, dt1, _ = derivatives(x1, s1, k, a, b, s_c, True)
        slope = h * (dx1 if component == 0 else dt1)
        miss = value - target
        if abs(miss) <= 4e-16 * abs(target) or not slope > 0.0:
            break
        theta = min(1.0, max(0.0, theta - miss / slope))
    return x1, s1, t1, dx1 / dt1


@njit(cache=True, fastmath=FAST)
def continue_in_closed_form(k, a, b, xi_inf, u_e, tau_e, tau_targets, xi_at, u_at):
    """xi and u = ln psi at reduced times beyond a state (u_e, tau_e) where E is already negligible.

    With E -> 0, ds = du/(1 - E) -> du and dtau = e^u ds, so tau = tau_e + e^u - e^u_e; the slip still to come
    at u is the closed-form tail (:func:`tail_slip`) with E evaluated at xi_inf. The neglected terms are
    relatively O(E_e/|1 - (mu1 + 2 m2 u)/A|) in psi and O(E^2) in xi; called once E_e < TAIL_SAFETY rtol, this
    replaces the integration of the long, featureless late trajectory (e.g. tau up to 1e250) by a formula.
    """
    for j in range(tau_targets.size):
        u = u_e + math.log1p((tau_targets[j] - tau_e) * math.exp(-u_e))
        u_at[j] = u
        xi_at[j] = xi_inf - tail_slip(k, a, b, u, math.exp(-(k * xi_inf + u * (a + b * u))))


@njit(cache=True, fastmath=FAST)
def march(k, a, b, h, s_c, max_steps, want_limit, rtol, atol, tau_targets, xi_at, u_at, xi_targets, tau_at,
          rate_at):
    """Integrate one stop point with fixed-step RK4 in sigma.

    Records xi and u = ln psi where tau crosses each of the increasing ``tau_targets`` (into xi_at, u_at)
    and tau and the slip rate dxi/dtau where xi crosses each of the increasing ``xi_targets`` (into tau_at,
    rate_at), from exact partial steps; tau targets beyond the end of the transient (E < TAIL_SAFETY rtol,
    relaxed slip known) come from :func:`continue_in_closed_form`
    (:func:`state_where`). Stops when the tail test passes (if ``want_limit``) and all targets are recorded.
    Returns (status, xi_inf, steps); xi_inf is NaN unless the tail was reached.
    """
    with_tau = tau_targets.size > 0 or xi_targets.size > 0
    xi, s, tau = 0.0, 0.0, 0.0
    dxi, ds, dtau, E = derivatives(xi, s, k, a, b, s_c, with_tau)
    it, ix = 0, 0
    while it < tau_targets.size and tau_targets[it] <= 0.0:
        xi_at[it], u_at[it] = 0.0, 0.0
        it += 1
    xi_inf = math.nan
    tail_done = not want_limit
    n = 0
    while n < max_steps:
        # stage 1 of each step is the previous step's end derivative (FSAL reuse)
        xi1, s1, tau1 = rk4_step(xi, s, tau, dxi, ds, dtau, h, k, a, b, s_c, with_tau)
        dxi1, ds1, dtau1, E = derivatives(xi1, s1, k, a, b, s_c, with_tau)
        n += 1
        if not (math.isfinite(xi1) and math.isfinite(dxi1) and math.isfinite(tau1) and math.isfinite(dtau1)):
            return NONFINITE, math.nan, n
        while it < tau_targets.size and tau_targets[it] <= tau1:
            th = hermite_crossing(tau, tau1, h * dtau, h * dtau1, tau_targets[it])
            xt, st, _, _ = state_where(2, tau_targets[it], th, xi, s, tau, dxi, ds, dtau, h, k, a, b, s_c)
            xi_at[it], u_at[it] = xt, st - xt
            it += 1
        while ix < xi_targets.size and xi_targets[ix] <= xi1:
            th = hermite_crossing(xi, xi1, h * dxi, h * dxi1, xi_targets[ix])
            _, _, tau_at[ix], rate_at[ix] = state_where(0, xi_targets[ix], th, xi, s, tau, dxi, ds, dtau, h, k, a,
                                                        b, s_c)
            ix += 1
        xi, s, tau, dxi, ds, dtau = xi1, s1, tau1, dxi1, ds1, dtau1
        if not tail_done:
            u = s - xi
            if tail_is_accurate(k, a, b, u, E, rtol * xi + atol):
                xi_inf = xi + tail_slip(k, a, b, u, E)
                tail_done = True
        if it < tau_targets.size and E < TAIL_SAFETY * rtol and math.isfinite(xi_inf):
            continue_in_closed_form(k, a, b, xi_inf, s - xi, tau, tau_targets[it:], xi_at[it:], u_at[it:])
            it = tau_targets.size
        if tail_done and it == tau_targets.size and ix == xi_targets.size:
            return OK, xi_inf, n
    return MAX_STEPS, xi_inf, n


@njit(cache=True, fastmath=FAST)
def solve_stop_point(k, a, b, h, s_c, max_steps, finite, rtol, atol, tau_targets, xi_at, u_at,
                     fractions, tau_at_fraction):
    """One stop point: pass 1 gives xi_inf and the time-resolved samples; if ``fractions`` is not empty a
    second pass (same steps) finds tau where xi = fraction * xi_inf (e.g. t50, t90).

    t_f is ill-conditioned where the slip creeps: an error d in xi_inf moves it by f d / xi'(t_f), i.e.
    relatively by G = f xi_inf / (t_f xi'(t_f)) times rtol (G ~ 30 for t90 with m1/A = 0.3). Where G > 1 the
    relaxed slip is recomputed with rtol/G (step h G^(-1/4)) before the crossings are located again.
    Returns (status, xi_inf, steps of pass 1)."""
    none = np.empty(0)
    status, xi_inf, n = march(k, a, b, h, s_c, max_steps, finite, rtol, atol, tau_targets, xi_at, u_at,
                              none, none, none)
    tau_at_fraction[:] = math.nan
    if not finite:
        return (NO_FINITE_LIMIT if status == OK else status), math.nan, n
    if fractions.size == 0 or status != OK:
        return status, xi_inf, n
    rate = np.empty(fractions.size)
    status, _, _ = march(k, a, b, h, s_c, max_steps, False, rtol, atol, none, none, none, fractions * xi_inf,
                         tau_at_fraction, rate)
    gain = np.max(fractions * xi_inf / (tau_at_fraction * rate)) if status == OK else 0.0
    if gain > 1.0:
        status, xi_inf, _ = march(k, a, b, h * gain**-0.25, s_c, max_steps, True, rtol / gain, atol / gain,
                                  none, none, none, none, none, none)
        if status == OK:
            status, _, _ = march(k, a, b, h, s_c, max_steps, False, rtol, atol, none, none, none,
                                 fractions * xi_inf, tau_at_fraction, rate)
    return status, xi_inf, n
