"""Which model each point uses: quasi-static or inertial (Scene.model, Scene.model_tol; docs/physics.md 3a-3b).

The model error (of neglecting inertia) is kept apart from the numerical error (rtol). With model="auto":

* stop scene, per point: the quasi-static model's relative error on xi_inf is estimated by its first-order
  inertial correction, integrated along the point's own quasi-static solution
  (sweep/integrate/models/stop_inertial.py; in
  the RK4 lanes beside the quasi-static state, the per-point RODAS3 module only where a lane run fails): a
  measurement per point, not a coefficient (the gap per unit gamma/A ranges from ~1e-3 where mu1 < 0 to several
  where mu1/A is large). Where the expansion is trusted (tau = gamma/A (1 + (chi + |mu1|)/A) <= FIRST_ORDER_TRUST)
  the true gap is within a factor of the estimate that grows with tau (sweep/accuracy.py); a
  point keeps the quasi-static result where that factor (:func:`routing_margin`) x estimate <= model_tol.
  Every other point (estimate above the tolerance, not trusted, or failed) is solved with inertia, and its
  ``model_error`` is then the gap measured between the two models. With time-resolved observables (which the
  inertial stop does not compute) such a point keeps its quasi-static values, with status model_error_above_tol
  where the measured gap exceeds model_tol.
* Hopf line and driven scene, per V: inertia shifts the line chi_c = mu1 (1 + gamma/A) by exactly gamma/A
  relative (linear theory), so the inertial model is used where gamma/A > model_tol; a driven point whose
  quasi-static run breaks down (regime runaway) is run again with inertia.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from ...accuracy import (
    CLOSE_TRUST,
    ESTIMATE_MARGIN,
    ESTIMATE_RTOL,
    ESTIMATE_STEP,
    FIRST_ORDER_TRUST,
    TIGHTER,
    WIDE_MARGIN,
)
from ...integrate.batch import relax_points
from ...integrate.lanes import LaneOutputs, LanePoints, LaneRuns, lane_kernels
from ...integrate.stop_inertial import RELAX_KEYS
from ...jitcache import pin_module
from ...plan.plan import Plan
from ...run.progress import Progress
from ...run.runner import ORDER_SEED
from ...scene.scene import Scene
from ...status import (
    MODEL_FLAG,  # noqa: F401 (re-exported: the model variable's flags)
    Status,
)
from .engine import RawResult, lane_runs

OK = int(Status.OK)

__all__ = ["ModelChoice", "MODEL_FLAG", "choose_stop_models", "routing_margin", "solve_inertial", "warm_up_models"]

ESTIMATE_MAX_STEPS = 20_000
"""Steps of the lane run that carries the correction (:func:`_estimate`) beyond which a point goes to the per-point
Rosenbrock module instead: explicit steps are limited by stability where the quasi-static stop is stiff (the default
scene's 209 ros4 points: 509 steps on average, 3.3x faster than RODAS3 at ESTIMATE_RTOL, and within 0.25 % of a
tight integration against its 1.9 %), the Rosenbrock steps are not."""
RELAX_BATCH = 256
"""Points per call of the per-point module (:func:`_relax`): an inertial point takes ~1 ms, so a batch ends every
~0.1 s on two threads and the progress bar moves (a grid of up to plan.ONE_CHUNK_POINTS is one chunk, whose
inertial points could otherwise take half a minute in one silent call)."""
EXTRA_RUNGS = 3
"""Rungs of the inertial ladder beyond the first pair (:func:`solve_inertial`): local tolerances down to
rtol/TIGHTER^5."""
LOCAL_RTOL_FLOOR = 1e-13
"""Tightest local tolerance of the inertial ladder (a few hundred ulps: the RODAS3 steps' rounding)."""
QUASISTATIC, INERTIAL = 0, 1


@dataclass
class ModelChoice:
    """Per flat point: ``inertial`` (bool: model used), ``model_error`` (estimated relative error of xi_inf with
    the quasi-static model; None when the scene forced a model and nothing was estimated)."""

    inertial: np.ndarray
    model_error: np.ndarray | None


def _relax(scene: Scene, plan: Plan, pts: np.ndarray, inertial: bool, rtols: tuple[float, ...],
           progress: bool | None, label: str) -> list[dict[str, np.ndarray]]:
    """:func:`relax_points` of the plan's points ``pts`` at each local tolerance of ``rtols`` (atol scaled alike),
    the points in a fixed shuffled order (the costly ones cluster on the grid and prange gives each thread a
    contiguous share; results do not depend on the order). ``pts`` is at most a chunk (the runner's chunk loop)."""
    order = np.random.default_rng(ORDER_SEED).permutation(pts.size)
    p = pts[order]
    outs = []
    with Progress(pts.size * len(rtols), enabled=progress, label=label) as bar:
        for rtol in rtols:
            parts = []
            # batches of at most RELAX_BATCH points (one, empty, for none): a point's numbers do not depend on its batch
            for q in np.array_split(p, max(1, -(-p.size // RELAX_BATCH))):
                parts.append(relax_points(plan.k[q], plan.a[q], plan.b[q], plan.G[q], inertial, rtol,
                                          scene.atol["xi_inf"] * rtol / scene.rtol, scene.max_steps))
                bar.update(q.size)
            outs.append({key: np.concatenate([part[key] for part in parts]) for key in RELAX_KEYS})
    back = np.argsort(order)
    return [{key: out[key][back] for key in RELAX_KEYS} for out in outs]


def _estimate(scene: Scene, plan: Plan, pts: np.ndarray, carried: np.ndarray, progress: bool | None
              ) -> dict[str, np.ndarray]:
    """Relaxed slip and its first-order inertial correction for the plan's points ``pts``. Where the relaxed-slip
    lanes carried the correction in the ladder's first run (``carried`` finite) it is used as it is; else one RK4
    run per point at ESTIMATE_STEP in the lanes carries it (float64 whatever the scene's type), and the per-point
    Rosenbrock module (:func:`_relax`) takes the points where that run failed or needed more than
    ESTIMATE_MAX_STEPS. ``xi_inf`` is NaN where the caller's own relaxed slip stands (the carried rows)."""
    lanes = ~np.isfinite(carried)
    if not lanes.any():  # the relaxed-slip lanes carried every point's correction (the usual chunk)
        return {"xi_inf": np.full(pts.size, np.nan), "correction": carried, "status": np.full(pts.size, OK, np.int8)}
    out = {"xi_inf": np.full(pts.size, np.nan), "correction": carried.astype(float),
           "status": np.where(lanes, Status.NONFINITE, Status.OK).astype(np.int8)}
    p = pts[lanes]
    with Progress(p.size, enabled=progress, label="model error") as bar:
        run = lane_runs(plan, "rk4", p, np.full(p.size, ESTIMATE_STEP), ESTIMATE_RTOL,
                        scene.atol["xi_inf"] * ESTIMATE_RTOL / scene.rtol, correction=True,
                        dtype=np.dtype(np.float64), max_steps=ESTIMATE_MAX_STEPS)
        bar.update(p.size)
    out["xi_inf"][lanes], out["correction"][lanes], out["status"][lanes] = run.xi_inf, run.correction, run.status
    rest = np.flatnonzero((out["status"] != Status.OK) | ~np.isfinite(out["correction"]))
    if rest.size:
        per_point = _relax(scene, plan, pts[rest], False, (ESTIMATE_RTOL,), progress, "model error")[0]
        for key in out:
            out[key][rest] = per_point[key]
    return out


def solve_inertial(scene: Scene, plan: Plan, raw: RawResult, rows: np.ndarray, idx: np.ndarray,
                   progress: bool | None = False) -> None:
    """Replace the relaxed slip of the rows ``rows`` of ``raw`` (whose rows are the plan's points ``idx``; points
    with a finite limit) by the inertial model's, with the error estimate of :data:`TIGHTER`: runs at local
    tolerances rtol/TIGHTER and rtol/TIGHTER^2, the tighter one kept, their difference its estimate. Where that
    estimate exceeds the scene's tolerance (points whose motion amplifies local errors, below the Hopf line: the
    global error reaches 100-1000x the local tolerance there), the ladder goes on, one run a rung at a tolerance
    TIGHTER times tighter (the last run becoming the coarse one), up to EXTRA_RUNGS rungs and not below
    LOCAL_RTOL_FLOOR."""
    if rows.size == 0:
        return
    local = scene.rtol / TIGHTER**2
    fine, coarse = _relax(scene, plan, idx[rows], True, (local, scene.rtol / TIGHTER), progress, "inertia")
    status = np.where(fine["status"] != Status.OK, fine["status"], coarse["status"])
    xi, err, work = fine["xi_inf"], np.abs(fine["xi_inf"] - coarse["xi_inf"]), fine["steps"] + coarse["steps"]
    steps = fine["steps"].copy()
    for _ in range(EXTRA_RUNGS):
        local /= TIGHTER
        with np.errstate(invalid="ignore"):
            over = np.flatnonzero((status == Status.OK) & (err > scene.rtol * np.abs(xi) + scene.atol["xi_inf"]))
        if over.size == 0 or local < LOCAL_RTOL_FLOOR:
            break
        finer = _relax(scene, plan, idx[rows[over]], True, (local,), progress, "inertia")[0]
        good = finer["status"] == Status.OK  # else the previous rung stands, with its estimate
        at = over[good]
        err[at] = np.abs(finer["xi_inf"][good] - xi[at])
        xi[at], steps[at] = finer["xi_inf"][good], finer["steps"][good]
        work[over] += finer["steps"]
    raw.xi_inf[rows], raw.xi_inf_err[rows], raw.status[rows] = xi, err, status
    raw.steps[rows], raw.work[rows] = steps, work


def choose_stop_models(scene: Scene, plan: Plan, raw: RawResult, idx: np.ndarray | None = None,
                       progress: bool | None = False, correction: np.ndarray | None = None) -> ModelChoice:
    """Decide the model of the points ``idx`` (default: all; the rows of ``raw``) of a stop scene, solve the
    inertial ones, and update ``raw`` in place (module docstring). ``progress`` as in :func:`sweep.run_sweep`;
    ``correction`` (rows of ``raw``): the first-order correction where the kernels already carried it, NaN
    elsewhere."""
    idx = np.arange(plan.n_points) if idx is None else np.asarray(idx)
    n = idx.size
    finite = np.flatnonzero(plan.finite[idx])  # rows
    if scene.model != "auto":
        if scene.model == "inertial":
            solve_inertial(scene, plan, raw, finite, idx, progress)
        return ModelChoice(np.full(n, scene.model == "inertial") & plan.finite[idx], None)
    pts = idx[finite]
    carried = np.full(n, np.nan) if correction is None else correction
    estimate = _estimate(scene, plan, pts, carried[finite], progress)
    model_error = np.full(n, np.nan)
    measure = np.zeros(n, bool)
    _route(RouteEstimates(finite, pts, estimate["xi_inf"], estimate["correction"], estimate["status"]), raw.xi_inf,
           LanePoints(plan.k, plan.a, plan.b, plan.s_c, plan.G), scene.model_tol, Routing(model_error, measure))
    rows = np.flatnonzero(measure)
    if rows.size == 0:  # every point keeps the quasi-static model (the default scene's chunks)
        return ModelChoice(measure, model_error)
    quasistatic = raw.xi_inf[rows].copy()
    if scene.time_resolved:  # keep the quasi-static values; the inertial xi_inf only measures the gap
        probe = RawResult.empty(n, 0, 0)
        solve_inertial(scene, plan, probe, rows, idx, progress)
        inertial_xi = probe.xi_inf[rows]
    else:
        solve_inertial(scene, plan, raw, rows, idx, progress)
        inertial_xi = raw.xi_inf[rows]
    with np.errstate(invalid="ignore", divide="ignore"):
        measured = np.abs(inertial_xi / quasistatic - 1.0)
    model_error[rows] = np.where(np.isfinite(measured), measured, model_error[rows])
    if scene.time_resolved:
        over = rows[~(measured <= scene.model_tol)]
        raw.status[over[raw.status[over] == Status.OK]] = Status.MODEL_ERROR_ABOVE_TOL
        return ModelChoice(np.zeros(n, bool), model_error)
    return ModelChoice(measure, model_error)


def routing_margin(tau: np.ndarray) -> np.ndarray:
    """Factor on the first-order estimate that bounds the true model gap, by tau = gamma/A (1 + (chi + |mu1|)/A):
    ESTIMATE_MARGIN up to CLOSE_TRUST, WIDE_MARGIN up to FIRST_ORDER_TRUST, inf beyond (not trusted: the point is
    solved with inertia)."""
    tau = np.asarray(tau, dtype=float)
    return _margins(tau.ravel()).reshape(tau.shape)


@njit(cache=True)
def _margin(tau: float) -> float:
    """:func:`routing_margin` of one tau."""
    return ESTIMATE_MARGIN if tau <= CLOSE_TRUST else (WIDE_MARGIN if tau <= FIRST_ORDER_TRUST else np.inf)


@njit(cache=True)
def _margins(tau):
    """:func:`_margin` of every element of the flat array ``tau``."""
    out = np.empty(tau.size)
    for i in range(tau.size):
        out[i] = _margin(tau[i])
    return out


class RouteEstimates(NamedTuple):
    """Per estimated point r of :func:`_route` (:func:`_estimate`'s outputs): its chunk row, its plan point, the
    estimate's own relaxed slip [1] (NaN where the chunk's run carried the correction), the first-order inertial
    correction [1] and the status of the run that carried it."""

    row: np.ndarray
    point: np.ndarray
    xi_inf: np.ndarray
    correction: np.ndarray
    status: np.ndarray


class Routing(NamedTuple):
    """Per chunk row, out of :func:`_route`: the quasi-static model's estimated relative error on xi_inf [1], and
    whether the point is solved with inertia (bool)."""

    model_error: np.ndarray
    measure: np.ndarray


@njit(cache=True)
def _route(est, xi_inf, points, model_tol, out):
    """The model of the estimated points ``est`` (:class:`RouteEstimates`) into ``out`` (:class:`Routing`):
    model_error = |correction / xi| where the estimate is ok and xi finite (xi: the estimate's own run where it made
    one, else the chunk's ``xi_inf``, whose run carried the correction), and ``measure`` (solve with inertia) where it
    is not, or where routing_margin(tau) x model_error > model_tol; ``points``: the plan's LanePoints (k, a, G). One
    pass (as numpy expressions over a chunk's points: ~0.1 ms of a default-scene chunk's ~7 ms), the same arithmetic
    (tau = G (1 + k + |a|), as the numpy expression orders it)."""
    for r in range(est.row.size):
        i, p = est.row[r], est.point[r]
        xi = xi_inf[i] if math.isnan(est.xi_inf[r]) else est.xi_inf[r]
        ok = est.status[r] == OK and math.isfinite(xi)
        if ok:
            out.model_error[i] = abs(est.correction[r] / xi)
        margin = _margin(points.G[p] * ((1.0 + points.k[p]) + abs(points.a[p])))
        out.measure[i] = not ok or not (margin * out.model_error[i] <= model_tol)


def warm_up_models() -> None:
    """Compile (or load from numba's cache) the kernels of both models of the stop scene on one point, and the RK4
    lanes that carry the first-order correction (:func:`_estimate`)."""
    one = np.ones(1)
    for inertial in (False, True):
        relax_points(2.0 * one, one, 0.0 * one, 0.1 * one, inertial, 1e-3, 1e-12, 10_000)
    lanes = lane_kernels(np.dtype(np.float64), "rk4", correction=True)[1]
    lanes(LanePoints(2.0 * one, one, 0.0 * one, 0.3 * one, 0.1 * one),
          LaneRuns(np.zeros(1, np.int64), ESTIMATE_STEP * one, ESTIMATE_RTOL, 1e-12, 10_000), 1,
          LaneOutputs(np.empty(1), np.empty(1), np.empty(1), np.zeros(1, np.int8), np.zeros(1, np.int32)))


pin_module(__name__)
