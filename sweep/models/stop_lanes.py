"""Relaxed slip only (the common large sweep): several stop points per thread, stepped in turn.

One point's RK4 step is a chain of dependent operations (each stage needs the previous one's exp), so a
single point leaves the core's pipelines half idle. Here each thread keeps LANES points in flight and
advances them in turn, so the independent chains overlap (1.3x on the default scene, measured by
benchmarks/throughput.py); a lane whose point is done takes the next one. The arithmetic per point is the
same functions as :func:`sweep.models.stop.march` (identical step counts; xi_inf equal to rounding, FMA
contraction may differ in the last bits), without trajectory, slip_at or t50/t90 bookkeeping.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .stop import FAST, MAX_STEPS, NO_FINITE_LIMIT, NONFINITE, OK, derivatives, rk4_step, tail_is_accurate, tail_slip

LANES = 2
"""Points in flight per thread (2 already hides most latency; 4 and 8 measured no faster)."""


@njit(cache=True, fastmath=FAST)
def relax_in_lanes(k, a, b, h, s_c, finite, max_steps, rtol, atol, points, xi_inf, status, steps):
    """xi_inf, status and steps for the flat ``points`` (indices into the per-point arrays)."""
    xi, s, dxi, ds = np.zeros(LANES), np.zeros(LANES), np.zeros(LANES), np.zeros(LANES)
    n = np.zeros(LANES, np.int64)
    lane_point = np.full(LANES, -1, np.int64)
    queued, busy = 0, 0
    for lane in range(LANES):
        queued = _take_next(k, a, b, s_c, finite, points, queued, lane, lane_point, xi, s, dxi, ds, n,
                            xi_inf, status, steps)
        busy += lane_point[lane] >= 0
    while busy > 0:
        for lane in range(LANES):
            p = lane_point[lane]
            if p < 0:
                continue
            x1, s1, _ = rk4_step(xi[lane], s[lane], 0.0, dxi[lane], ds[lane], 0.0, h[p], k[p], a[p], b[p], s_c[p],
                                 False)
            dx1, ds1, _, E = derivatives(x1, s1, k[p], a[p], b[p], s_c[p], False)
            n[lane] += 1
            xi[lane], s[lane], dxi[lane], ds[lane] = x1, s1, dx1, ds1
            if not (math.isfinite(x1) and math.isfinite(dx1)):
                xi_inf[p], status[p] = math.nan, NONFINITE
            elif tail_is_accurate(k[p], a[p], b[p], s1 - x1, E, rtol * x1 + atol):
                xi_inf[p], status[p] = x1 + tail_slip(k[p], a[p], b[p], s1 - x1, E), OK
            elif n[lane] >= max_steps:
                xi_inf[p], status[p] = math.nan, MAX_STEPS
            else:
                continue
            steps[p] = n[lane]
            queued = _take_next(k, a, b, s_c, finite, points, queued, lane, lane_point, xi, s, dxi, ds, n,
                                xi_inf, status, steps)
            busy -= lane_point[lane] < 0


@njit(cache=True, fastmath=FAST)
def _take_next(k, a, b, s_c, finite, points, queued, lane, lane_point, xi, s, dxi, ds, n, xi_inf, status, steps):
    """Load the next point with a finite limit into ``lane`` (others are settled on the way); returns the
    new queue position. Leaves the lane empty (-1) when the queue is exhausted."""
    lane_point[lane] = -1
    while queued < points.size:
        p = points[queued]
        queued += 1
        if not finite[p]:
            xi_inf[p], status[p], steps[p] = math.nan, NO_FINITE_LIMIT, 0
            continue
        lane_point[lane], xi[lane], s[lane], n[lane] = p, 0.0, 0.0, 0
        dxi[lane], ds[lane], _, _ = derivatives(0.0, 0.0, k[p], a[p], b[p], s_c[p], False)
        break
    return queued
