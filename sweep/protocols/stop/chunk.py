"""How a chunk of the stop protocol is computed: the quasi-static kernels (engine.py), the choice of model per point
(model_choice.py), the error_above_tol marks; and the stop kernels alone through the one chunk loop (the dry run's
pilot, the warm-up)."""

from __future__ import annotations

import functools
import time
from collections.abc import Callable

import numpy as np

from ...plan.plan import Plan
from ...run.runner import in_process, rows, run_chunks
from ...scene.scene import Scene
from ...status import Status
from ...write.writer import FlatArrays
from .engine import SAMPLED, RawResult, mark_error_above_tol, n_samples, run_points
from .model_choice import ModelChoice, choose_stop_models

__all__ = ["execute", "kernel_task", "stop_chunk", "stop_outputs", "warm_up"]


def stop_chunk(scene: Scene, plan: Plan, progress: bool | None = False
               ) -> Callable[[np.ndarray], dict[str, np.ndarray]]:
    """compute(points) of the stop protocol: the quasi-static kernels (unless the model is forced inertial), the
    choice of model, the inertial points (with a bar if ``progress``), the error_above_tol marks."""
    n_t = n_samples(scene, plan)

    def compute(points: np.ndarray) -> dict[str, np.ndarray]:
        # the first-order correction, where the lanes carry it (model="auto" only needs it)
        carried = np.full(points.size, np.nan) if scene.model == "auto" else None
        if scene.model == "inertial":
            raw = RawResult.empty(points.size, n_t, 0)
            raw.status[~plan.finite[points]] = Status.NO_FINITE_LIMIT
        else:
            raw = run_points(scene, plan, points, correction=carried)
            mark_error_above_tol(scene, raw)
        choice = choose_stop_models(scene, plan, raw, points, progress=progress, correction=carried)
        mark_error_above_tol(scene, raw)
        arrays = {name: value for name, value in vars(raw).items() if isinstance(value, np.ndarray)}
        arrays["inertial"] = choice.inertial
        if choice.model_error is not None:
            arrays["model_error"] = choice.model_error
        return arrays

    return compute

def kernel_task(scene: Scene, plan: Plan, points: np.ndarray, shared: bool = False,
                progress: bool | None = False) -> dict[str, np.ndarray]:
    """The stop kernels alone on one chunk (no choice of model, no error marks): :func:`execute`'s task (arguments
    as :func:`chunk_task`'s; no inertial points, so no bar)."""
    t0 = time.perf_counter()
    raw = run_points(scene, plan, rows(points, shared))
    arrays = {name: value for name, value in vars(raw).items() if isinstance(value, np.ndarray)}
    arrays["seconds"] = np.array(time.perf_counter() - t0)
    return arrays

def execute(scene: Scene, plan: Plan, indices: np.ndarray | None = None, progress: bool | None = None,
            chunk_size: int | None = None) -> RawResult:
    """The stop kernels alone (no choice of model) over the plan's points ``indices`` (default: all), through the
    one chunk loop in this process; flat outputs in the order of ``indices``, error_above_tol marked."""
    part = plan if indices is None else plan.take(np.asarray(indices))
    result = FlatArrays(part.n_points)
    run_chunks(scene, part, chunk_size, [result], progress, imap=functools.partial(in_process, task=kernel_task))
    out = RawResult(**result.flat, seconds=result.seconds)
    mark_error_above_tol(scene, out)
    return out

def warm_up(scene: Scene, plan: Plan) -> float:
    """Compile the kernels (or load them from numba's on-disk cache) on one point per method of the plan;
    returns the seconds taken."""
    t0 = time.perf_counter()
    firsts = np.array([int(np.argmax(plan.point_method == m)) for m in range(len(plan.point_methods))])
    if scene.model == "auto" and plan.lanes:  # the run's own lanes: those that carry the first-order correction
        run_points(scene, plan.take(firsts), np.arange(firsts.size), correction=np.full(firsts.size, np.nan))
    else:
        execute(scene, plan, firsts, progress=False)
    return time.perf_counter() - t0

def stop_outputs(flat: dict[str, np.ndarray], seconds: float = 0.0) -> tuple[RawResult, ModelChoice]:
    """The arrays of :func:`stop_chunk` (one chunk's, or consolidated) as the kernel outputs and the model choice."""
    n = flat["xi_inf"].size
    fields = {name: flat[name] if name in flat else np.empty((n, 0)) for name in RawResult.__dataclass_fields__
              if name in flat or name in SAMPLED}
    raw = RawResult(**fields, seconds=seconds)
    return raw, ModelChoice(flat["inertial"], flat.get("model_error"))

