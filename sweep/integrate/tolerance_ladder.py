"""Error estimate of the adaptive lanes (:mod:`sweep.integrate.lanes_adaptive`): a ladder in tolerance.

An embedded pair controls the local error of each step; the global error of xi_inf is some multiple of the control
tolerance that depends on the point (how errors made early are damped or amplified later on). Each run therefore
has a fine twin that takes every step of it as two half steps, in the same pass of the lanes
(:mod:`sweep.integrate.lanes_adaptive`), and the run (coarse) is returned with

    estimate = COARSE_GAIN |x_fine - x| + 2 x both closed-form tails' error bounds + rounding              (1)

as on the per-point path (:mod:`sweep.integrate.stop_point`): it bounds the coarse error whenever the fine one is at
most half of it (or of the other sign), with no need for the pair to be asymptotic, and exceeds it by at most 3x then.
On the same mesh halved the fine error is ~2^p times smaller where the steps are accuracy-limited, and far smaller
still where they are stability-limited (the creep manifold of the costly corner), since the half steps lie well
inside the stability region. Two independent adaptive runs at tolerances a decade apart (tried first: 2.4 runs'
cost instead of 3) do not have this property: their step sequences differ, and their errors stagnated between the
two tolerances at ~1,500 of the 20,000 default-scene points (up to 0.012 tol relative in the corner), which the
difference cannot see. The runs go on until the tails' error bounds are negligible (TAIL_RTOL, as on the per-point
path); the bounds are doubled as in :mod:`sweep.integrate.ladder`. Where the rounding of long runs matters the separate
rounding bound of :func:`sweep.integrate.ladder.rounding_error` carries it.

A point whose estimate exceeds its tolerance is run again at tol / TOL_RATIO (at most MAX_RUNS runs, none where
rounding alone exceeds the tolerance).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..accuracy import COARSE_GAIN, LANE_TOL_FLOOR, MAX_RUNS, TOL_RATIO
from ..models.stop import MAX_STEPS, NONFINITE, OK
from .ladder import LadderResult, rounding_error

AdaptiveRunner = Callable[[np.ndarray, np.ndarray, np.ndarray],
                          tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
"""run(points, control tolerances, first steps) -> (xi_inf, fine xi_inf, tail bounds, status, attempts), one run per
entry."""


def climb_tolerances(run: AdaptiveRunner, points: np.ndarray, h0: np.ndarray, tol0: float, rtol: float, atol: float,
                     roundoff: float, growth: np.ndarray | float = 0.0) -> LadderResult:
    """Run ``points`` at the control tolerance ``tol0`` (first trial steps ``h0``), and again TOL_RATIO times tighter
    where the estimate (1) exceeds the tolerance. ``LadderResult.step`` holds the returned run's control tolerance,
    ``work`` counts 3 steps per attempt (a step and two half steps); ``growth``: see
    :func:`sweep.integrate.ladder.rounding_error`."""
    n = points.size
    out = LadderResult(np.full(n, np.nan), np.full(n, np.inf), np.zeros(n, np.int8), np.zeros(n, np.int32),
                       np.full(n, float(tol0)), np.zeros(n, np.int8), np.zeros(n, np.int64))
    growth = np.broadcast_to(np.asarray(growth, dtype=float), (n,))
    todo = np.ones(n, bool)
    while todo.any():
        i = np.flatnonzero(todo)
        x, fine, tail, status, attempts = run(points[i], out.step[i], h0[i])
        rounding = rounding_error(roundoff, 2 * attempts, x, growth[i])  # the fine run's steps round too
        estimate = COARSE_GAIN * np.abs(fine - x) + 2.0 * tail + rounding
        estimate = np.where(np.isfinite(estimate), estimate, np.inf)  # a run went non-finite: the next rung
        tol_x = rtol * np.abs(x) + atol
        out.xi[i], out.error[i], out.steps[i] = x, estimate, attempts
        out.status[i] = np.where(status != OK, status, np.where(np.isfinite(estimate), OK, NONFINITE))
        out.runs[i] += 1
        out.work[i] += 3 * attempts.astype(np.int64)
        more = ((status != MAX_STEPS) & ~(estimate <= tol_x) & (rounding <= tol_x) & (out.runs[i] < MAX_RUNS)
                & (out.step[i] / TOL_RATIO >= LANE_TOL_FLOOR))
        todo[:] = False
        todo[i[more]] = True
        out.step[i[more]] /= TOL_RATIO
    out.error[out.status != OK] = np.nan
    return out
