"""ONE explicit Runge-Kutta stage loop, for every right-hand side and every tableau.

A right-hand side is a numba function ``rhs(y, p, dy) -> aux`` of an autonomous system of n components: it writes
f(y) into ``dy`` and returns one auxiliary number of the model (the stop scene's E = xi' psi, the driven scene's
ln xi'), with ``p`` the model's parameter record. :func:`make_erk_step` composes it with the stage loop at compile
time (a closure over the function: a direct call, never a call through a pointer). The tableau is data
(:meth:`sweep.integrate.solvers.tableau.ButcherTableau.arrays`) given to :func:`make_erk_step`: its coefficients are
compile-time constants and LLVM unrolls the stages (the driven scene's dp5: ~15 % faster than reading them at run
time). Users: the driven scene and the generic adaptive march (sweep/integrate/adaptive.py); the lanes and the
per-point stop path keep their own loop for measured reasons (docs/design.md 3.2).
"""

from __future__ import annotations

from numba import njit

from ...jitcache import pin
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
    step = _stage_loop_source(n, *tableau.arrays()[1:])
    namespace = {"rhs": rhs, "__name__": __name__}  # the generated function belongs to this module
    exec(compile(step, f"<sweep.integrate.solvers.explicit: {tableau.name}, n={n}>", "exec"), namespace)
    fixed_step = njit(fastmath=FAST, error_model="numpy")(namespace["fixed_step"])
    return pin(fixed_step, rhs.py_func.__module__, rhs.py_func.__qualname__, n, tableau.name)


def _stage_loop_source(n: int, A, B, E) -> str:
    """Python source of the stage loop written out for n components and the tableau (A, B, E): every stage state
    one expression per component, sum_j a_ij K[j, m] with the coefficients as literals (exact: repr of a float
    round-trips), summed in the order of j, as a loop would (zero coefficients kept, so that a non-finite stage
    still poisons the step and is rejected). Written out, the compiler keeps the sums in registers instead of
    storing and reloading a scratch row per term (the driven scene's step: 7 % faster than the loop)."""
    stages = B.size

    def weighted(weights, component: int) -> str:
        return " + ".join(f"({float(w)!r}) * K[{j}, {component}]" for j, w in enumerate(weights)) or "0.0"

    lines = ["def fixed_step(K, ys, y, h, p, y_new, err):", "    aux = 0.0"]
    for i in range(1, stages):
        lines += [f"    ys[{m}] = y[{m}] + h * ({weighted(A[i, :i], m)})" for m in range(n)]
        lines.append(f"    aux = rhs(ys, p, K[{i}])")
    for m in range(n):
        lines.append(f"    y_new[{m}] = y[{m}] + h * ({weighted(B, m)})")
        lines.append(f"    err[{m}] = h * ({weighted(E, m)})")
    lines.append("    return aux")
    return "\n".join(lines) + "\n"
