"""Local refinement: every problem's least squares from its best grid point, in lockstep (sweep.fit.levenberg).

One Levenberg-Marquardt over every task at once (one engine round an iteration, sweep.fit.levenberg) with
forward-difference Jacobians (p + 1 parameter sets an iteration); the one at its optimum gives the covariance
(sweep.fit.uncertainty; a central-difference Jacobian there, one more round of 2p sets, moved the standard errors
by < 1.4e-3 of themselves and the 95 % bounds by < 4e-4 of their half-widths on 100 records and 30 stop curves, and
took ~10 % of a record fit's time: sweep.fit.levenberg). Central-difference iterations
from that optimum (2p + 1 sets each, one or two more rounds) moved the best values of
benchmarks/fit.py's 100 curves by < 5e-4 of their standard errors, the standard errors by < 1.2e-5 and the 95 % bounds
by < 7e-4 of their half-widths: the forward differences' error (~FD_STEP) barely moves the optimum they stop at.
The 100 curves took 67 forward solves a curve with central differences throughout; Broyden's secants from one
central Jacobian (one solve an iteration, as the profile points do from the best fit) took up to 100 iterations from
the coarse global grid. The engine runs at the fit's ``rtol``.
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
    sliding was stable before every stop, the status (sweep.fit.levenberg.STATUS) and its message, and the number of
    residuals the model gave no number for (MODEL_FAILED stands in for them: sweep.fit.verdict)."""

    theta: np.ndarray
    residuals: np.ndarray
    jac: np.ndarray
    rss: float
    nfev: int
    stable: bool
    status: int
    message: str
    failures: int = 0


def refine_all(stack: ProblemStack, theta0: list[np.ndarray]) -> list[LocalFit]:
    """Least squares of every problem of ``stack`` from ``theta0[q]``."""
    tasks = np.arange(len(stack.problems))
    theta0 = np.clip(np.array(theta0, dtype=float), stack.space.lower, stack.space.upper)
    sol = solve(stack, tasks, theta0, tol=FIT)
    jac = sol.jac  # the last step's forward differences at the best set (module docstring)
    out = []
    for q, n in enumerate(stack.n_res):
        out.append(LocalFit(sol.theta[q].copy(), sol.residuals[q, :n].copy(), jac[q, :n].copy(),
                            float(sol.rss[q]), int(sol.nfev[q]) + 1, bool(sol.stable[q]), int(sol.status[q]),
                            STATUS[int(sol.status[q])], int(sol.failures[q])))
    return out
