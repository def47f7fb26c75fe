"""ONE explicit Runge-Kutta stage loop, for every right-hand side and every tableau.

A right-hand side is a numba function ``rhs(y, p, dy) -> aux`` of an autonomous system of n components: it writes
f(y) into ``dy`` and returns one auxiliary number of the model (the stop scene's E = xi' psi, the driven scene's
ln xi'), with ``p`` the model's parameter record. :func:`make_erk_step` composes it with the stage loop at compile
time (a closure over the function: a direct call, never a call through a pointer). The tableau is data
(:meth:`sweep.solvers.tableau.ButcherTableau.arrays`): given to :func:`make_erk_step`, its coefficients are
compile-time constants and LLVM unrolls the stages (the driven scene's dp5: ~15 % faster than reading them at run
time); otherwise they are arguments, and one compiled driver serves every tableau (the stop scene's per-point
path, whose method is the scene's choice).
"""

from __future__ import annotations

from numba import njit

from ..jitcache import pin
from .fastmath import FAST

__all__ = ["make_erk_step"]


def make_erk_step(rhs, n: int, tableau=None):
    """One explicit RK step of size h from y (n components), K[0] = f(y) on entry; fills K[1:], the new state
    y_new and the embedded error estimate err = h sum_j e_j K[j] (zero for a method without one). For an FSAL
    tableau K[s-1] is f(y_new). ``ys`` is scratch for the stage states (n).

    Without ``tableau``: step(c, A, b, e, K, ys, y, h, p, y_new, err); with one: step(K, ys, y, h, p, y_new, err).
    """

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def stage_loop(c, A, b, e, K, ys, y, h, p, y_new, err):
        stages = b.size
        for i in range(1, stages):
            for m in range(n):
                acc = 0.0
                for j in range(i):
                    acc += A[i, j] * K[j, m]
                ys[m] = y[m] + h * acc
            rhs(ys, p, K[i])
        for m in range(n):
            acc, acc_e = 0.0, 0.0
            for j in range(stages):
                acc += b[j] * K[j, m]
                acc_e += e[j] * K[j, m]
            y_new[m] = y[m] + h * acc
            err[m] = h * acc_e

    if tableau is None:
        @njit(fastmath=FAST, error_model="numpy")
        def step(c, A, b, e, K, ys, y, h, p, y_new, err):
            stage_loop(c, A, b, e, K, ys, y, h, p, y_new, err)

        return pin(step, rhs.py_func.__module__, rhs.py_func.__qualname__, n)

    C, A_, B, E = tableau.arrays()  # frozen into the compiled code as constants

    @njit(fastmath=FAST, error_model="numpy")
    def fixed_step(K, ys, y, h, p, y_new, err):
        stage_loop(C, A_, B, E, K, ys, y, h, p, y_new, err)

    return pin(fixed_step, rhs.py_func.__module__, rhs.py_func.__qualname__, n, tableau.name)
