"""A subsample of a large grid, so that a dry run answers without planning (or holding) the whole grid."""

from __future__ import annotations

import numpy as np

from ..scene.scene import Scene

__all__ = ["PLANNED_POINTS", "plan_sample"]

PLANNED_POINTS = 250_000
"""The dry run plans grids of at most this many points whole (~0.2 s); a larger grid through a subsample of its axes
(:func:`plan_sample`), so that its answer never waits on, or runs out of memory for, the plan of the whole grid."""


def plan_sample(scene: Scene, max_points: int = PLANNED_POINTS) -> tuple[Scene, str | None]:
    """(scene, None) for a grid of at most ``max_points`` points; else the scene on values spread evenly over each
    axis (both ends kept, at most ``max_points`` points in all), with a line that says so."""
    if scene.n_points <= max_points:
        return scene, None
    picked, room = {}, max_points
    for d, n in sorted(zip(scene.dims, scene.shape), key=lambda item: item[1]):  # the short axes first, whole
        left = len(scene.dims) - len(picked)
        take = min(n, max(2, int(room ** (1.0 / left))))
        picked[d] = np.unique(np.linspace(0, n - 1, take).round().astype(int))
        room = max(1, room // picked[d].size)
    values = {d: scene.axis(d)[picked[d]] for d in scene.dims}
    sample = scene.on_values(values)
    sizes = " x ".join(f"{picked[d].size} {'K/M' if d == 'K_over_M' else d}" for d in scene.dims)
    return sample, (f"a subsample of {sizes} spread over the grid (its {scene.n_points:,} points are too many to plan "
                    f"for a dry run): the counts below are the subsample's")
