"""The stop protocol's kernels over one chunk: a plan's points through the compiled batch loops, in parallel; the flat
outputs (:class:`RawResult`).

The numba layer (integrate/batch.py, the lanes) knows nothing of xarray: it fills preallocated flat arrays, one point
written once by one thread. Which kernel a point takes (:func:`run_points`):

* the relaxed slip alone, method "auto": the adaptive lanes of LANES_METHOD (dop853, 32 runs in flight a thread,
  integrate/lanes_adaptive.py), each run with a fine twin for its error estimate, tightened down a tolerance ladder
  where the estimate exceeds the tolerance (integrate/tolerance_ladder.py);
* the relaxed slip with a fixed step (method rk4, a step or float32 asked for): the fixed-step lanes (rk4, and the
  Rosenbrock ros4 at stiff points), each point down its own step ladder (integrate/ladder.py);
* values inside the transient: the sampled adaptive lanes (integrate/lanes_sampled.py) where
  :func:`samples_in_lanes` takes them, else one point per thread (integrate/stop_point.py, a Richardson pair);
* a state law without the aging identity: that law's own kernel (:data:`GENERAL_PATHS`).

The costly points cluster in one corner of the grid (small K/M with mu1 < 0), so a chunk's points come in a fixed
pseudo-random order (sweep.run.runner.chunk_points): every thread's share mixes cheap and costly points. Results do
not depend on the order.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numba
import numpy as np

from ...accuracy import SAMPLED_TOL_SCALE, lane_control_tolerance
from ...integrate.batch import StopOutputs, slip_batch, stop_batch
from ...integrate.ladder import climb
from ...integrate.lanes import LaneOutputs, LanePoints, LaneRuns, lane_kernels
from ...integrate.lanes_adaptive import AdaptiveOutputs, AdaptiveRuns, adaptive_lane_kernels
from ...integrate.lanes_sampled import LANES, SampledOutputs, SampledRuns, sampled_lane_kernels
from ...integrate.models.state_laws import STATE_LAWS
from ...integrate.models.stop import MAX_STEPS, NO_FINITE_LIMIT, NONFINITE, OK
from ...integrate.solvers import METHODS
from ...integrate.stop_point import Method, StopPoints, Tolerances
from ...integrate.tolerance_ladder import SampleEstimates, climb_tolerances
from ...physics import perturbation_growth
from ...plan.plan import LANES_METHOD, Plan
from ...plan.plan import samples_in_lanes as plan_samples_in_lanes
from ...scene.scene import Scene
from ...status import Status

__all__ = ["SAMPLED", "RawResult", "lane_runs", "mark_error_above_tol", "n_samples", "run_points"]

FRACTIONS = np.array([0.5, 0.9])
"""Fractions of the relaxed slip whose times are reported as t50 and t90."""
ERROR_ABOVE_TOL = int(Status.ERROR_ABOVE_TOL)
SAMPLED = ("xi_at", "u_at", "xi_at_err", "u_at_err")
"""The RawResult arrays sampled in time (n points x n samples): the large ones, written per chunk by a journaled run."""


@dataclass
class RawResult:
    """Flat per-point outputs of the kernel (numpy only), in reduced units; ``*_err`` are the absolute error
    estimates of the same quantities (u = ln psi: its error is the relative error of psi). ``steps``: of the
    returned run (lanes) or of the fine run of pass 1 (per point); ``work``: steps of all runs of the point
    (lanes: the whole ladder; per point: counted as 1.5 x steps, the coarse run taking about half as many)."""

    xi_inf: np.ndarray
    xi_inf_err: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    xi_at: np.ndarray
    u_at: np.ndarray
    xi_at_err: np.ndarray
    u_at_err: np.ndarray
    tau_at_fraction: np.ndarray
    tau_at_fraction_err: np.ndarray
    work: np.ndarray
    seconds: float = 0.0

    @classmethod
    def empty(cls, n: int, n_t: int, n_fractions: int = FRACTIONS.size) -> RawResult:
        """NaN-filled outputs of n points with n_t sampled times; ``n_fractions`` = 0 where no t50/t90 is computed
        (the relaxed-slip lanes: 32 bytes per point less on a 1e7-point sweep)."""
        nan = lambda *shape: np.full(shape, np.nan)  # noqa: E731
        return cls(nan(n), nan(n), np.zeros(n, np.int8), np.zeros(n, np.int32), nan(n, n_t), nan(n, n_t),
                   nan(n, n_t), nan(n, n_t), nan(n, n_fractions), nan(n, n_fractions), np.zeros(n, np.int64))

    def assign(self, sel: np.ndarray, part: RawResult) -> None:
        for name, value in vars(part).items():
            if isinstance(value, np.ndarray):
                mine = getattr(self, name)
                if not mine.flags.writeable:  # a read-only NaN view (estimates not formed): a copy of its own
                    mine = np.array(mine)
                    setattr(self, name, mine)
                mine[sel] = value


def _obs_tau(scene: Scene, points: np.ndarray) -> np.ndarray:
    """Reduced times tau = V t / D0 of the slip_at observations at the points of the grid ``points`` (flat index
    over Scene.dims, i_K n_V + i_V in 2-D; V and D0 of each point)."""
    t = np.asarray(scene.t_obs if "slip_at" in scene.observables else (), dtype=float)
    V, D0 = (np.reshape(scene.at_points(name, points), (-1, 1)) for name in ("V", "D0"))
    return np.ascontiguousarray(V * t[None, :] / D0)


def n_samples(scene: Scene, plan: Plan) -> int:
    """Sampled times per point: the trajectory's and the slip_at observations'."""
    return plan.tau_samples.size + (len(scene.t_obs) if "slip_at" in scene.observables else 0)


def lane_runs(plan: Plan, method: str, points: np.ndarray, steps: np.ndarray, rtol: float, atol: float,
              correction: bool = False, dtype: np.dtype | None = None, max_steps: int | None = None) -> LaneOutputs:
    """One fixed-step run per entry of ``points`` (plan points) at ``steps`` in the lane kernels of ``method``, with
    the first-order inertial correction if asked for (else its array is empty); at most ``max_steps`` steps per run
    (default: the plan's)."""
    relax_batch = lane_kernels(plan.dtype if dtype is None else dtype, method, correction)[1]
    n = points.size
    out = LaneOutputs(np.full(n, np.nan), np.full(n, np.nan), np.full(n if correction else 0, np.nan),
                      np.zeros(n, np.int8), np.zeros(n, np.int32))
    relax_batch(LanePoints(plan.k, plan.a, plan.b, plan.s_c, plan.G),
                LaneRuns(points, np.ascontiguousarray(steps, dtype=float), rtol, atol,
                         plan.max_steps if max_steps is None else max_steps),
                4 * numba.get_num_threads(), out)
    return out


def _lane_runner(scene: Scene, plan: Plan, method: str, correction: np.ndarray | None = None):
    """run(points, steps) -> (xi_inf, tail bound, status, steps taken): one fixed-step run per entry, in lanes.
    With ``correction`` (an array over the points of the first call) the first call's runs also carry the first-order
    inertial correction into it: the ladder's coarsest run, so that model="auto" needs no run of its own."""
    carry = correction is not None

    def run(points, steps):
        nonlocal carry
        out = lane_runs(plan, method, points, steps, scene.rtol, scene.atol["xi_inf"], correction=carry)
        if carry:
            correction[:] = out.correction
            carry = False
        return out.xi_inf, out.tail_err, out.status, out.steps

    return run


GROUPS_PER_THREAD = 1
"""Groups of runs per thread in the adaptive lanes (batch.lanes_in_threads takes them as threads come free): each
group ends with lanes idle while its last runs finish, and a chunk's points are shuffled (:func:`chunk_points`), so
equal shares balance. Default scene, ``execute``, best of 9: 2 threads over 1 gave 1.73x with 1 group a thread,
1.65x with 2, 1.57x with 4 (the prange loop's), 1.34x with 8."""


def _adaptive_runner(plan: Plan, method: str, atol: float, correction: np.ndarray | None = None):
    """run(points, tolerances, first steps) -> (xi_inf, fine xi_inf, tail bounds, status, attempts) in the adaptive
    lanes of ``method``; the first call's runs carry the first-order inertial correction into ``correction`` if
    given. The later calls (the few points run again at a tighter tolerance) use the same kernel, so that a run of
    model "auto" compiles one adaptive kernel, not two (~14 s each from an empty cache)."""
    with_correction = correction is not None
    carry = with_correction

    def run(points, tols, h0):
        nonlocal carry
        relax_batch = adaptive_lane_kernels(method, with_correction)[1]
        out = AdaptiveOutputs.empty(points.size, with_correction)
        relax_batch(LanePoints(plan.k, plan.a, plan.b, plan.s_c, plan.G),
                    AdaptiveRuns(points, np.ascontiguousarray(tols, dtype=float), np.ascontiguousarray(h0, dtype=float),
                                 atol, plan.max_steps), GROUPS_PER_THREAD * numba.get_num_threads(), out)
        if carry:
            correction[:] = out.correction
            carry = False
        return out.xi_inf, out.fine, out.tail_err, out.status, out.steps

    return run


def _relax_in_lanes(scene: Scene, plan: Plan, g: np.ndarray, correction: np.ndarray | None = None) -> RawResult:
    """Relaxed slip of the points g through the lane kernels (one per method of the plan), each point down its own
    step ladder (sweep/integrate/ladder.py: a pilot pair, then rungs until a checked estimate meets the tolerance).
    ``correction`` (over g, NaN-filled): the first-order inertial correction of the rk4 points is written there from
    the ladder's first run (:func:`_lane_runner`)."""
    out = RawResult.empty(g.size, 0, 0)
    finite = plan.finite[g]
    out.status[~finite] = NO_FINITE_LIMIT
    for m, method in enumerate(plan.point_methods):
        live = np.flatnonzero(finite & (plan.point_method[g] == m))
        if live.size == 0:
            continue
        if live.size == g.size:  # every point (the usual chunk): slices instead of gathers and scatters
            live = slice(None)
        pts = g[live]
        carried = (np.full(pts.size, np.nan) if correction is not None and not METHODS[method].implicit
                   else None)
        growth = perturbation_growth(plan.k[pts], plan.a[pts], 1.0)
        if plan.adaptive:
            res = climb_tolerances(_adaptive_runner(plan, method, scene.atol["xi_inf"], carried), pts,
                                   plan.step[pts], plan.ctrl_tol, scene.rtol, scene.atol["xi_inf"], plan.roundoff,
                                   growth)
        else:
            res = climb(_lane_runner(scene, plan, method, carried), pts, plan.step[pts], METHODS[method].order,
                        scene.rtol, scene.atol["xi_inf"], plan.roundoff, fixed=plan.step_source == "override",
                        growth=growth)
        out.xi_inf[live], out.xi_inf_err[live], out.status[live], out.steps[live], out.work[live] = (
            res.xi, res.error, res.status, res.steps, res.work)
        if carried is not None:
            correction[live] = carried
    return out


def _relax_slip_law(scene: Scene, plan: Plan, g: np.ndarray) -> RawResult:
    """Relaxed slip of the points g with the slip law, in its phase plane (sweep/integrate/stop_slip.py)."""
    out = RawResult.empty(g.size, 0, 0)
    slip_batch(plan.k[g], plan.a[g], plan.b[g], scene.rtol, scene.atol["xi_inf"], plan.max_steps, out.xi_inf,
               out.xi_inf_err, out.status, out.steps)
    out.work[:] = out.steps
    return out


GENERAL_PATHS = {"slip-law stop": _relax_slip_law}
"""The stop kernels of the state laws without the aging identity, by their kernel family (StateLaw.stop_family)."""


def lane_groups(n: int) -> int:
    """Groups of runs for the sampled lanes (each group stepped by one thread, 16 runs in flight): up to 4 per thread
    for the load balance, but at least 4 x 16 runs a group, so that a lane rarely waits idle for its group's last
    runs (a forward solve of 100 runs at 1 thread: 4 groups of 25 left each group's second wave 9/16 full)."""
    threads = numba.get_num_threads()
    return max(1, min(4 * threads, max(threads, n // (4 * LANES))))


def _sampled_runner(plan: Plan, method: str, targets: np.ndarray, atol: float, rtol: float, with_psi: bool,
                    twin: bool = True):
    """run(points, rows, tolerances, first steps) -> (xi_inf, fine xi_inf, tail bounds, status, attempts, samples)
    in the sampled adaptive lanes of ``method`` (sweep/integrate/lanes_sampled.py): run r solves the plan point
    ``points[r]`` with the sorted sample times ``targets[rows[r]]``; the samples are a SampledOutputs (the twin's
    NaN where ``twin`` is false)."""

    def run(points, rows, tols, h0):
        sample_batch = sampled_lane_kernels(method)[1]
        out = SampledOutputs.empty(points.size, targets.shape[1])
        sample_batch(LanePoints(plan.k, plan.a, plan.b, plan.s_c, plan.G),
                     SampledRuns(points, rows, np.ascontiguousarray(tols, dtype=float),
                                 np.ascontiguousarray(h0, dtype=float), targets, atol, rtol, plan.max_steps,
                                 with_psi, twin),
                     lane_groups(points.size), out)
        return out.xi_inf, out.fine, out.tail_err, out.status, out.steps, out

    return run


def samples_in_lanes(scene: Scene, plan: Plan | None = None) -> bool:
    """Whether the time-resolved points of ``scene`` go through the sampled adaptive lanes
    (sweep.plan.plan.samples_in_lanes,
    which the plan records and hashes; ``plan`` is accepted for the callers that hold one)."""
    return plan.sampled_lanes if plan is not None else plan_samples_in_lanes(scene)


def _samples_of_lanes(scene: Scene, plan: Plan, g: np.ndarray, targets: np.ndarray, estimates: bool = True
                      ) -> RawResult:
    """Relaxed slip and samples at the sorted reduced times ``targets`` (one row per point of g, all finite) in the
    sampled adaptive lanes (dop853 with its fine twin), each point down the tolerance ladder (tolerance_ladder.py);
    without ``estimates`` one run each, no twin, errors NaN."""
    n_t = targets.shape[1]
    atol = scene.atol["xi_inf"]
    with_psi = plan.tau_samples.size > 0  # the trajectory's psi; slip_at alone needs xi only
    samples = SampleEstimates.empty(g.size, n_t, scene.rtol, scene.atol["trajectory"], plan.roundoff, with_psi)
    run = _sampled_runner(plan, LANES_METHOD, targets, atol, scene.rtol, with_psi, estimates)
    rows = np.arange(g.size)
    ctrl = lane_control_tolerance(scene.rtol, SAMPLED_TOL_SCALE)
    h0 = np.full(g.size, min(0.5, ctrl ** (1.0 / (METHODS[LANES_METHOD].error_order + 1))))
    res = climb_tolerances(lambda entries, tols, h: run(g[entries], entries, tols, h), rows, h0, ctrl, scene.rtol,
                           atol, plan.roundoff, perturbation_growth(plan.k[g], plan.a[g], 1.0), samples, estimates)
    return RawResult(res.xi, res.error, res.status, res.steps, samples.xi, samples.u, samples.xi_err, samples.u_err,
                     np.full((g.size, FRACTIONS.size), np.nan), np.full((g.size, FRACTIONS.size), np.nan), res.work)


def _per_point(scene: Scene, plan: Plan, g: np.ndarray, obs_tau: np.ndarray) -> RawResult:
    """The points g one per thread (sweep/integrate/stop_point.py: a Richardson pair each), ``obs_tau`` their rows of
    slip_at times."""
    part = RawResult.empty(g.size, plan.tau_samples.size + obs_tau.shape[1])
    fractions = FRACTIONS if {"t50", "t90"} & set(scene.observables) else np.empty(0)
    stop_batch(Method.of(plan.tableau), StopPoints(plan.k[g], plan.a[g], plan.b[g], plan.s_c[g], plan.step[g]),
               plan.finite[g], Tolerances(scene.rtol, scene.atol["xi_inf"], plan.ctrl_tol), plan.max_steps,
               plan.tau_samples, obs_tau, fractions, StopOutputs(*(getattr(part, f) for f in StopOutputs._fields)))
    part.work[:] = 3 * part.steps.astype(np.int64) // 2
    return part


LANE_FAILURES = (MAX_STEPS, NONFINITE, int(Status.STEP_UNDERFLOW))
"""Statuses of the sampled lanes whose points are solved again on the per-point path."""


def _time_resolved(scene: Scene, plan: Plan, g: np.ndarray, obs_tau: np.ndarray, estimates: bool = True
                   ) -> RawResult:
    """Time-resolved points g: the finite ones in the sampled lanes where :func:`samples_in_lanes` (``estimates``:
    :func:`_samples_of_lanes`), the rest (no finite relaxed slip, failures of the lanes) and every other scene one
    per thread (with their estimates, always)."""
    if not plan.sampled_lanes:
        return _per_point(scene, plan, g, obs_tau)
    targets = (np.concatenate((np.broadcast_to(plan.tau_samples, (g.size, plan.tau_samples.size)), obs_tau), axis=1)
               if plan.tau_samples.size else obs_tau)
    live = np.flatnonzero(plan.finite[g])
    out = None if live.size == g.size else RawResult.empty(g.size, targets.shape[1])
    if live.size:
        targets = targets[live]
        ordered = bool(np.all(targets[:, 1:] >= targets[:, :-1]))  # the usual case (the fit's times): no reordering
        order = None if ordered else np.argsort(targets, axis=1, kind="stable")
        part = _samples_of_lanes(scene, plan, g[live], np.ascontiguousarray(
            targets if ordered else np.take_along_axis(targets, order, 1)), estimates)
        if not ordered:
            for name in SAMPLED:  # back from each row's sorted order (a read-only NaN view has none)
                if getattr(part, name).flags.writeable:
                    np.put_along_axis(getattr(part, name), order, getattr(part, name).copy(), 1)
        if out is None:  # every point in the lanes
            out = part
        else:
            out.assign(live, part)
    failed = functools.reduce(np.logical_or, (out.status == code for code in LANE_FAILURES))  # np.isin: 150 us
    rest = np.flatnonzero(~plan.finite[g] | failed)
    if rest.size:
        out.assign(rest, _per_point(scene, plan, g[rest], obs_tau[rest]))
    return out


def run_points(scene: Scene, plan: Plan, g: np.ndarray, obs_tau: np.ndarray | None = None,
               correction: np.ndarray | None = None, estimates: bool = True) -> RawResult:
    """Run the plan's points ``g`` (one chunk: one call of a compiled batch) and return their flat outputs, in the
    order of ``g``. A point's numbers do not depend on the other points of the chunk.

    ``obs_tau`` (shape (g.size, n_t), reduced times tau = V t/D0 [1]): each point's own sample times of slip_at,
    instead of the scene's t_obs (shared along V); for plans whose points do not lie on a grid (sweep.fit). Only the
    time-resolved paths sample in time (:func:`_time_resolved`): a relaxed-slip plan (lanes, other state laws) has no
    sampled times. ``correction`` (over g, NaN-filled): where the relaxed-slip lanes run, the first-order inertial
    correction of their rk4 points is written there. ``estimates=False``: the points that the sampled lanes solve
    are run once each, at the ladder's first control tolerance, without their fine twin (~0.6x the cost), and carry
    no error estimate (NaN): for callers that check the accuracy otherwise (sweep.fit's iterations)."""
    if not plan.aging_identity:  # the law's own stop kernel (StateLaw.stop_family)
        return GENERAL_PATHS[STATE_LAWS[plan.state_law].stop_family](scene, plan, g)
    if plan.lanes:
        return _relax_in_lanes(scene, plan, g, correction)
    obs_tau = _obs_tau(scene, plan.flat_index(g)) if obs_tau is None else np.ascontiguousarray(obs_tau, float)
    return _time_resolved(scene, plan, g, obs_tau, estimates)


def mark_error_above_tol(scene: Scene, out: RawResult) -> None:
    """Status error_above_tol where an ok point's error estimate exceeds rtol |value| + atol (any observable)."""
    ok = out.status == OK
    bad = out.xi_inf_err > scene.rtol * np.abs(out.xi_inf) + scene.atol["xi_inf"]
    for val, err, name in ((out.xi_at, out.xi_at_err, "trajectory"), (out.tau_at_fraction, out.tau_at_fraction_err,
                                                                      "t50")):
        if val.shape[1]:
            with np.errstate(invalid="ignore"):
                over = err > scene.rtol * np.abs(val) + scene.atol[name]
            bad |= np.any(over, axis=1)
    n_psi = min(scene.tau_samples.size, out.u_at.shape[1])  # psi is output at the trajectory times only (first)
    if n_psi:  # psi = exp(u): the error of u is the relative error of psi
        with np.errstate(invalid="ignore"):
            bad |= np.any(out.u_at_err[:, :n_psi] > scene.rtol, axis=1)
    out.status[ok & bad] = ERROR_ABOVE_TOL
