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

A parameter that shifts every weighted residual along a fixed direction (ProblemStack.offset: a record's mu0, mu(t)
= mu0 + a function of the others) is not gridded: the grid of the others is solved at its start value, and the sums
sum r g and sum g^2 (g the residuals' derivative along it) give each set's misfit at any value of it exactly, so each
set takes its best value within the bounds and the landscape is filled along its grid values without a solve (a
record fit of a, b, Dc, mu0: 6^3 + 1 sets solved instead of 6^4 + 1, and mu0 at its optimum rather than on 6 values).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .space import ParamSpace
from .stack import Misfits, ProblemStack

__all__ = ["GRID_POINTS", "GlobalResult", "grid_axes", "grid_sets", "search_all"]

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


def grid_sets(space: ParamSpace, offset: int | None = None) -> np.ndarray:
    """The parameter sets the global stage solves: the level-1 grid, then the start; with an ``offset`` parameter
    (ProblemStack.offset) its axis is the start's value alone (its best value per set follows from the misfit
    sums: :func:`search_all`)."""
    axes = grid_axes(space)
    if offset is not None:
        axes[offset] = space.start[offset:offset + 1]
    return np.vstack((_product(axes), space.start))


def _at_best_offset(sp: ParamSpace, j: int, sets: np.ndarray, m: Misfits) -> tuple[np.ndarray, np.ndarray]:
    """(shift of parameter j (Q, S): the least misfit's, within its bounds; the misfit there (Q, S))."""
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.where(m.norm > 0, -m.cross / m.norm, 0.0)
    c = np.clip(c, sp.lower[j] - sets[:, j], sp.upper[j] - sets[:, j])
    return c, m.rss + 2.0 * c * m.cross + c * c * m.norm


def search_all(stack: ProblemStack) -> list[GlobalResult]:
    """The grid and the start for every problem of ``stack`` (engine at its rtol), in one engine round; with an
    offset parameter (ProblemStack.offset) each set at that parameter's best value (the landscape at its grid
    values, exactly, from the same sums)."""
    sp, j = stack.space, stack.offset
    axes = grid_axes(sp)
    sets = grid_sets(sp, j)
    Q = len(stack.problems)
    m = stack.misfits(np.arange(Q), sets)
    shape = [Q] + [1 if i == j else a.size for i, a in enumerate(axes)]  # the solved grid
    if j is None:
        shift, rss, landscape = np.zeros_like(m.rss), m.rss, m.rss[:, :-1].reshape(shape)
    else:
        shift, rss = _at_best_offset(sp, j, sets, m)
        d = (axes[j] - sp.start[j]).reshape([axes[j].size if i == j + 1 else 1 for i in range(sp.p + 1)])
        landscape = (m.rss[:, :-1].reshape(shape) + 2.0 * d * m.cross[:, :-1].reshape(shape)
                     + d * d * m.norm[:, :-1].reshape(shape))
    rss = np.where(m.stable, rss, np.nan)
    failures = m.failures
    landscape = np.where((m.stable & (failures == 0))[:, :-1].reshape(shape), landscape, np.nan)
    out: list[GlobalResult] = []
    for q in range(Q):
        usable = np.flatnonzero(np.isfinite(rss[q]))
        if not usable.size:  # cannot happen for validated data (sweep.fit.checks): keep the start
            out.append(GlobalResult(sp.start.copy(), float("nan"), landscape[q], int(failures[q, -1])))
            continue
        i = usable[np.lexsort((rss[q, usable], failures[q, usable]))[0]]  # fewest failures, then least misfit
        theta = sets[i].copy()
        if j is not None:
            theta[j] += shift[q, i]
        out.append(GlobalResult(theta, float(rss[q, i]), landscape[q], int(failures[q, i])))
    return out
