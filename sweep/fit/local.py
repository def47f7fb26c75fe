"""Local refinement: every problem's least squares from its best grid point, in lockstep (sweep.fit.levenberg).

Central-difference Jacobians (2p + 1 parameter sets a task and iteration, one engine round for all tasks), the
engine at the fit's ``rtol``; the Jacobian at the best fit gives the covariance (sweep.fit.uncertainty).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .levenberg import FIT, STATUS, solve
from .stack import ProblemStack

__all__ = ["LocalFit", "refine_all"]


@dataclass
class LocalFit:
    """Result of a least squares: the parameter set (all free parameters), its weighted residuals (n_residuals),
    the Jacobian of those over every free parameter, the sum of squares, function evaluations, whether steady
    sliding was stable before every stop, and the status (sweep.fit.levenberg.STATUS) and its message."""

    theta: np.ndarray
    residuals: np.ndarray
    jac: np.ndarray
    rss: float
    nfev: int
    stable: bool
    status: int
    message: str


def refine_all(stack: ProblemStack, theta0: list[np.ndarray]) -> list[LocalFit]:
    """Least squares of every problem of ``stack`` from ``theta0[q]``."""
    sol = solve(stack, np.arange(len(stack.problems)), np.array(theta0), central=True, tol=FIT)
    out = []
    for q, n in enumerate(stack.n_res):
        out.append(LocalFit(sol.theta[q].copy(), sol.residuals[q, :n].copy(), sol.jac[q, :n].copy(),
                            float(sol.rss[q]), int(sol.nfev[q]), bool(sol.stable[q]), int(sol.status[q]),
                            STATUS[int(sol.status[q])]))
    return out
