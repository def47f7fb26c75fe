"""Load-history driver with inertia (docs/physics.md 7b; aging law): one point through its segments in the state
(s, u, w) of :func:`sweep.integrate.models.history.inertial_history_system`, with the same per-segment records as
the quasi-static driver (sweep/integrate/history.py) and s at requested times.

The equations are stiff wherever the slip velocity is small (rate e^-w/G: every hold), so the stepper is RODAS3
(L-stable Rosenbrock, order 3 with an embedded order 2, analytic Jacobian) with an I controller (exponent 1/3) on the
mixed norm max_i |err_i| / (tol (1 + max(|y_i|, |y_new_i|))); every segment ends exactly at its end. The run starts
in steady sliding at the first segment's velocity (w = ln r_0, the inertial term P = 0) with s raised by
``s_kick``. A peak of s (s' = k (r - e^w) turning from > 0 to <= 0 inside a step) is located by the Illinois method
on partial steps from the step's start, as accurate as the accepted step. s at a sample time inside a step is the
cubic Hermite interpolant of the step's ends and their rates s' (error O(h^4) per step, as the step's own).

A point never raises: its status is ok, max_steps or step_underflow (records NaN from the failing segment on).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..jitcache import pin_module
from .history import H_FLOOR, MAX_FACTOR, MAX_STEPS, MIN_FACTOR, OK, SAFETY, STEADY_TOL, STEP_UNDERFLOW
from .models.history import inertial_history_system, steady_state
from .solvers.rosenbrock_step import make_rodas3_step, scratch

__all__ = ["history_inertial_batch", "history_inertial_point"]

_step = make_rodas3_step(inertial_history_system)
EXPONENT = 1.0 / 3.0
"""Controller exponent: 1/(embedded order + 1) of RODAS3."""


@njit(error_model="numpy")
def _peak_in_step(y, h, p, yt, err, work):
    """The largest s inside a step of size h from y (s' > 0 there, <= 0 at the step's end): s at the root of
    s'(theta) = k (r - e^w(theta)), located by the Illinois method on partial RODAS3 steps from y."""
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
    work = scratch(3)
    y, y_new, err, yt, et = np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3)
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
        p = (k, a, b, g, r)
        final = j == n - 1
        s_start[j] = y[0]
        peak = y[0]
        while i < m and times[i] * scale <= t0:
            s_out[i] = y[0]
            i += 1
        h = min(h0, T)
        t = 0.0
        while t < T:
            if steps >= max_steps:
                return MAX_STEPS, steps
            last = h >= T - t
            if last:
                h = T - t
            ok = _step(0.0, y, h, p, y_new, err, work)
            steps += 1
            e = 0.0
            for c in range(3):
                e = max(e, abs(err[c]) / (tol * (1.0 + max(abs(y[c]), abs(y_new[c])))))
            if not ok or not math.isfinite(e) or e > 1.0:
                h *= MIN_FACTOR if not (ok and math.isfinite(e)) else max(MIN_FACTOR, SAFETY * e ** -EXPONENT)
                if h < H_FLOOR * (1.0 + t):
                    return STEP_UNDERFLOW, steps
                continue
            ds0, ds1 = k * (r - math.exp(y[2])), k * (r - math.exp(y_new[2]))
            if ds0 > 0.0 and ds1 <= 0.0:
                peak = max(peak, _peak_in_step(y, h, p, yt, et, work))
            t_next = T if last else t + h
            while i < m and (times[i] * scale - t0 <= t_next or (last and final)):
                x = min(1.0, max(0.0, (times[i] * scale - t0 - t) / h))
                # cubic Hermite of s on the step
                h00, h10, h01, h11 = (1 + 2 * x) * (1 - x) ** 2, x * (1 - x) ** 2, x * x * (3 - 2 * x), x * x * (x - 1)
                s_out[i] = h00 * y[0] + h10 * h * ds0 + h01 * y_new[0] + h11 * h * ds1
                i += 1
            t = t_next
            y[0], y[1], y[2] = y_new[0], y_new[1], y_new[2]
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
