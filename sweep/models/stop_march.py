"""One stop point with any explicit Runge-Kutta tableau, fixed or adaptive steps, and its error estimate.

The equations and the time map are those of :mod:`sweep.models.stop`; the method is data: the arrays
(c, a, b, e) of a :class:`sweep.solvers.tableau.ButcherTableau` (e = b - b_hat, the embedded error weights)
with its FSAL flag and error order q. One step fills the stage derivatives K[i] = f(y + h sum_j a_ij K[j]).

Step sequences (a *mesh* of step sizes in sigma):

* ``ADAPTIVE``: a PI controller (Gustafsson; exponents 0.7/(q+1) and 0.4/(q+1)) keeps the embedded local error
  estimate below ``ctrl_tol`` (relative, with the atol floor, over xi and s), and records the accepted steps;
* ``REPLAY``: steps mesh[i]/split, each mesh step taken as ``split`` equal substeps (the last size repeated if the
  run needs more steps than the mesh has). A fixed step h is the one-element mesh (h,).

Error estimate (Richardson): each point is solved twice, on a coarse mesh and on the same mesh with every step
halved. The fine solution is returned; since the global error of an order-p method scales as h^p, the difference
is (2^p - 1) times the fine solution's error, and ``ERROR_GAIN`` / (2^p - 1) times the difference, plus the tail's
own error bound, is its estimate: it bounds the true error by a factor ~ERROR_GAIN while the mesh resolves the
solution (tests/test_error_estimates.py checks 1 <= estimate/true error <= 100 on a table of points).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..status import Status
from .stop import (
    FAST,
    MAX_STEPS,
    NO_FINITE_LIMIT,
    NONFINITE,
    OK,
    TAIL_SAFETY,
    continue_in_closed_form,
    derivatives,
    tail_error,
    tail_slip,
)

STEP_UNDERFLOW = int(Status.STEP_UNDERFLOW)
ADAPTIVE, REPLAY = 0, 1
ERROR_GAIN = 15.0
"""Nominal ratio of the error estimate to the true error (the estimate errs on the safe side)."""
TAIL_TIGHTENING = 0.01
"""The per-point path starts the closed-form tail (and continuation) at TAIL_TIGHTENING x rtol: a few steps more,
and the tail's error bound, not sharp where its two neglected terms cancel, then stays small next to the
integration error, so that the estimate of an over-resolved xi_inf (steps set by t50/t90) stays within 100x."""
H_FLOOR = 1e-12
"""Smallest adaptive step in sigma, relative to max(1, sigma): below it the point gets status step_underflow."""


@njit(cache=True, fastmath=FAST, error_model="numpy")
def erk_step(c, A, b, e, K, xi, s, tau, h, k, a, bb, s_c, with_tau):
    """One explicit RK step of size h from (xi, s, tau), with K[0] the derivative there; fills K[1:].

    Returns (xi1, s1, tau1, err_xi, err_s): the new state and the embedded error estimate h sum_j e_j K[j]
    (zero for a method without an embedded pair). For an FSAL method K[-1] is the derivative at the new state.
    """
    stages = b.size
    for i in range(1, stages):
        dx, ds, dt = 0.0, 0.0, 0.0
        for j in range(i):
            dx += A[i, j] * K[j, 0]
            ds += A[i, j] * K[j, 1]
            dt += A[i, j] * K[j, 2]
        K[i, 0], K[i, 1], K[i, 2], _ = derivatives(xi + h * dx, s + h * ds, k, a, bb, s_c, with_tau)
    dx, ds, dt, ex, es = 0.0, 0.0, 0.0, 0.0, 0.0
    for j in range(stages):
        dx += b[j] * K[j, 0]
        ds += b[j] * K[j, 1]
        dt += b[j] * K[j, 2]
        ex += e[j] * K[j, 0]
        es += e[j] * K[j, 1]
    return xi + h * dx, s + h * ds, tau + h * dt, h * ex, h * es


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
def state_where(method, K, component, target, theta, xi, s, tau, d0x, d0s, d0t, h, split, k, a, bb, s_c):
    """State (xi, s, tau) and slip rate dxi/dtau inside a step where ``component`` (0: xi, 2: tau) equals
    ``target``: Newton on theta in [0, 1] with exact partial steps of size theta*h from the step's start (the
    method's own local order), started from the Hermite estimate ``theta``. The partial step is taken as ``split``
    equal substeps, like the run's own steps, so that the Richardson pair also differs on targets that fall inside
    a first step shared by the coarse and the fine run."""
    c, A, b, e, _, _ = method
    x1, s1, t1, dx1, dt1 = xi, s, tau, d0x, d0t
    for _ in range(8):
        x1, s1, t1 = xi, s, tau
        K[0, 0], K[0, 1], K[0, 2] = d0x, d0s, d0t
        for _ in range(split):
            x1, s1, t1, _, _ = erk_step(c, A, b, e, K, x1, s1, t1, theta * h / split, k, a, bb, s_c, True)
            dx1, ds1, dt1, _ = derivatives(x1, s1, k, a, bb, s_c, True)
            K[0, 0], K[0, 1], K[0, 2] = dx1, ds1, dt1
        value = x1 if component == 0 else t1
        slope = h * (dx1 if component == 0 else dt1)
        miss = value - target
        if abs(miss) <= 4e-16 * abs(target) or not slope > 0.0:
            break
        theta = min(1.0, max(0.0, theta - miss / slope))
    return x1, s1, t1, dx1 / dt1


@njit(cache=True, fastmath=FAST, error_model="numpy")
def march(method, mode, h0, mesh, n_mesh, split, k, a, bb, s_c, max_steps, want_limit, rtol, atol, ctrl_tol,
          tau_targets, xi_at, u_at, xi_targets, tau_at, rate_at):
    """Integrate one stop point along a mesh (module docstring).

    Records xi and u = ln psi where tau crosses each increasing ``tau_targets`` (into xi_at, u_at) and tau and
    the slip rate dxi/dtau where xi crosses each increasing ``xi_targets`` (into tau_at, rate_at); tau targets
    beyond the transient (E < TAIL_SAFETY rtol, relaxed slip known) come from the closed form. Stops when the
    tail test passes (if ``want_limit``) and all targets are recorded.

    Returns (status, xi_inf, steps, tail error bound, mesh, n_mesh, first continued target, its bound): xi_inf is
    NaN unless the tail was reached; in ADAPTIVE mode the returned mesh holds the n_mesh accepted steps; targets
    from the first continued one on carry the closed form's own error in u = ln psi, bounded by
    int E du ~ E_e A/(mu1 + 2 m2 u_e), the slip rate neglected by :func:`continue_in_closed_form`.
    """
    c, A, b, e, fsal, q = method
    stages = b.size
    K = np.empty((stages, 3))
    with_tau = tau_targets.size > 0 or xi_targets.size > 0
    xi, s, tau = 0.0, 0.0, 0.0
    dxi, ds, dtau, E = derivatives(xi, s, k, a, bb, s_c, with_tau)
    it, ix = 0, 0
    while it < tau_targets.size and tau_targets[it] <= 0.0:
        xi_at[it], u_at[it] = 0.0, 0.0
        it += 1
    xi_inf, tail_err = math.nan, math.nan
    tail_done = not want_limit
    if mode == ADAPTIVE:
        mesh = np.empty(256)
        n_mesh = 0
    h, sigma, err_prev, rejected_nonfinite = h0, 0.0, 1e-4, False
    cont_from, cont_bound = tau_targets.size, 0.0
    n = 0
    while n < max_steps:
        if mode == REPLAY:
            h = mesh[min(n // split, n_mesh - 1)] / split
        K[0, 0], K[0, 1], K[0, 2] = dxi, ds, dtau
        xi1, s1, tau1, ex, es = erk_step(c, A, b, e, K, xi, s, tau, h, k, a, bb, s_c, with_tau)
        if fsal:
            dxi1, ds1, dtau1 = K[stages - 1, 0], K[stages - 1, 1], K[stages - 1, 2]
            E = dxi1 / ds1
        else:
            dxi1, ds1, dtau1, E = derivatives(xi1, s1, k, a, bb, s_c, with_tau)
        finite = math.isfinite(xi1) and math.isfinite(dxi1) and math.isfinite(tau1) and math.isfinite(dtau1)
        if mode == ADAPTIVE:
            sx = atol + ctrl_tol * max(abs(xi), abs(xi1))
            ss = atol + ctrl_tol * max(abs(s), abs(s1))
            err = math.sqrt(0.5 * ((ex / sx) ** 2 + (es / ss) ** 2)) if finite else math.inf
            if not err <= 1.0:  # rejected (also when a stage left the finite range)
                rejected_nonfinite = not finite
                h *= max(0.2, 0.9 * err ** (-1.0 / (q + 1))) if finite else 0.25
                if h < H_FLOOR * max(1.0, sigma):
                    return (NONFINITE if rejected_nonfinite else STEP_UNDERFLOW), math.nan, n, tail_err, mesh, n_mesh, \
                        cont_from, cont_bound
                continue
            if n_mesh == mesh.size:
                mesh = np.concatenate((mesh, np.empty(mesh.size)))
            mesh[n_mesh] = h
            n_mesh += 1
        n += 1
        if not finite:
            return NONFINITE, math.nan, n, tail_err, mesh, n_mesh, cont_from, cont_bound
        while it < tau_targets.size and tau_targets[it] <= tau1:
            th = hermite_crossing(tau, tau1, h * dtau, h * dtau1, tau_targets[it])
            xt, st, _, _ = state_where(method, K, 2, tau_targets[it], th, xi, s, tau, dxi, ds, dtau, h, split, k, a,
                                       bb, s_c)
            xi_at[it], u_at[it] = xt, st - xt
            it += 1
        while ix < xi_targets.size and xi_targets[ix] <= xi1:
            th = hermite_crossing(xi, xi1, h * dxi, h * dxi1, xi_targets[ix])
            _, _, tau_at[ix], rate_at[ix] = state_where(method, K, 0, xi_targets[ix], th, xi, s, tau, dxi, ds, dtau,
                                                        h, split, k, a, bb, s_c)
            ix += 1
        xi, s, tau, dxi, ds, dtau = xi1, s1, tau1, dxi1, ds1, dtau1
        sigma += h
        if mode == ADAPTIVE:  # PI step-size controller
            err = max(err, 1e-10)
            h *= min(5.0, max(0.2, 0.9 * err ** (-0.7 / (q + 1)) * err_prev ** (0.4 / (q + 1))))
            err_prev = err
        if not tail_done:
            u = s - xi
            bound = tail_error(k, a, bb, u, E)
            if bound <= TAIL_SAFETY * (rtol * xi + atol):
                xi_inf, tail_err, tail_done = xi + tail_slip(k, a, bb, u, E), bound, True
        if it < tau_targets.size and E < TAIL_SAFETY * rtol and math.isfinite(xi_inf):
            continue_in_closed_form(k, a, bb, xi_inf, s - xi, tau, tau_targets[it:], xi_at[it:], u_at[it:])
            cont_from, cont_bound = it, E / (a + 2.0 * bb * (s - xi))
            it = tau_targets.size
        if tail_done and it == tau_targets.size and ix == xi_targets.size:
            return OK, xi_inf, n, tail_err, mesh, n_mesh, cont_from, cont_bound
    return MAX_STEPS, xi_inf, n, tail_err, mesh, n_mesh, cont_from, cont_bound


@njit(cache=True, fastmath=FAST, error_model="numpy")
def solve_stop_point(method, order, adaptive, h, k, a, bb, s_c, max_steps, finite, rtol, atol, ctrl_tol, tau_targets,
                     xi_at, u_at, xi_at_err, u_at_err, fractions, tau_at_fraction, tau_at_fraction_err):
    """One stop point as a Richardson pair (module docstring): pass 1 gives xi_inf and the time-resolved
    samples with their error estimates; if ``fractions`` is not empty a second pass (same meshes) finds tau
    where xi = fraction * xi_inf (t50, t90).

    t_f is ill-conditioned where the slip creeps: an error d in xi_inf moves it by f d / xi'(t_f), i.e.
    relatively by G = f xi_inf / (t_f xi'(t_f)) times rtol (G ~ 30 for t90 with m1/A = 0.3). Where G > 1 the
    relaxed slip is recomputed with tolerances / G before the crossings are located again.

    ``method`` = (c, a, b, e, fsal, error order q) of the tableau, ``order`` its order p; ``h``: the fine step
    (fixed-step methods) or the first trial step of the coarse run (adaptive).
    Returns (status, xi_inf, xi_inf error estimate, steps of the fine pass 1).
    """
    none = np.empty(0)
    gain = ERROR_GAIN / (2.0**order - 1.0)
    tail_rtol = TAIL_TIGHTENING * rtol
    n_t = tau_targets.size
    xc_at, uc_at = np.full(n_t, math.nan), np.full(n_t, math.nan)
    tau_at_fraction[:] = math.nan
    tau_at_fraction_err[:] = math.nan
    # pass 1, coarse then fine on the coarse mesh halved
    fixed = np.full(1, 2.0 * h)
    st_c, x_c, _, _, mesh, n_mesh, c_from, c_bound = march(
        method, ADAPTIVE if adaptive else REPLAY, h, fixed, 1, 1, k, a, bb, s_c, max_steps, finite, tail_rtol, atol,
        ctrl_tol, tau_targets, xc_at, uc_at, none, none, none)
    if n_mesh == 0:
        return st_c, math.nan, math.nan, 0
    st, x_f, n, tail_err, _, _, f_from, f_bound = march(
        method, REPLAY, h, mesh, n_mesh, 2, k, a, bb, s_c, max_steps, finite, tail_rtol, atol, ctrl_tol, tau_targets,
        xi_at, u_at, none, none, none)
    for j in range(n_t):
        xi_at_err[j] = gain * abs(xi_at[j] - xc_at[j])
        u_at_err[j] = gain * abs(u_at[j] - uc_at[j]) + (c_bound if j >= c_from else 0.0) + (
            f_bound if j >= f_from else 0.0)
    if st == OK and st_c != OK:
        st = st_c
    if not finite:
        return (NO_FINITE_LIMIT if st == OK else st), math.nan, math.nan, n
    xi_err = gain * abs(x_f - x_c) + 2.0 * tail_err
    if fractions.size == 0 or st != OK:
        return st, x_f, xi_err, n
    # pass 2: the crossings, on the same meshes
    rate_c, rate_f, tau_c = np.empty(fractions.size), np.empty(fractions.size), np.empty(fractions.size)
    xi_ref_f, xi_ref_c, cross_err = x_f, x_c, 0.0
    st2 = march(method, REPLAY, h, mesh, n_mesh, 2, k, a, bb, s_c, max_steps, False, tail_rtol, atol, ctrl_tol, none,
                none, none, fractions * x_f, tau_at_fraction, rate_f)[0]
    cond = np.max(fractions * x_f / (tau_at_fraction * rate_f)) if st2 == OK else 0.0
    if cond > 1.0:  # ill-conditioned crossings: a more accurate relaxed slip for both runs' targets
        shrink = cond**-0.25
        st3, x_c3, _, _, mesh3, n_mesh3, _, _ = march(
            method, ADAPTIVE if adaptive else REPLAY, h * shrink, fixed * shrink, 1, 1, k, a, bb, s_c, max_steps, True,
            tail_rtol / cond, atol / cond, ctrl_tol / cond, none, none, none, none, none, none)
        st4, x_f3, _, tail3, _, _, _, _ = march(
            method, REPLAY, h, mesh3, n_mesh3, 2, k, a, bb, s_c, max_steps, True, tail_rtol / cond, atol / cond,
            ctrl_tol / cond, none, none, none, none, none, none)
        if st3 != OK or st4 != OK:
            return max(st3, st4), x_f, xi_err, n
        xi_ref_f, xi_ref_c, cross_err = x_f3, x_f3, gain * abs(x_f3 - x_c3) + 2.0 * tail3
        st2 = march(method, REPLAY, h, mesh, n_mesh, 2, k, a, bb, s_c, max_steps, False, tail_rtol, atol, ctrl_tol,
                    none, none, none, fractions * xi_ref_f, tau_at_fraction, rate_f)[0]
    st2c = march(method, REPLAY, h, mesh, n_mesh, 1, k, a, bb, s_c, max_steps, False, tail_rtol, atol, ctrl_tol, none,
                 none, none, fractions * xi_ref_c, tau_c, rate_c)[0]
    if st2 != OK or st2c != OK:
        return max(st2, st2c), x_f, xi_err, n
    for j in range(fractions.size):
        tau_at_fraction_err[j] = gain * abs(tau_at_fraction[j] - tau_c[j]) + fractions[j] * cross_err / rate_f[j]
    return st, x_f, xi_err, n
