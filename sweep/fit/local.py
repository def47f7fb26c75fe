"""Local refinement: every problem's least squares from its best grid point, in lockstep (sweep.fit.levenberg).

Two phases, each one Levenberg-Marquardt over every task at once (one engine round an iteration,
sweep.fit.levenberg): forward-difference Jacobians (p + 1 parameter sets an iteration), then from where they
stopped central-difference ones (2p + 1 sets), which stop after one or two iterations: the Jacobian at the best fit,
central, gives the covariance (sweep.fit.uncertainty). The 100 curves of benchmarks/fit.py took 67 forward solves a
curve with central differences throughout, ~50 so; Broyden's secants from one central Jacobian (one solve an
iteration, as the profile points do from the best fit) took up to 100 iterations from the coarse global grid. The
engine runs at the fit's ``rtol``.
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
    tasks = np.arange(len(stack.problems))
    theta0 = np.clip(np.array(theta0, dtype=float), stack.space.lower, stack.space.upper)
    first = solve(stack, tasks, theta0, central=False, tol=FIT)
    sol = solve(stack, tasks, first.theta, central=True, tol=FIT)
    sol.nfev += first.nfev
    out = []
    for q, n in enumerate(stack.n_res):
        out.append(LocalFit(sol.theta[q].copy(), sol.residuals[q, :n].copy(), sol.jac[q, :n].copy(),
                            float(sol.rss[q]), int(sol.nfev[q]), bool(sol.stable[q]), int(sol.status[q]),
                            STATUS[int(sol.status[q])]))
    return out
