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
path, or TAIL_SHARE of |x_fine - x|); the bounds are doubled as in :mod:`sweep.integrate.ladder`. Where the
rounding of long runs matters the separate rounding bound of :func:`sweep.integrate.ladder.rounding_error` carries
it.

A point whose estimate exceeds its tolerance is run again at tol / TOL_RATIO (at most MAX_RUNS runs, none where
rounding alone exceeds the tolerance).

Samples at given times (:mod:`sweep.integrate.lanes_sampled`) are mesh points of the run and of its twin, so each
gets the same estimate,

    xi:  COARSE_GAIN |xi_fine - xi| (+ 2 x both tails' bounds if continued in closed form) + rounding,
    u:   COARSE_GAIN |u_fine - u| + both continuations' bounds in u + rounding of u = s - xi,           (2)

(:class:`SampleEstimates`), and a point is run again where any of them exceeds its tolerance (rtol |xi| + atol of
the trajectory; rtol for u = ln psi, whose error is the relative error of psi).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from ..accuracy import COARSE_GAIN, LANE_TOL_FLOOR, MAX_RUNS, TOL_RATIO
from ..jitcache import pin_module
from .ladder import LadderResult
from .models.stop import MAX_STEPS, NONFINITE, OK
from .solvers.fastmath import FAST

AdaptiveRunner = Callable[[np.ndarray, np.ndarray, np.ndarray],
                          tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
"""run(points, control tolerances, first steps) -> (xi_inf, fine xi_inf, tail bounds, status, attempts), one run per
entry."""


class LadderRuns(NamedTuple):
    """The runs of one pass of :func:`climb_tolerances`, per run r (inputs of :func:`_judge`)."""

    entry: np.ndarray
    """int64: the point run r solved (a row of the :class:`LadderResult`)."""
    xi: np.ndarray
    """float64: relaxed slip of the run (the coarse one) [1]."""
    fine: np.ndarray
    """float64: relaxed slip of its fine twin [1]."""
    tail_err: np.ndarray
    """float64: the sum of both runs' closed-form tail bounds [1]."""
    status: np.ndarray
    """int8: the run's status."""
    attempts: np.ndarray
    """int32: its attempts (each a step and two half steps)."""
    within: np.ndarray
    """bool: whether its samples' estimates (2) are within their tolerances (all True without samples)."""


def climb_tolerances(run: AdaptiveRunner, points: np.ndarray, h0: np.ndarray, tol0: float, rtol: float, atol: float,
                     roundoff: float, growth: np.ndarray | float = 0.0, samples: SampleEstimates | None = None,
                     estimates: bool = True) -> LadderResult:
    """Run ``points`` at the control tolerance ``tol0`` (first trial steps ``h0``), and again TOL_RATIO times tighter
    where the estimate (1) exceeds the tolerance. ``LadderResult.step`` holds the returned run's control tolerance,
    ``work`` counts 3 steps per attempt (a step and two half steps); ``growth``: see
    :func:`sweep.integrate.ladder.rounding_error`. With ``samples`` the runner returns a sixth item, the runs'
    samples (:class:`sweep.integrate.lanes_sampled.SampledOutputs`), kept there with their estimates (2); a point
    is then run again also where a sample's estimate exceeds its tolerance.

    ``estimates=False``: the runner runs without the fine twin (its outputs NaN); every point is run once, at
    ``tol0``, and returned with no estimate (``error`` NaN, the samples' too): for callers that need the values
    only and check their accuracy otherwise (sweep.fit: the iterations of its optimisations)."""
    n = points.size
    out = LadderResult(np.full(n, np.nan), np.full(n, np.inf), np.zeros(n, np.int8), np.zeros(n, np.int32),
                       np.full(n, float(tol0)), np.zeros(n, np.int8), np.zeros(n, np.int64))
    # a writable copy: numba compiles _judge and _sample_estimates again for a read-only array (a broadcast view)
    growth = np.array(np.broadcast_to(np.asarray(growth, dtype=float), (n,)))
    if not estimates:
        x, _, _, status, attempts, *sampled = run(points, out.step, h0)
        out.xi[:], out.steps[:], out.runs[:], out.work[:] = x, attempts, 1, attempts
        out.status[:] = np.where((status == OK) & ~np.isfinite(x), NONFINITE, status)
        out.error[:] = np.nan
        if samples is not None:
            samples.store(sampled[0])
        return out
    entries = np.arange(n)
    again = np.empty(n, np.int64)
    while entries.size:
        # the first pass takes every point: slices (views) instead of gathers through an index array
        i = slice(None) if entries.size == n else entries
        x, fine, tail, status, attempts, *sampled = run(points[i], out.step[i], h0[i])
        within = (np.ones(entries.size, np.bool_) if samples is None
                  else samples.keep(entries, sampled[0], attempts, growth[i], tail))
        n_again = _judge(LadderRuns(entries, x, fine, tail, status, attempts, within), growth, roundoff, rtol, atol,
                         out, again)
        entries = again[:n_again].copy()
    out.error[out.status != OK] = np.nan
    return out


@njit(cache=True, error_model="numpy")
def _judge(runs, growth, roundoff, rtol, atol, out, again):
    """One pass of :func:`climb_tolerances` over its runs ``runs`` (:class:`LadderRuns`): each run's estimate (1),
    stored with its value, status and attempts into its entry's row of ``out`` (:class:`LadderResult`); the entries
    to run again, at step / TOL_RATIO, into ``again``; returns how many. ``growth``: per point, the growth factor of
    :func:`sweep.integrate.ladder.rounding_error` [1]; ``roundoff``, ``rtol`` [1], ``atol`` [1] as in
    :func:`climb_tolerances`. In one pass: as numpy expressions over a chunk's runs they cost ~0.2 ms of a
    default-scene chunk's ~3 ms. No fastmath: the same arithmetic as :func:`sweep.integrate.ladder.rounding_error`
    and the estimate (1) written in numpy."""
    n_again = 0
    for r in range(runs.entry.size):
        e = runs.entry[r]
        v = runs.xi[r]
        size = abs(v)
        rounding = roundoff * (2 * runs.attempts[r] + math.exp(min(growth[e] * size, 700.0))) * size
        estimate = COARSE_GAIN * abs(runs.fine[r] - v) + 2.0 * runs.tail_err[r] + rounding
        finite = math.isfinite(estimate)
        if not finite:  # a run went non-finite: the next rung
            estimate = math.inf
        tol_x = rtol * size + atol
        out.xi[e], out.error[e], out.steps[e] = v, estimate, runs.attempts[r]
        status = runs.status[r]
        out.status[e] = status if status != OK else (OK if finite else NONFINITE)
        out.runs[e] += 1
        out.work[e] += 3 * np.int64(runs.attempts[r])
        if (status != MAX_STEPS and not (estimate <= tol_x and runs.within[r]) and rounding <= tol_x
                and out.runs[e] < MAX_RUNS and out.step[e] / TOL_RATIO >= LANE_TOL_FLOOR):
            out.step[e] /= TOL_RATIO
            again[n_again] = e
            n_again += 1
    return n_again


@dataclass
class SampleEstimates:
    """The samples of the points of a :func:`climb_tolerances` (n points x n_t times, in the order of each point's
    targets row) with their estimates (2), filled run by run: a point's rerun overwrites its row."""

    xi: np.ndarray
    u: np.ndarray
    xi_err: np.ndarray
    u_err: np.ndarray
    rtol: float
    atol: float
    """Absolute floor of the slip samples' tolerance [1]."""
    roundoff: float
    with_psi: bool
    """Whether psi is wanted at the samples; without it u carries no estimate (NaN) and no tolerance (the runs did
    not control tau: :class:`sweep.integrate.lanes_sampled.SampledRuns`)."""

    @classmethod
    def empty(cls, n: int, n_t: int, rtol: float, atol: float, roundoff: float, with_psi: bool = True
              ) -> SampleEstimates:
        """For n points of n_t samples, uninitialised: the first run of every point fills its row."""
        blank = lambda: np.empty((n, n_t))  # noqa: E731
        return cls(blank(), blank(), blank(), blank(), rtol, atol, roundoff, with_psi)

    def store(self, runs) -> None:
        """The samples of ``runs`` (SampledOutputs of every point, in order) without estimates: the arrays themselves,
        no copy, and read-only NaN views for the estimates (no memory: RawResult.assign copies them before writing)."""
        self.xi, self.u = runs.xi_at, runs.u_at
        self.xi_err = self.u_err = np.broadcast_to(np.nan, runs.xi_at.shape)

    def keep(self, entries: np.ndarray, runs, attempts: np.ndarray, growth: np.ndarray, tail: np.ndarray
             ) -> np.ndarray:
        """Store the samples of ``runs`` (SampledOutputs of the points ``entries``) with their estimates (2);
        returns, per entry, whether every estimate is within its tolerance."""
        within = np.empty(entries.size, np.bool_)
        _sample_estimates(runs, SampledPass(entries, 2 * attempts.astype(np.int64),
                                            np.ascontiguousarray(growth, dtype=float), tail),
                          self.roundoff, self.rtol, self.atol, self.with_psi,
                          SampleArrays(self.xi, self.u, self.xi_err, self.u_err), within)
        return within


class SampledPass(NamedTuple):
    """Per run r of one pass of the sampled lanes, what the estimates (2) need beside its samples."""

    entry: np.ndarray
    """int64: the point run r solved (a row of the :class:`SampleArrays`)."""
    steps: np.ndarray
    """int64: the steps of the run and its twin, 2 x attempts (the rounding bound's count)."""
    growth: np.ndarray
    """float64: the growth factor of the run's point (:func:`sweep.integrate.ladder.rounding_error`) [1]."""
    tail_err: np.ndarray
    """float64: the sum of both runs' closed-form tail bounds [1]."""


class SampleArrays(NamedTuple):
    """The arrays of a :class:`SampleEstimates` (n points x n_t times, out of :func:`_sample_estimates`): xi and u =
    ln psi at the samples, and their estimates (2) [1]."""

    xi: np.ndarray
    u: np.ndarray
    xi_err: np.ndarray
    u_err: np.ndarray


@njit(cache=True, fastmath=FAST, error_model="numpy")
def _sample_estimates(samples, runs, roundoff, rtol, atol, with_psi, out, within):
    """Run r's samples (``samples``: :class:`sweep.integrate.lanes_sampled.SampledOutputs`) and their estimates (2)
    into row runs.entry[r] of ``out`` (:class:`SampleArrays`), and per run whether all are within tolerance into
    ``within``; ``runs``: :class:`SampledPass`; ``roundoff``, ``rtol`` [1], ``atol`` [1], ``with_psi`` as in
    :class:`SampleEstimates`. One pass: as numpy expressions over the (runs x samples) arrays they cost 6 us a
    200-sample point, a quarter of its solve. The rounding of a sample is bounded with its row's largest |xi| in the
    growth factor (:func:`sweep.integrate.ladder.rounding_error`: the exponential is monotonic in |xi|; one exp a
    run)."""
    x, xf, u, uf, cont_err = samples.xi_at, samples.xi_fine, samples.u_at, samples.u_fine, samples.cont_err
    for r in range(x.shape[0]):
        largest = 0.0
        for j in range(x.shape[1]):
            largest = max(largest, abs(x[r, j]))
        amplified = runs.steps[r] + math.exp(min(runs.growth[r] * largest, 700.0))
        ok = True
        e = runs.entry[r]
        for j in range(x.shape[1]):
            continued = 2.0 * runs.tail_err[r] if j >= samples.first_continued[r] else 0.0
            xi_err = COARSE_GAIN * abs(xf[r, j] - x[r, j]) + continued + roundoff * amplified * abs(x[r, j])
            u_err = (COARSE_GAIN * abs(uf[r, j] - u[r, j]) + cont_err[r, j]
                     + roundoff * runs.steps[r] * (abs(u[r, j]) + abs(x[r, j]))) if with_psi else math.nan
            out.xi[e, j], out.u[e, j], out.xi_err[e, j], out.u_err[e, j] = x[r, j], u[r, j], xi_err, u_err
            ok = ok and xi_err <= rtol * abs(x[r, j]) + atol and (u_err <= rtol or not with_psi)
        within[r] = ok


pin_module(__name__)
