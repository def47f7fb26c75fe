"""Load-history driver with inertia (docs/physics.md 7b; aging law): one point through its segments in the state
(s, u, w, tau) of :func:`sweep.integrate.models.history.inertial_history_mapped` (the inertial equations in the
plunge-resolving time sigma), with the same per-segment records as the quasi-static driver
(sweep/integrate/history.py) and s at requested times.

The equations are stiff wherever the slip velocity is small (rate R = e^-w/G: every hold), so the stepper is RODAS3
(L-stable Rosenbrock, order 3 with an embedded order 2, analytic Jacobian) with an I controller (exponent 1/3) on the
mixed norm max_i |err_i| / (tol (1 + max(|y_i|, |y_new_i|))). Steps are taken in sigma, tau being the fourth state:
sigma = tau up to rounding except in the plunge at the end of an inertial swing (k G large), which stepped in tau
underflowed (measured: 28 of 117 points of a K/M 1e2..1e8 x V 1e-6..1e-2 m/s grid with a step up, a hold and a
reslide; 0 now). Every segment ends at its end: a step that would pass it is aimed at it (tau(sigma) is nearly
linear there) and the last few ulps are an Euler step in tau. The run starts in steady sliding at the first
segment's velocity (w = ln r_0, the inertial term P = 0) with s raised by ``s_kick``. A peak of s (s' = k (r - e^w)
turning from > 0 to <= 0 inside a step) is located by the Illinois method on partial steps from the step's start, as
accurate as the accepted step. s at a sample time inside a step is the cubic Hermite interpolant in tau of the step's
ends and their rates ds/dtau (error O(h^4) per step, as the step's own).

A point never raises: its status is ok, max_steps or step_underflow (a rejected step that moved no state: records
NaN from the failing segment on).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..jitcache import pin_module
from .history import MAX_FACTOR, MAX_STEPS, MIN_FACTOR, OK, SAFETY, STEADY_TOL, STEP_UNDERFLOW
from .models.history import DEAD_BAND, PLUNGE_WEIGHT, inertial_history_mapped, steady_state
from .solvers.rosenbrock_step import make_rodas3_step, scratch

__all__ = ["history_inertial_batch", "history_inertial_point"]

_step = make_rodas3_step(inertial_history_mapped)
EXPONENT = 1.0 / 3.0
"""Controller exponent: 1/(embedded order + 1) of RODAS3."""
STALL = 8.0 * 2.220446049250313e-16
"""A rejected step that moves no state by more than this (relative to max(|y_i|, 1)) flags step_underflow."""
END_TOL = 1e-13
"""A step that ends within END_TOL (1 + T) of its segment's end T (in tau) ends the segment: an Euler step in tau
covers the rest (its error O(END_TOL^2))."""


@njit(error_model="numpy")
def _peak_in_step(y, h, p, yt, err, work):
    """The largest s inside a step of size h (in sigma) from y (s' > 0 there, <= 0 at the step's end): s at the root
    of s'(theta) = k (r - e^w(theta)), located by the Illinois method on partial RODAS3 steps from y."""
    k, r = p[0], p[4]
    lo, hi = 0.0, h
    g_lo = k * (r - math.exp(y[2]))
    _step(0.0, y, h, p, yt, err, work)
    g_hi = k * (r - math.exp(yt[2]))
    best = max(y[0], yt[0])
    side = 0
    for _ in range(80):
        theta = (lo * g_hi - hi * g_lo) / (g_hi - g_lo) if g_hi != g_lo else 0.5 * (lo + hi)
        if not lo < theta < hi:
            theta = 0.5 * (lo + hi)
        if not _step(0.0, y, theta, p, yt, err, work):
            break
        g_t = k * (r - math.exp(yt[2]))
        best = max(best, yt[0])
        if g_t > 0.0:
            lo, g_lo = theta, g_t
            if side == 1:
                g_hi *= 0.5
            side = 1
        else:
            hi, g_hi = theta, g_t
            if side == -1:
                g_lo *= 0.5
            side = -1
        if hi - lo <= 1e-13 * h:
            break
    return best


@njit(inline="always", error_model="numpy")
def _stalled(y, y_new):
    """Whether a rejected step from y to y_new moved no state by more than STALL ulps (relative to max(|y_i|, 1)):
    a step too small to move the state it is to resolve (in sigma the step's size says nothing: autonomous)."""
    for c in range(y.size):
        if not abs(y_new[c] - y[c]) <= STALL * max(abs(y[c]), 1.0):  # moved, or not finite
            return False
    return True


