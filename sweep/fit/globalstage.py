"""Global stage: a coarse sweep of the free parameters over their bounds, so that no local minimum is taken.

A grid over the bound box (GRID_POINTS[p] values per parameter: log-spaced for the positive ones, linear otherwise)
plus the starting values, for every problem in one engine round (sweep.fit.stack: problems that share (K/M, V),
times and bounds share their grid, solved once). The least squares start from the best of them: a finer grid around
it (a second level of 5^p sets a problem) cost more forward solves than the Levenberg-Marquardt iterations it saved.
Parameter sets under which some stop of the data would start from unstable sliding (chi <= mu1, eq. 3: no steady
sliding before the stop) are excluded. The misfit (sum of squared weighted residuals) over the grid is kept as the
misfit landscape of the output.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .space import ParamSpace
from .stack import ProblemStack

__all__ = ["GRID_POINTS", "GlobalResult", "grid_axes", "search_all"]

GRID_POINTS = {1: 41, 2: 15, 3: 9, 4: 6, 5: 5}
"""Level-1 grid values per free parameter, by the number of free parameters (41, 225, 729, 1296, 3125 sets)."""


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


def _product(axes: list[np.ndarray]) -> np.ndarray:
    return np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)


def search_all(stack: ProblemStack) -> list[GlobalResult]:
    """The grid and the start for every problem of ``stack`` (engine at its rtol), in one engine round."""
    sp = stack.space
    axes = grid_axes(sp)
    sets = np.vstack((_product(axes), sp.start))
    Q = len(stack.problems)
    rss, stable = stack.misfits(np.arange(Q), sets)
    rss = np.where(stable, rss, np.nan)
    out: list[GlobalResult] = []
    for q in range(Q):
        landscape = rss[q, :-1].reshape([a.size for a in axes])
        if not np.isfinite(rss[q]).any():  # cannot happen for validated data (sweep.fit.checks): keep the start
            out.append(GlobalResult(sp.start.copy(), float("nan"), landscape))
            continue
        i = int(np.nanargmin(rss[q]))
        out.append(GlobalResult(sets[i].copy(), float(rss[q, i]), landscape))
    return out
