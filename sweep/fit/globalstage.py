"""Global stage: a coarse sweep of the free parameters over their bounds, so that no local minimum is taken.

A grid over the bound box (GRID_POINTS[p] values per parameter: log-spaced for the positive ones, linear otherwise)
plus the starting values, for every problem in one engine round (sweep.fit.stack: problems that share (K/M, V),
times and bounds share their grid, solved once). The least squares start from the best of them: a finer grid around
it (a second level of 5^p sets a problem) cost more forward solves than the Levenberg-Marquardt iterations it saved.
Parameter sets under which some stop of the data would start from unstable sliding (chi <= mu1, eq. 3: no steady
sliding before the stop) are excluded. Sets are ranked by the number of data the model did not solve (no finite
value: e.g. no finite relaxed slip, m2 = 0 with mu1 < 0) first, then by the misfit over the solved data: a failed
solve never wins, whatever the noise (with the noise estimated the misfit of a poor but solved set outweighed any
fixed penalty per failure, and every sample of issue 37's relaxed slips ended at a corner where nothing solved). The
misfit (sum of squared weighted residuals) over the grid, NaN where a datum failed, is kept as the misfit landscape of
the output.
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
    """Best parameter set of the global stage, its misfit over the data it solved, the number of data it did not
    solve (``failures``, 0 for a usable start) and the level-1 misfit landscape (shape: one axis per free parameter,
    NaN where excluded or where a datum failed)."""

    theta: np.ndarray
    rss: float
    landscape: np.ndarray
    failures: int = 0


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
    rss, stable, failures = stack.misfits(np.arange(Q), sets)
    rss = np.where(stable, rss, np.nan)
    out: list[GlobalResult] = []
    for q in range(Q):
        landscape = np.where(failures[q, :-1] == 0, rss[q, :-1], np.nan).reshape([a.size for a in axes])
        usable = np.flatnonzero(np.isfinite(rss[q]))
        if not usable.size:  # cannot happen for validated data (sweep.fit.checks): keep the start
            out.append(GlobalResult(sp.start.copy(), float("nan"), landscape, int(failures[q, -1])))
            continue
        i = usable[np.lexsort((rss[q, usable], failures[q, usable]))[0]]  # fewest failures, then least misfit
        out.append(GlobalResult(sets[i].copy(), float(rss[q, i]), landscape, int(failures[q, i])))
    return out
