"""Which model each point uses: quasi-static or inertial (Scene.model, Scene.model_tol; PHYSICS.md 3a-3b).

The model error (of neglecting inertia) is kept apart from the numerical error (rtol). With model="auto":

* stop scene, per point: the quasi-static model's relative error on xi_inf is estimated by its first-order
  inertial correction, integrated along the point's own quasi-static solution (sweep/models/stop_inertial.py, at
  ESTIMATE_RTOL): a measurement per point, not a coefficient (the gap per unit gamma/A ranges from ~1e-3 where
  mu1 < 0 to several where mu1/A is large). Where the expansion is trusted (FIRST_ORDER_TRUST) it is within
  0.95..1.11 of the true gap; a point keeps the quasi-static result where ESTIMATE_MARGIN x estimate <= model_tol.
  Every other point (estimate above the tolerance, not trusted, or failed) is solved with inertia, and its
  ``model_error`` is then the gap measured between the two models. With time-resolved observables (which the
  inertial stop does not compute) such a point keeps its quasi-static values, with status model_error_above_tol
  where the measured gap exceeds model_tol.
* Hopf line and driven scene, per V: inertia shifts the line chi_c = mu1 (1 + gamma/A) by exactly gamma/A
  relative (linear theory), so the inertial model is used where gamma/A > model_tol; a driven point whose
  quasi-static run breaks down (regime runaway) is run again with inertia.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from . import physics
from .engine import RawResult
from .models.stop_inertial import relax_points
from .plan import Plan
from .scene import Scene
from .status import Status

__all__ = ["ModelChoice", "MODEL_FLAG", "choose_stop_models", "line_uses_inertia", "solve_inertial",
           "warm_up_models"]

ESTIMATE_RTOL = 1e-4
"""Tolerance of the first-order correction's integration (the estimate is needed to a few %, not to rtol)."""
ESTIMATE_MARGIN = 1.5
"""A point keeps the quasi-static model only where ESTIMATE_MARGIN x its estimate is within model_tol (the
first-order estimate is within 0.95..1.11 of the true gap where it is trusted)."""
FIRST_ORDER_TRUST = 1.0
"""The first-order estimate is trusted where gamma/A (1 + (chi + |mu1|)/A) <= FIRST_ORDER_TRUST: the inertial time
gamma/A short against the fastest time of the quasi-static stop, its stiff start A/(chi + |mu1|). Beyond, the
expansion fails (estimate/true 0.84..1.34 at 1..3, down to 1e-6 at chi/A = 1e3, gamma/A = 1, where the slider
rebounds inertially), so the gap is measured by solving the point with inertia."""
TIGHTER = 10.0
"""The inertial solution is run at rtol/TIGHTER and rtol; their difference is its error estimate."""
MODEL_FLAG = {"flag_values": np.array([0, 1], np.int8), "flag_meanings": "quasistatic inertial"}
QUASISTATIC, INERTIAL = 0, 1


@dataclass
class ModelChoice:
    """Per flat point: ``inertial`` (bool: model used), ``model_error`` (estimated relative error of xi_inf with
    the quasi-static model; None when the scene forced a model and nothing was estimated), seconds spent."""

    inertial: np.ndarray
    model_error: np.ndarray | None
    seconds: float = 0.0


def line_uses_inertia(gamma_over_A: np.ndarray, model: str, model_tol: float) -> np.ndarray:
    """Per V: whether the Hopf line / driven points use the inertial model (module docstring)."""
    g = np.asarray(gamma_over_A, dtype=float)
    if model == "auto":
        return g > model_tol
    return np.full(g.shape, model == "inertial")


def _gamma_over_A(scene: Scene) -> np.ndarray:
    p = scene.params
    gamma = physics.inertia_number(scene.V, p.D0, p.g) / p.A
    return np.tile(gamma, scene.K_over_M.size)


