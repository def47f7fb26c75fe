"""Global stage: a coarse sweep of the free parameters over their bounds, so that no local minimum is taken.

Level 1 is a grid over the bound box (GRID_POINTS[p] values per parameter: log-spaced for the positive ones,
linear otherwise) plus the starting values; level 2 a finer grid (ZOOM_POINTS per parameter) spanning one level-1
spacing either side of the best level-1 point. Each problem posts both its levels as one batch each (with many
problems, all their grids go into the same engine calls). Parameter sets under which some stop of the data would
start from unstable sliding (chi <= mu1, eq. 3: no steady sliding before the stop) are excluded. The level-1
misfit (sum of squared weighted residuals) is kept as the misfit landscape of the output.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .local import Evaluate
from .problem import Problem
from .space import ParamSpace

__all__ = ["GRID_POINTS", "GlobalResult", "grid_axes", "search"]

GRID_POINTS = {1: 41, 2: 15, 3: 9, 4: 6, 5: 5}
"""Level-1 grid values per free parameter, by the number of free parameters (41, 225, 729, 1296, 3125 sets)."""
ZOOM_POINTS = 5


@dataclass
class GlobalResult:
    """Best parameter set of the global stage and the level-1 misfit landscape (shape: one axis per free
    parameter, NaN where excluded)."""

    theta: np.ndarray
    rss: float
    landscape: np.ndarray


def _spaced(lo: float, hi: float, n: int, log: bool) -> np.ndarray:
    return np.geomspace(lo, hi, n) if log else np.linspace(lo, hi, n)


def grid_axes(space: ParamSpace) -> list[np.ndarray]:
    """The level-1 grid values of each free parameter."""
    n = GRID_POINTS[space.p]
    return [_spaced(lo, hi, n, log) for lo, hi, log in zip(space.lower, space.upper, space.log)]


def _zoom_axes(space: ParamSpace, axes: list[np.ndarray], best: tuple[int, ...]) -> list[np.ndarray]:
    out = []
    for ax, i, log in zip(axes, best, space.log):
        lo, hi = ax[max(i - 1, 0)], ax[min(i + 1, ax.size - 1)]
        out.append(_spaced(lo, hi, ZOOM_POINTS, log))
    return out


def _misfit(problem: Problem, sets: np.ndarray, evaluate: Evaluate) -> np.ndarray:
    res = evaluate(problem.points(sets))
    r = problem.residuals(res, sets.shape[0])
    rss = np.sum(r * r, axis=1)
    return np.where(problem.stable(res, sets.shape[0]), rss, np.nan)


def _product(axes: list[np.ndarray]) -> np.ndarray:
    return np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)


def search(problem: Problem, evaluate: Evaluate) -> GlobalResult:
    """Both levels for one problem (run it inside :class:`sweep.fit.lockstep.Lockstep` to batch many)."""
    sp = problem.space
    axes = grid_axes(sp)
    sets = np.vstack((_product(axes), sp.start))
    rss = _misfit(problem, sets, evaluate)
    landscape = rss[:-1].reshape([a.size for a in axes])
    candidates = [(rss, sets)]
    if np.isfinite(landscape).any():
        best = np.unravel_index(np.nanargmin(landscape), landscape.shape)
        zoom = _product(_zoom_axes(sp, axes, tuple(int(i) for i in best)))
        candidates.append((_misfit(problem, zoom, evaluate), zoom))
    all_rss = np.concatenate([c[0] for c in candidates])
    all_sets = np.vstack([c[1] for c in candidates])
    if not np.isfinite(all_rss).any():  # cannot happen for validated data (sweep.fit.checks): keep the start
        return GlobalResult(sp.start.copy(), float("nan"), landscape)
    i = int(np.nanargmin(all_rss))
    return GlobalResult(all_sets[i].copy(), float(all_rss[i]), landscape)
