"""Local refinement: scipy.optimize.least_squares (trust-region reflective, within the bounds) on the engine.

The Jacobian is by central finite differences, d r/d theta_j = (r(theta + h_j) - r(theta - h_j))/(2 h_j) with
h_j = FD_STEP x the parameter's scale (one-sided where a bound is closer), and it is computed speculatively:
every function evaluation posts theta and its 2q perturbed sets as ONE batch, so an iteration costs one engine
round. A profile point (``hold``) uses forward differences (q + 1 sets, not 2q + 1): only its optimum's misfit is
kept, which the Jacobian's accuracy does not change (it steers the steps only), and with HOLD_TOLERANCES it took
76 evaluations of 3 sets for benchmarks/fit.py's 18 profile points against 65 of 5 with central differences, the
same misfits to 1e-4; the best fit's Jacobian, which gives the covariance, stays central. With the engine at
rtol 1e-6 (the default) the derivative carries a relative error ~rtol/FD_STEP ~ 1e-3 and a truncation error
~FD_STEP^2 ~ 1e-6, far below what the noise of a measured curve (>~1e-3) resolves.

Some parameters may be held fixed (``hold``): the profile likelihoods (sweep.fit.profiles) minimise over the
others at fixed values of one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .forward import ForwardPoints, ForwardResult
from .problem import Problem

__all__ = ["FD_STEP", "LocalFit", "refine"]

FD_STEP = 1e-3
"""Finite-difference step relative to each parameter's scale (ParamSpace.scale)."""
TOLERANCES = {"ftol": 1e-10, "xtol": 1e-9, "gtol": 1e-10}
"""least_squares' stopping tolerances (relative)."""
HOLD_TOLERANCES = {"ftol": 1e-8, "xtol": 1e-6, "gtol": 1e-8}
"""The same for a profile point (``hold``), whose misfit only is kept: its rise over the best fit is read against
3.84 to ~1e-3, i.e. to ~1e-5 of a misfit of ~n = 200 (ftol 1e-8 is 1e-6 of it), and a parameter 1e-6 (relative,
xtol) off its optimum changes the misfit by ~(1e-6/0.01)^2 for a 1 % standard error."""
MAX_NFEV = 200

Evaluate = Callable[[ForwardPoints], ForwardResult]


@dataclass
class LocalFit:
    """Result of :func:`refine`: the parameter set (all free parameters, held ones included), its weighted
    residuals, the Jacobian of those over every free parameter (held ones too, so that the best fit's Jacobian
    serves the covariance), the sum of squares, function evaluations, whether steady sliding was stable before every
    stop, and least_squares' status and message."""

    theta: np.ndarray
    residuals: np.ndarray
    jac: np.ndarray
    rss: float
    nfev: int
    stable: bool
    status: int
    message: str


def _perturbed(problem: Problem, theta: np.ndarray, columns: np.ndarray, central: bool
               ) -> tuple[np.ndarray, np.ndarray]:
    """(sets, steps): theta, then for each j of ``columns`` theta +- h_j (central; clipped to the bounds) or theta + h_j
    (forward; theta - h_j at the upper bound), and the actual step widths (signed: from the lower set to the upper)."""
    sp = problem.space
    h = FD_STEP * sp.scale
    sets = [theta]
    widths = []
    for j in columns:
        up, down = theta.copy(), theta.copy()
        up[j] = min(theta[j] + h[j], sp.upper[j])
        down[j] = max(theta[j] - h[j], sp.lower[j])
        if central:
            sets += [up, down]
            widths.append(up[j] - down[j])
        else:
            one = up if up[j] > theta[j] else down
            sets.append(one)
            widths.append(one[j] - theta[j])
    return np.array(sets), np.array(widths)


def evaluate_with_jacobian(problem: Problem, theta: np.ndarray, evaluate: Evaluate,
                           columns: np.ndarray | None = None, central: bool = True
                           ) -> tuple[np.ndarray, np.ndarray, bool]:
    """(residuals, Jacobian over ``columns`` (default all free parameters), stable) at theta, in one batch; central
    differences, or forward ones (``central=False``: q + 1 sets instead of 2q + 1)."""
    columns = np.arange(problem.space.p) if columns is None else columns
    sets, widths = _perturbed(problem, theta, columns, central)
    res = evaluate(problem.points(sets))
    r = problem.residuals(res, sets.shape[0])
    if not columns.size:
        jac = np.empty((r.shape[1], 0))
    elif central:
        jac = ((r[1::2] - r[2::2]) / widths[:, None]).T
    else:
        jac = ((r[1:] - r[0]) / widths[:, None]).T
    return r[0], jac, bool(problem.stable(res, sets.shape[0])[0])


def refine(problem: Problem, theta0: np.ndarray, evaluate: Evaluate, hold: dict[int, float] | None = None
           ) -> LocalFit:
    """Least squares from theta0 over the free parameters not in ``hold`` (index -> fixed value)."""
    sp = problem.space
    hold = hold or {}
    theta0 = np.clip(np.asarray(theta0, dtype=float), sp.lower, sp.upper)
    for j, v in hold.items():
        theta0[j] = v
    move = np.array([j for j in range(sp.p) if j not in hold], dtype=int)
    cache: dict[bytes, tuple[np.ndarray, np.ndarray, bool]] = {}

    def full(x):
        th = theta0.copy()
        th[move] = x
        return th

    def at(x):
        key = np.asarray(x, dtype=float).tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = evaluate_with_jacobian(problem, full(x), evaluate, move, central=not hold)
        return cache[key]

    if move.size == 0:
        r, _, stable = evaluate_with_jacobian(problem, theta0, evaluate, move)
        return LocalFit(theta0, r, np.empty((r.size, sp.p)), float(r @ r), 1, stable, 1, "nothing to optimise")
    lo, hi = sp.lower[move], sp.upper[move]
    x0 = np.clip(theta0[move], lo, hi)
    sol = least_squares(lambda x: at(x)[0], x0, jac=lambda x: at(x)[1], bounds=(lo, hi), x_scale=sp.scale[move],
                        method="trf", max_nfev=MAX_NFEV, **(HOLD_TOLERANCES if hold else TOLERANCES))
    theta = full(sol.x)
    if hold:  # a profile point: its residuals at the optimum are all it needs
        r, stable = at(sol.x)[0], at(sol.x)[2]
        return LocalFit(theta, r, np.empty((r.size, 0)), float(r @ r), int(sol.nfev), stable, int(sol.status),
                        sol.message)
    r, jac, stable = at(sol.x)
    return LocalFit(theta, r, jac, float(r @ r), int(sol.nfev), stable, int(sol.status), sol.message)
