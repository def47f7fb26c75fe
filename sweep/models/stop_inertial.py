"""Stop scene with inertia (PHYSICS.md 3a), and the first-order inertial correction of the quasi-static model.

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
:func:`relax` returns y at the end, propagated through the closed-form tail to first order in E. Its use:
``model="auto"`` routes a point to the inertial model where |y|/xi_inf exceeds model_tol (sweep/model_choice.py).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..jitcache import pin, pin_module
from ..solvers.rosenbrock import RODAS3
from ..status import Status
from .stop import EXP_MAX, FAST, tail_integral, tail_is_accurate, tail_slip

__all__ = ["relax", "relax_batch", "HANDOVER_FRACTION"]

OK, MAX_STEPS, NONFINITE = int(Status.OK), int(Status.MAX_STEPS), int(Status.NONFINITE)
STEP_UNDERFLOW = int(Status.STEP_UNDERFLOW)

HANDOVER_FRACTION = 0.1
"""The inertial term is handed over once below this fraction of rtol (module docstring)."""
H_START = 1e-3
"""First step in s, times min(1, G, 1/k): the initial layer lasts s ~ G, the stiff start 1/k."""
LN_R_MAX = 600.0
"""Cap of ln R in the right-hand side (comment there)."""
H_FLOOR = 8.0 * 2.220446049250313e-16
"""Smallest step in s, relative to s, before a point is flagged step_underflow (a few ulps: below it s + h
stops moving). Relative, not absolute: where a fast rebound (k/G large) drops xi' towards 0, ln(xi' psi) has a
log singularity that the steps resolve down to ~1e-16 near s ~ 0.05, and then grow again."""
SAFETY, GROW_MAX, SHRINK_MIN = 0.9, 5.0, 0.2
"""Step controller h_new = h min(GROW_MAX, max(SHRINK_MIN, SAFETY err^(-1/3))) (the embedded order is 2)."""

# RODAS3's transformed coefficients (sweep/solvers/rosenbrock.py), read once into constants for the compiler.
_GAM = RODAS3.gamma
(_, _, _, _), (_A21, _, _, _), (_A31, _A32, _, _), (_A41, _A42, _A43, _) = RODAS3.a
(_, _, _, _), (_C21, _, _, _), (_C31, _C32, _, _), (_C41, _C42, _C43, _) = RODAS3.c
_AL2, _AL3, _AL4 = RODAS3.alpha_x[1:]
_G1, _G2, _G3, _G4 = RODAS3.gamma_x
_M1, _M2, _M3, _M4 = RODAS3.m
_E1, _E2, _E3, _E4 = RODAS3.e
_SAME_F2 = _A21 == 0.0 and _AL2 == 0.0
_ERROR_EXPONENT = -1.0 / (RODAS3.order_hat + 1)


@njit(inline="always", fastmath=FAST, error_model="numpy")
def inertial_rhs(s, xi, q, k, a, b, G):
    """(f_xi, f_q, J11, J12, J21, J22, df_xi/ds, df_q/ds) of the inertial system in s (module docstring)."""
    u = s - xi
    g = a + 2.0 * b * u
    P = k * xi + u * (a + b * u) + q
    # R capped at e^LN_R_MAX: beyond that the inertial term relaxes in far less than any step (L-stability then
    # slaves it), and the capped value keeps the 2x2 solve in range when xi' plunges towards 0 in a rebound
    R = math.exp(min(2.0 * u - q - math.log(G), LN_R_MAX))
    E = math.exp(q) if q < EXP_MAX else math.nan
    return (E, 1.0 - E - P * R,
            0.0, E, R * (2.0 * P - k + g), R * (P - 1.0) - E,
            0.0, -R * (g + 2.0 * P))


@njit(inline="always", fastmath=FAST, error_model="numpy")
def quasistatic_rhs(s, xi, y, k, a, b, G):
    """The same for the quasi-static model in s with the first-order inertial correction y (module docstring):
    dxi/ds = E, dy/ds = J y + S; G = 0 leaves y at 0."""
    u = s - xi
    g = a + 2.0 * b * u
    expo = -(k * xi + u * (a + b * u))
    if expo > EXP_MAX:
        return math.nan, math.nan, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    E = math.exp(expo)
    J = E * (g - k)
    dJ_ds, dJ_dxi = -g * J + 2.0 * b * E, (g - k) * J - 2.0 * b * E
    if G == 0.0:
        return E, 0.0, J, 0.0, 0.0, J, -g * E, 0.0
    w = G * math.exp(2.0 * (expo - u))
    Q = k * E + (g + 1.0) * (1.0 - E)
    S = w * Q
    dQ_ds = -k * g * E + 2.0 * b * (1.0 - E) + g * (g + 1.0) * E
    dQ_dxi = k * (g - k) * E - 2.0 * b * (1.0 - E) - (g + 1.0) * (g - k) * E
    dS_ds = -2.0 * (g + 1.0) * S + w * dQ_ds
    dS_dxi = 2.0 * (g - k + 1.0) * S + w * dQ_dxi
    return E, J * y + S, J, 0.0, y * dJ_dxi + dS_dxi, J, -g * E, y * dJ_ds + dS_ds


def _make_step(rhs):
    """One RODAS3 step of a 2-state system given by ``rhs`` (:func:`inertial_rhs` or :func:`quasistatic_rhs`):
    (y1, y2, e1, e2) = new state and embedded error estimate (HW IV.7.25'; the 2x2 matrix I/(h gamma) - J is
    inverted once per step). The estimate is not filtered by (I - h gamma J)^-1: tried, it let steps grow past
    where the inertial term changes sign and ended sample2 runs in step_underflow."""

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def step(s, y1, y2, h, k, a, b, G):
        f1, f2, j11, j12, j21, j22, t1, t2 = rhs(s, y1, y2, k, a, b, G)
        d = 1.0 / (h * _GAM)
        m11, m12, m21, m22 = d - j11, -j12, -j21, d - j22
        det = m11 * m22 - m12 * m21
        i11, i12, i21, i22 = m22 / det, -m12 / det, -m21 / det, m11 / det
        # stage 1
        r1, r2 = f1 + _G1 * h * t1, f2 + _G1 * h * t2
        u11, u12 = i11 * r1 + i12 * r2, i21 * r1 + i22 * r2
        # stage 2
        if not _SAME_F2:
            f1, f2 = rhs(s + _AL2 * h, y1 + _A21 * u11, y2 + _A21 * u12, k, a, b, G)[:2]
        r1, r2 = f1 + _C21 * u11 / h + _G2 * h * t1, f2 + _C21 * u12 / h + _G2 * h * t2
        u21, u22 = i11 * r1 + i12 * r2, i21 * r1 + i22 * r2
        # stage 3
        f1, f2 = rhs(s + _AL3 * h, y1 + _A31 * u11 + _A32 * u21, y2 + _A31 * u12 + _A32 * u22, k, a, b, G)[:2]
        r1 = f1 + (_C31 * u11 + _C32 * u21) / h + _G3 * h * t1
        r2 = f2 + (_C31 * u12 + _C32 * u22) / h + _G3 * h * t2
        u31, u32 = i11 * r1 + i12 * r2, i21 * r1 + i22 * r2
        # stage 4
        f1, f2 = rhs(s + _AL4 * h, y1 + _A41 * u11 + _A42 * u21 + _A43 * u31,
                     y2 + _A41 * u12 + _A42 * u22 + _A43 * u32, k, a, b, G)[:2]
        r1 = f1 + (_C41 * u11 + _C42 * u21 + _C43 * u31) / h + _G4 * h * t1
        r2 = f2 + (_C41 * u12 + _C42 * u22 + _C43 * u32) / h + _G4 * h * t2
        u41, u42 = i11 * r1 + i12 * r2, i21 * r1 + i22 * r2
        return (y1 + _M1 * u11 + _M2 * u21 + _M3 * u31 + _M4 * u41,
                y2 + _M1 * u12 + _M2 * u22 + _M3 * u32 + _M4 * u42,
                _E1 * u11 + _E2 * u21 + _E3 * u31 + _E4 * u41,
                _E1 * u12 + _E2 * u22 + _E3 * u32 + _E4 * u42)

    return pin(step, rhs.py_func.__name__)


inertial_step = _make_step(inertial_rhs)
quasistatic_step = _make_step(quasistatic_rhs)


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
    s, xi, v = 0.0, 0.0, 0.0  # v: q (inertial phase) or y (quasi-static phase)
    phase_inertial = inertial
    g_sens = 0.0 if inertial else G
    h = H_START * min(1.0, G, 1.0 / k)
    eps = HANDOVER_FRACTION * rtol
    s_handover = 0.0
    steps = 0
    while steps < max_steps:
        steps += 1
        if phase_inertial:
            x1, v1, e1, e2 = inertial_step(s, xi, v, h, k, a, b, G)
            err2 = abs(e2) / rtol
        else:
            x1, v1, e1, e2 = quasistatic_step(s, xi, v, h, k, a, b, g_sens)
            err2 = abs(e2) / (rtol * max(abs(v), abs(v1)) + atol * G)
        err = max(abs(e1) / (rtol * max(abs(xi), abs(x1)) + atol), err2)
        if not (math.isfinite(err) and math.isfinite(x1) and math.isfinite(v1)):
            h *= SHRINK_MIN  # an overflow in a stage: retry smaller, flag once the step underflows
            if h < H_FLOOR * s:
                return math.nan, math.nan, NONFINITE, steps, s_handover
            continue
        factor = min(GROW_MAX, max(SHRINK_MIN, SAFETY * err ** _ERROR_EXPONENT)) if err > 0.0 else GROW_MAX
        if err > 1.0:
            h *= factor
            if h < H_FLOOR * s:
                return math.nan, math.nan, STEP_UNDERFLOW, steps, s_handover
            continue
        s, xi, v = s + h, x1, v1
        h *= factor
        if phase_inertial:
            if _inertia_negligible(s, xi, v, k, a, b, G, eps):
                phase_inertial, v, s_handover = False, 0.0, s
            continue
        u = s - xi
        E = math.exp(-(k * xi + u * (a + b * u)))
        if tail_is_accurate(k, a, b, u, E, rtol * xi + atol):
            return xi + tail_slip(k, a, b, u, E), _tail_correction(k, a, b, g_sens, u, E, v), OK, steps, s_handover
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
    out = {"xi_inf": np.full(n, np.nan), "correction": np.full(n, np.nan), "status": np.zeros(n, np.int8),
           "steps": np.zeros(n, np.int64), "s_handover": np.zeros(n)}
    relax_batch(*(np.ascontiguousarray(x, dtype=float) for x in (k, a, b, G)), inertial, rtol, atol, max_steps,
                *out.values())
    return out


pin_module(__name__)