@njit(error_model="numpy")
def history_inertial_point(k, a, b, g, s_kick, ratios, durations, scale, times, tol, max_steps, s_start, s_end,
                           s_peak, steady, s_out):
    """Integrate one point with inertia (G = ``g`` = gamma/A at the reference velocity) through its segments
    (``ratios`` r_j, reduced ``durations`` T_j) at the local tolerance ``tol``; fills the per-segment records as
    the quasi-static driver (sweep.integrate.history_dense) does and s at the sorted physical ``times`` [s]
    (reduced by ``scale`` = V/D0; NaN past the history's end) into ``s_out``; returns (status, steps)."""
    n, m = ratios.size, times.size
    for j in range(n):
        s_start[j], s_end[j], s_peak[j], steady[j] = np.nan, np.nan, np.nan, 0
    for i in range(m):
        s_out[i] = np.nan
    work = scratch(4)
    y, y_new, err, yt, et, f = np.empty(4), np.empty(4), np.empty(4), np.empty(4), np.empty(4), np.empty(4)
    jac = np.empty((4, 4))
    s0, u0 = steady_state(ratios[0], a, b)
    y[0], y[1], y[2] = s0 + s_kick, u0, math.log(ratios[0])
    total = 0.0
    for j in range(n):
        total += durations[j]
    while m > 0 and times[m - 1] * scale > total * (1.0 + 1e-12):
        m -= 1
    steps = 0
    h0 = 1e-3 / (1.0 + k + abs(a)) * min(1.0, g)
    i = 0
    t0 = 0.0  # reduced start of the segment
    for j in range(n):
        r, T = ratios[j], durations[j]
        p = (k, a, b, g, r, PLUNGE_WEIGHT, DEAD_BAND * tol)
        final = j == n - 1
        y[3] = 0.0  # tau into the segment
        s_start[j] = y[0]
        peak = y[0]
        while i < m and times[i] * scale <= t0:
            s_out[i] = y[0]
            i += 1
        h = min(h0, T)  # in sigma (= tau where the time map is 1)
        end_tol = END_TOL * (1.0 + T)
        while y[3] < T:
            if steps >= max_steps:
                return MAX_STEPS, steps
            t = y[3]
            ok = _step(0.0, y, h, p, y_new, err, work)
            steps += 1
            e = 0.0
            for c in range(4):
                e_c = abs(err[c]) / (tol * (1.0 + max(abs(y[c]), abs(y_new[c]))))
                e = e_c if not e_c <= e else e  # a NaN stays (max would drop it)
            if not ok or not math.isfinite(e) or e > 1.0:
                h *= MIN_FACTOR if not (ok and math.isfinite(e)) else max(MIN_FACTOR, SAFETY * e ** -EXPONENT)
                if (ok and _stalled(y, y_new)) or h < 1e-300:
                    return STEP_UNDERFLOW, steps
                continue
            t_new = y_new[3]
            if t_new > T + end_tol:  # past the segment's end: aim at it (tau(sigma) is nearly linear there)
                h *= (T - t) / (t_new - t)
                continue
            last = t_new >= T - end_tol
            if last:  # end exactly at T: one Euler step in tau (W = dtau/dsigma) over the few ulps left, unless in
                # a plunge (W < 1/2: tau hardly moves there, and the rates in tau are not a guide)
                inertial_history_mapped(0.0, y_new, p, f, jac, et, False)
                if f[3] >= 0.5:
                    for c in range(3):
                        y_new[c] += f[c] / f[3] * (T - t_new)
                t_new = T
            y_new[3] = t_new
            ds0, ds1 = k * (r - math.exp(y[2])), k * (r - math.exp(y_new[2]))
            if ds0 > 0.0 and ds1 <= 0.0:
                peak = max(peak, _peak_in_step(y, h, p, yt, et, work))
            dt = t_new - t
            while i < m and (times[i] * scale - t0 <= t_new or (last and final)):
                x = min(1.0, max(0.0, (times[i] * scale - t0 - t) / dt)) if dt > 0.0 else 1.0
                # cubic Hermite of s in tau on the step (rates ds/dtau at its ends)
                h00, h10, h01, h11 = (1 + 2 * x) * (1 - x) ** 2, x * (1 - x) ** 2, x * x * (3 - 2 * x), x * x * (x - 1)
                s_out[i] = h00 * y[0] + h10 * dt * ds0 + h01 * y_new[0] + h11 * dt * ds1
                i += 1
            for c in range(4):
                y[c] = y_new[c]
            peak = max(peak, y[0])
            if not last:
                h *= min(MAX_FACTOR, max(MIN_FACTOR, SAFETY * max(e, 1e-10) ** -EXPONENT))
        s_end[j], s_peak[j] = y[0], peak
        if r > 0.0 and abs(y[2] - math.log(r)) <= STEADY_TOL and abs(y[1] + math.log(r)) <= STEADY_TOL:
            steady[j] = 1
        t0 += T
    return OK, steps


@njit(nogil=True, cache=True, error_model="numpy")
def history_inertial_batch(k, a, b, g, s_kick, ratios, durations, scale, times, tol, max_steps, s_start, s_end,
                           s_peak, steady, s_out, status, steps):
    """:func:`history_inertial_point` for every point i: its k[i], a[i], b[i], g[i], s_kick[i], scale[i], ratios[i]
    and reduced durations[i]; the records and s_out are rows of the 2-D outputs; the sample times are shared."""
    for i in range(k.size):
        status[i], steps[i] = history_inertial_point(k[i], a[i], b[i], g[i], s_kick[i], ratios[i], durations[i],
                                                     scale[i], times, tol, max_steps, s_start[i], s_end[i],
                                                     s_peak[i], steady[i], s_out[i])


pin_module(__name__)