def solve_inertial(scene: Scene, plan: Plan, raw: RawResult, rows: np.ndarray, idx: np.ndarray) -> None:
    """Replace the relaxed slip of the rows ``rows`` of ``raw`` (whose rows are the plan's points ``idx``; points
    with a finite limit) by the inertial model's, with the error estimate |x(rtol) - x(rtol/TIGHTER)| (the tighter
    value is kept)."""
    if rows.size == 0:
        return
    pts = idx[rows]
    args = (plan.k[pts], plan.a[pts], plan.b[pts], _gamma_over_A(scene)[pts], True)
    atol = scene.atol["xi_inf"]
    fine = relax_points(*args, scene.rtol / TIGHTER, atol / TIGHTER, scene.max_steps)
    coarse = relax_points(*args, scene.rtol, atol, scene.max_steps)
    raw.xi_inf[rows] = fine["xi_inf"]
    raw.xi_inf_err[rows] = np.abs(fine["xi_inf"] - coarse["xi_inf"])
    raw.status[rows] = np.where(fine["status"] != Status.OK, fine["status"], coarse["status"])
    raw.steps[rows] = fine["steps"]
    raw.work[rows] = fine["steps"] + coarse["steps"]


def choose_stop_models(scene: Scene, plan: Plan, raw: RawResult, idx: np.ndarray | None = None) -> ModelChoice:
    """Decide the model of the points ``idx`` (default: all; the rows of ``raw``) of a stop scene, solve the
    inertial ones, and update ``raw`` in place (module docstring)."""
    t0 = time.perf_counter()
    idx = np.arange(plan.n_points) if idx is None else np.asarray(idx)
    n = idx.size
    finite = np.flatnonzero(plan.finite[idx])  # rows
    if scene.model != "auto":
        if scene.model == "inertial":
            solve_inertial(scene, plan, raw, finite, idx)
        return ModelChoice(np.full(n, scene.model == "inertial") & plan.finite[idx], None, time.perf_counter() - t0)
    pts = idx[finite]
    G = _gamma_over_A(scene)[pts]
    estimate = relax_points(plan.k[pts], plan.a[pts], plan.b[pts], G, False, ESTIMATE_RTOL, scene.atol["xi_inf"],
                            scene.max_steps)
    model_error = np.full(n, np.nan)
    ok = estimate["status"] == Status.OK
    model_error[finite[ok]] = np.abs(estimate["correction"][ok] / estimate["xi_inf"][ok])
    trusted = G * (1.0 + plan.k[pts] + np.abs(plan.a[pts])) <= FIRST_ORDER_TRUST
    measure = np.zeros(n, bool)
    measure[finite] = ~ok | ~trusted | (ESTIMATE_MARGIN * model_error[finite] > scene.model_tol)
    rows = np.flatnonzero(measure)
    quasistatic = raw.xi_inf[rows].copy()
    if scene.time_resolved:  # keep the quasi-static values; the inertial xi_inf only measures the gap
        probe = RawResult.empty(n, 0)
        solve_inertial(scene, plan, probe, rows, idx)
        inertial_xi = probe.xi_inf[rows]
    else:
        solve_inertial(scene, plan, raw, rows, idx)
        inertial_xi = raw.xi_inf[rows]
    with np.errstate(invalid="ignore", divide="ignore"):
        measured = np.abs(inertial_xi / quasistatic - 1.0)
    model_error[rows] = np.where(np.isfinite(measured), measured, model_error[rows])
    if scene.time_resolved:
        over = rows[~(measured <= scene.model_tol)]
        raw.status[over[raw.status[over] == Status.OK]] = Status.MODEL_ERROR_ABOVE_TOL
        return ModelChoice(np.zeros(n, bool), model_error, time.perf_counter() - t0)
    return ModelChoice(measure, model_error, time.perf_counter() - t0)


def warm_up_models() -> None:
    """Compile (or load from numba's cache) the kernels of both models of the stop scene on one point."""
    one = np.ones(1)
    for inertial in (False, True):
        relax_points(2.0 * one, one, 0.0 * one, 0.1 * one, inertial, 1e-3, 1e-12, 10_000)
