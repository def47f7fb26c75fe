"""Stop scene with inertia (docs/physics.md 3a), and the first-order inertial correction of the quasi-static model.

The Newton equation gamma xi'' = -chi xi - dmu(psi) - A ln(xi' psi) (' = d/dtau) is integrated in the
contact-age time s = int dtau/psi of :mod:`sweep.models.stop`, where xi + u = s still holds exactly (u = ln psi),
with q = ln(xi' psi) = ln E as the second state (k = chi/A, a = mu1/A, b = m2/A, G = gamma/A):

    dxi/ds = e^q,    dq/ds = -P R + 1 - e^q,
    P = k xi + a u + b u^2 + q = (q - q_qs),    R = e^(2u - q)/G = A psi/(gamma xi'),

P being the inertial term: A P = -gamma xi'' exactly, q_qs the quasi-static ln E. R is the relaxation rate of P in
s: 1/G at the start, growing without bound late in every stop (as psi/xi'). The system is integrated with the
L-stable, stiffly accurate RODAS3 (:data:`sweep.solvers.RODAS3`) and the analytic 2x2 Jacobian, step size by the
embedded error (controller below), and handed over to the quasi-static form (state xi alone, as in
:mod:`sweep.models.stop`) once inertia is negligible now and later:

    |P| <= eps,   (k + |g| + 1)/R <= eps,   d ln R/ds = 2 (1 - E) - dq/ds > 0,    eps = HANDOVER_FRACTION rtol,

the second being a bound on the slaved inertial term -gamma xi''/A along the quasi-static solution, P_slaved =
(k E + (g + 1)(1 - E))/R with g = a + 2 b u, which keeps decreasing while R grows. After the hand-over the
neglected term shifts dxi/ds by a factor e^P, i.e. xi_inf by <= eps times the slip still to come. The quasi-static
phase ends in the closed-form tail of :mod:`sweep.models.stop` (``tail_slip``, with its own error test).

The same quasi-static phase, run from the start with G > 0, carries the first-order inertial correction
y = d xi (model error of the quasi-static model, to first order in G): perturbing q_qs by P_slaved,

    dy/ds = J y + S,    J = dE/dxi = E (g - k),    S = E P_slaved = G E^2 e^(-2u) (k E + (g + 1)(1 - E)),

(a singular-perturbation expansion; the initial layer, where P rises from 0 to P_slaved over s ~ G, adds O(G^2)).
:func:`relax` returns y at the end, propagated through the closed-form tail to first order in E. Measured against
the inertial model: the true gap is 0.80..1.17x |y|/xi_inf where G (1 + k + |a|) <= 1, 0.70..1.33x where <= 2,
and the expansion fails beyond a few (down to 1e-6 of it at k = 1e3, G = 1, where the slider rebounds and xi_inf ~
sqrt(G/k), the pure-inertia slip of eq. 15). ``model="auto"`` uses it where it holds (sweep/model_choice.py).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..jitcache import pin_module
from ..solvers import RODAS3
from ..solvers.controllers import I_CONTROLLER, MIN_FACTOR, accepted_factor, rejected_factor
from ..solvers.rosenbrock_step import make_rodas3_step, scratch
from ..status import Status
from .stop import EXP_MAX, FAST, tail_integral, tail_is_accurate, tail_slip

__all__ = ["relax", "relax_batch", "relax_points", "HANDOVER_FRACTION", "RELAX_KEYS"]

RELAX_KEYS = ("xi_inf", "correction", "status", "steps", "s_handover")
"""The outputs of :func:`relax_points`."""

OK, MAX_STEPS, NONFINITE = int(Status.OK), int(Status.MAX_STEPS), int(Status.NONFINITE)
STEP_UNDERFLOW = int(Status.STEP_UNDERFLOW)

HANDOVER_FRACTION = 0.1
"""The inertial term is handed over once below this fraction of rtol (module docstring)."""
H_START = 1e-3
"""First step in s, times min(1, G, 1/k): the initial layer lasts s ~ G, the stiff start 1/k."""
H_FLOOR = 8.0 * 2.220446049250313e-16
"""Smallest step in s, relative to s, before a point is flagged step_underflow (a few ulps: below it s + h
stops moving). Relative, not absolute: where a fast rebound (k/G large) drops xi' towards 0, ln(xi' psi) has a
log singularity that the steps resolve down to ~1e-16 near s ~ 0.05, and then grow again."""
CONTROLLER = I_CONTROLLER._replace(nonfinite_factor=MIN_FACTOR)
"""The elementary controller of sweep/solvers/controllers.py (a stage that overflowed: the step is divided by 5)."""
ORDER = RODAS3.order_hat
"""Order of RODAS3's embedded error estimate (the controller's exponent is 1/(ORDER + 1))."""
LN_R_MAX = 600.0
"""Cap of ln R in the right-hand side (comment there)."""


@njit(inline="always", fastmath=FAST, error_model="numpy")
def inertial_system(s, y, p, f, J, ft, jacobian):
    """The inertial system in s (module docstring) for :func:`sweep.solvers.rosenbrock_step.make_rodas3_step`:
    y = (xi, q), p = (k, a, b, G)."""
    k, a, b, G = p
    xi, q = y[0], y[1]
    u = s - xi
    g = a + 2.0 * b * u
    P = k * xi + u * (a + b * u) + q
    # R capped at e^LN_R_MAX: beyond that the inertial term relaxes in far less than any step (L-stability then
    # slaves it), and the capped value keeps the linear algebra in range when xi' plunges towards 0 in a rebound
    R = math.exp(min(2.0 * u - q - math.log(G), LN_R_MAX))
    E = math.exp(q) if q < EXP_MAX else math.nan
    f[0], f[1] = E, 1.0 - E - P * R
    if jacobian:
        J[0, 0], J[0, 1] = 0.0, E
        J[1, 0], J[1, 1] = R * (2.0 * P - k + g), R * (P - 1.0) - E
        ft[0], ft[1] = 0.0, -R * (g + 2.0 * P)


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


inertial_step = make_rodas3_step(inertial_system)
quasistatic_step = make_rodas3_step(quasistatic_system)


@njit(cache=True, fastmath=FAST, error_model="numpy")
def _inertia_negligible(s, xi, q, k, a, b, G, eps):
    """The hand-over test of the module docstring at an accepted state."""
    u = s - xi
    g = a + 2.0 * b * u
    P = k * xi + u * (a + b * u) + q
    ln_r = 2.0 * u - q - math.log(G)
    if abs(P) > eps or ln_r < math.log((k + abs(g) + 1.0) / eps):
        return False
    E = math.exp(q)
    return 2.0 * (1.0 - E) > 1.0 - E - P * math.exp(min(ln_r, EXP_MAX))


@njit(cache=True, fastmath=FAST, error_model="numpy")
def _tail_correction(k, a, b, G, u, E, y):
    """First-order correction at infinity from y at the end of the integration: y times d xi_inf/d xi_e of the
    closed-form tail (1 + E (1 - k T1)/(1 + k T), T1 = tail_integral) plus the source still to come (S decays at
    the rate 2 (g + 1))."""
    g = a + 2.0 * b * u
    t1 = tail_integral(a, b, u, 1.0)
    T = E * t1
    S = G * E * E * math.exp(-2.0 * u) * (k * E + (g + 1.0) * (1.0 - E))
    return y * (1.0 + E * (1.0 - k * t1) / (1.0 + k * T)) + S / (2.0 * (g + 1.0))


@njit(cache=True, fastmath=FAST, error_model="numpy")
def relax(k, a, b, G, inertial, rtol, atol, max_steps):
    """Relaxed slip of one stop point with the inertial model (``inertial``) or the quasi-static one with its
    first-order inertial correction; k = chi/A, a = mu1/A, b = m2/A, G = gamma/A > 0.

    Returns (xi_inf, y_inf, status, steps, s_handover): y_inf the first-order correction (0 for the inertial model),
    s_handover the contact-age time at which inertia was dropped (0 for the quasi-static model).
    """
    y, y_new, err_v = np.zeros(2), np.empty(2), np.empty(2)  # (xi, q) inertial, (xi, y) quasi-static
    K, M, piv, f, ft, ys = scratch(2)
    s = 0.0
    phase_inertial = inertial
    p_inertial, p_quasi = (k, a, b, G), (k, a, b, 0.0 if inertial else G)
    h = H_START * min(1.0, G, 1.0 / k)
    eps = HANDOVER_FRACTION * rtol
    s_handover = 0.0
    steps, err_prev, rejected = 0, 1.0, False
    while steps < max_steps:
        steps += 1
        if phase_inertial:
            done = inertial_step(s, y, h, p_inertial, y_new, err_v, K, M, piv, f, ft, ys)
            err2 = abs(err_v[1]) / rtol
        else:
            done = quasistatic_step(s, y, h, p_quasi, y_new, err_v, K, M, piv, f, ft, ys)
            err2 = abs(err_v[1]) / (rtol * max(abs(y[1]), abs(y_new[1])) + atol * G)
        err = max(abs(err_v[0]) / (rtol * max(abs(y[0]), abs(y_new[0])) + atol), err2)
        if not (done and math.isfinite(err) and math.isfinite(y_new[0]) and math.isfinite(y_new[1])):
            h *= rejected_factor(CONTROLLER, math.nan, ORDER)  # an overflow in a stage: retry smaller
            rejected = True
            if h < H_FLOOR * s:
                return math.nan, math.nan, NONFINITE, steps, s_handover
            continue
        if err > 1.0:
            h *= rejected_factor(CONTROLLER, err, ORDER)
            rejected = True
            if h < H_FLOOR * s:
                return math.nan, math.nan, STEP_UNDERFLOW, steps, s_handover
            continue
        s += h
        y[0], y[1] = y_new[0], y_new[1]
        factor, err_prev = accepted_factor(CONTROLLER, err, err_prev, ORDER, rejected)
        h *= factor
        rejected = False
        xi = y[0]
        if phase_inertial:
            if _inertia_negligible(s, xi, y[1], k, a, b, G, eps):
                phase_inertial, y[1], s_handover = False, 0.0, s
            continue
        u = s - xi
        E = math.exp(-(k * xi + u * (a + b * u)))
        if tail_is_accurate(k, a, b, u, E, rtol * xi + atol):
            return (xi + tail_slip(k, a, b, u, E), _tail_correction(k, a, b, p_quasi[3], u, E, y[1]), OK, steps,
                    s_handover)
    return math.nan, math.nan, MAX_STEPS, steps, s_handover


@njit(parallel=True, cache=True)
def relax_batch(k, a, b, G, inertial, rtol, atol, max_steps, xi_inf, correction, status, steps, s_handover):
    """:func:`relax` over flat arrays of points (in parallel); results written into the output arrays."""
    for i in prange(k.size):
        xi_inf[i], correction[i], status[i], steps[i], s_handover[i] = relax(k[i], a[i], b[i], G[i], inertial,
                                                                             rtol, atol, max_steps)


def relax_points(k: np.ndarray, a: np.ndarray, b: np.ndarray, G: np.ndarray, inertial: bool, rtol: float,
                 atol: float, max_steps: int) -> dict[str, np.ndarray]:
    """:func:`relax_batch` with its output arrays: keys xi_inf, correction, status, steps, s_handover."""
    n = np.size(k)
    out = dict(zip(RELAX_KEYS, (np.full(n, np.nan), np.full(n, np.nan), np.zeros(n, np.int8), np.zeros(n, np.int64),
                                np.zeros(n))))
    relax_batch(*(np.ascontiguousarray(x, dtype=float) for x in (k, a, b, G)), inertial, rtol, atol, max_steps,
                *out.values())
    return out


pin_module(__name__)
