"""The dry run's estimate of a stop sweep's wall time, from timed pilot subsamples."""

from __future__ import annotations

import time

import numpy as np

from ...plan.plan import Plan, make_plan
from ...scene.scene import Scene
from .chunk import execute, warm_up
from .engine import RawResult
from .model_choice import choose_stop_models, warm_up_models

__all__ = ["estimate_seconds"]


def estimate_seconds(scene: Scene, plan: Plan | None = None, sample: int = 256,
                     n_points: int | None = None) -> tuple[float, float]:
    """Estimate the wall time of the whole sweep (with the choice of model and its inertial points) from strided
    pilot subsamples of ``sample`` and 4 x ``sample`` points.

    Returns (estimated seconds, mean steps per point of the pilot). A call has a fixed cost (~0.4 ms: chunking,
    the ladder's array work, thread start) besides its cost per point, so the estimate is fixed + marginal x N
    from the two pilots (one pilot scaled by N / sample overstated the default scene 3x). The kernel is warmed up
    first and each pilot is timed three times, keeping the fastest, so that a passing hiccup of the machine does
    not inflate the estimate. Sweeps of at most 4 x ``sample`` points are timed whole. ``n_points``: the points
    of the grid that ``scene`` samples (:func:`plan_sample`), default its own.
    """
    plan = plan or make_plan(scene)

    warm_up(scene, plan)
    if scene.model != "quasistatic":
        warm_up_models()

    def run(pilot: np.ndarray) -> RawResult:
        t0 = time.perf_counter()
        if scene.model == "inertial":
            raw = RawResult.empty(pilot.size, 0, 0)
        else:
            raw = execute(scene, plan, pilot, progress=False)
        choose_stop_models(scene, plan, raw, pilot)
        raw.seconds = time.perf_counter() - t0
        return raw

    def timed_pilot(n: int) -> tuple[float, RawResult, int]:
        pilot = np.arange(0, plan.n_points, max(1, plan.n_points // n))
        runs = [run(pilot) for _ in range(3)]
        return min(r.seconds for r in runs), runs[0], pilot.size

    t_big, res, n_big = timed_pilot(4 * sample)
    total = n_points or plan.n_points
    if n_big >= plan.n_points and total == plan.n_points:
        return t_big, float(res.steps.mean())
    t_small, _, n_small = timed_pilot(sample)
    marginal = max((t_big - t_small) / (n_big - n_small), 0.0) if n_big > n_small else t_big / n_big
    fixed = max(t_small - marginal * n_small, 0.0)
    return fixed + marginal * total, float(res.steps.mean())
