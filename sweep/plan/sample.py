"""A subsample of a large grid, so that a dry run answers without planning (or holding) the whole grid."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..scene.scene import Scene

__all__ = ["PLANNED_POINTS", "plan_sample"]

PLANNED_POINTS = 250_000
"""The dry run plans grids of at most this many points whole (~0.2 s); a larger grid through a subsample of its axes
(:func:`plan_sample`), so that its answer never waits on, or runs out of memory for, the plan of the whole grid."""


def plan_sample(scene: Scene, max_points: int = PLANNED_POINTS) -> tuple[Scene, str | None]:
    """(scene, None) for a grid of at most ``max_points`` points; else the scene on every n-th value of each axis
    (both ends kept, at most ``max_points`` points), with a line that says so."""
    if scene.n_points <= max_points:
        return scene, None
    n_k, n_v = scene.shape
    per_axis = max(2, int(math.isqrt(max_points)))
    k = np.unique(np.linspace(0, n_k - 1, min(n_k, per_axis)).round().astype(int))
    v = np.unique(np.linspace(0, n_v - 1, min(n_v, max_points // k.size)).round().astype(int))
    sample = replace(scene, K_over_M=scene.K_over_M[k], V=scene.V[v])
    return sample, (f"a subsample of {k.size} K/M x {v.size} V spread over the grid (its {scene.n_points:,} points "
                    f"are too many to plan for a dry run): the counts below are the subsample's")
