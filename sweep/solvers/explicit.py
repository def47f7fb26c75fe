"""ONE explicit Runge-Kutta stage loop, for every right-hand side and every tableau.

A right-hand side is a numba function ``rhs(y, p, dy) -> aux`` of an autonomous system of n components: it writes
f(y) into ``dy`` and returns one auxiliary number of the model (the stop scene's E = xi' psi, the driven scene's
ln xi'), with ``p`` the model's parameter record. :func:`make_erk_step` composes it with the stage loop at compile
time (a closure over the function: a direct call, never a call through a pointer). The tableau is data
(:meth:`sweep.solvers.tableau.ButcherTableau.arrays`) given to :func:`make_erk_step`: its coefficients are
compile-time constants and LLVM unrolls the stages (the driven scene's dp5: ~15 % faster than reading them at run
time). Users: the driven scene and the generic adaptive march (sweep/integrate/adaptive.py); the lanes and the
per-point stop path keep their own loop for measured reasons (docs/design.md 3.2).
"""

from __future__ import annotations

from numba import njit

from ..jitcache import pin
from .fastmath import FAST

__all__ = ["make_erk_step"]


def make_erk_step(rhs, n: int, tableau):
    """One explicit RK step of size h from y (n components), K[0] = f(y) on entry; fills K[1:], the new state
    y_new and the embedded error estimate err = h sum_j e_j K[j] (zero for a method without one); returns the aux
    value of the last stage. For an FSAL tableau K[s-1] is f(y_new) and the returned aux is rhs's at y_new (the
    last stage's state is y_new to the last bit: its row of A is b, and b's last weight is 0). ``ys`` is scratch
    for the stage states (n).

    Returns step(K, ys, y, h, p, y_new, err), the tableau's coefficients frozen into the compiled code.
    """

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def stage_loop(c, A, b, e, K, ys, y, h, p, y_new, err):
        stages = b.size
        aux = 0.0
        for i in range(1, stages):
            # one pass over the earlier stages for all components (the same sums, in the same order, as one sum
            # per component, with a third of the loop overhead): ys accumulates sum_j a_ij K[j] first
            for m in range(n):
                ys[m] = 0.0
            for j in range(i):
                a_ij = A[i, j]
                for m in range(n):
                    ys[m] += a_ij * K[j, m]
            for m in range(n):
                ys[m] = y[m] + h * ys[m]
            aux = rhs(ys, p, K[i])
        for m in range(n):
            y_new[m], err[m] = 0.0, 0.0
        for j in range(stages):
            b_j, e_j = b[j], e[j]
            for m in range(n):
                y_new[m] += b_j * K[j, m]
                err[m] += e_j * K[j, m]
        for m in range(n):
            y_new[m] = y[m] + h * y_new[m]
            err[m] = h * err[m]
        return aux

    C, A_, B, E = tableau.arrays()  # frozen into the compiled code as constants

    @njit(fastmath=FAST, error_model="numpy")
    def fixed_step(K, ys, y, h, p, y_new, err):
        return stage_loop(C, A_, B, E, K, ys, y, h, p, y_new, err)

    return pin(fixed_step, rhs.py_func.__module__, rhs.py_func.__qualname__, n, tableau.name)
