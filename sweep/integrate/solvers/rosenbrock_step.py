"""One compiled step of the RODAS3 Rosenbrock method (:data:`sweep.integrate.solvers.RODAS3`) for a small stiff system.

The system is a numba function ``system(s, y, p, f, J, ft, jacobian)`` that writes f = dy/ds into ``f`` and, when
``jacobian`` is True, J = df/dy into ``J`` (n x n) and df/ds into ``ft``; ``p`` is a tuple of parameters. The step
solves the stages of HW IV.7.25' with the matrix I/(h gamma) - J, factorised once per step (LU with partial
pivoting, n <= a few), and returns the embedded error estimate beside the new state. Every other array is scratch
space owned by the caller (:class:`RodasWork`, from :func:`scratch`), so a step allocates nothing.

Used by the inertial stop (sweep/integrate/models/stop_inertial.py, n = 2) and the inertial driven scene
(sweep/integrate/models/driven.py, n = 3), both stiff where the slip velocity xi' is small (rate A/(gamma xi')).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ...jitcache import pin, pin_module
from .rosenbrock import RODAS3

__all__ = ["RodasWork", "make_rodas3_step", "scratch"]

_GAM = RODAS3.gamma
(_, _, _, _), (_A21, _, _, _), (_A31, _A32, _, _), (_A41, _A42, _A43, _) = RODAS3.a
(_, _, _, _), (_C21, _, _, _), (_C31, _C32, _, _), (_C41, _C42, _C43, _) = RODAS3.c
_AL2, _AL3, _AL4 = RODAS3.alpha_x[1:]
_G1, _G2, _G3, _G4 = RODAS3.gamma_x
_M1, _M2, _M3, _M4 = RODAS3.m
_E1, _E2, _E3, _E4 = RODAS3.e
_SAME_F2 = _A21 == 0.0 and _AL2 == 0.0


class RodasWork(NamedTuple):
    """Scratch arrays of one RODAS3 step of a system of size n (:func:`make_rodas3_step`)."""

    K: np.ndarray
    """(4, n): the stages."""
    M: np.ndarray
    """(n, n): the Jacobian J, then the LU factors of I/(h gamma) - J."""
    piv: np.ndarray
    """(n,) int64: the pivots."""
    f: np.ndarray
    """(n,): the right-hand side at a stage."""
    ft: np.ndarray
    """(n,): df/ds."""
    ys: np.ndarray
    """(n,): a stage's state."""


@njit(cache=True)
def scratch(n):
    """A :class:`RodasWork` for a system of size n (compiled, so that kernels can call it)."""
    return RodasWork(np.empty((4, n)), np.empty((n, n)), np.empty(n, np.int64), np.empty(n), np.empty(n), np.empty(n))


@njit(inline="always", fastmath={"contract": True}, error_model="numpy")
def _factor(M, piv):
    """LU factorisation of M in place with partial pivoting (Doolittle); False if singular."""
    n = M.shape[0]
    for c in range(n):
        p = c
        for r in range(c + 1, n):
            if abs(M[r, c]) > abs(M[p, c]):
                p = r
        piv[c] = p
        if M[p, c] == 0.0 or not np.isfinite(M[p, c]):
            return False
        if p != c:
            for j in range(n):
                M[c, j], M[p, j] = M[p, j], M[c, j]
        for r in range(c + 1, n):
            M[r, c] /= M[c, c]
            for j in range(c + 1, n):
                M[r, j] -= M[r, c] * M[c, j]
    return True


@njit(inline="always", fastmath={"contract": True}, error_model="numpy")
def _solve(M, piv, x):
    """Solve (LU) x = b in place, x holding b on entry."""
    n = M.shape[0]
    for c in range(n):
        p = piv[c]
        if p != c:
            x[c], x[p] = x[p], x[c]
    for r in range(1, n):
        for j in range(r):
            x[r] -= M[r, j] * x[j]
    for r in range(n - 1, -1, -1):
        for j in range(r + 1, n):
            x[r] -= M[r, j] * x[j]
        x[r] /= M[r, r]


def make_rodas3_step(system):
    """step(s, y, h, p, y_new, err, work) -> bool: one RODAS3 step of size h of ``system`` (module docstring) from
    y at s, with the scratch arrays ``work`` (:class:`RodasWork`); writes the new state into y_new and the embedded
    error estimate into err; False if the matrix was singular or not finite (the caller retries with a smaller h)."""

    @njit(fastmath={"contract": True}, error_model="numpy")
    def step(s, y, h, p, y_new, err, work):
        K, M, piv, f, ft, ys = work
        n = y.size
        system(s, y, p, f, M, ft, True)
        d = 1.0 / (h * _GAM)
        for i in range(n):
            for j in range(n):
                M[i, j] = -M[i, j]
            M[i, i] += d
        if not _factor(M, piv):
            return False
        for i in range(n):  # stage 1
            K[0, i] = f[i] + _G1 * h * ft[i]
        _solve(M, piv, K[0])
        if not _SAME_F2:  # stage 2
            for i in range(n):
                ys[i] = y[i] + _A21 * K[0, i]
            system(s + _AL2 * h, ys, p, f, M, ft, False)
        for i in range(n):
            K[1, i] = f[i] + _C21 * K[0, i] / h + _G2 * h * ft[i]
        _solve(M, piv, K[1])
        for i in range(n):  # stage 3
            ys[i] = y[i] + _A31 * K[0, i] + _A32 * K[1, i]
        system(s + _AL3 * h, ys, p, f, M, ft, False)
        for i in range(n):
            K[2, i] = f[i] + (_C31 * K[0, i] + _C32 * K[1, i]) / h + _G3 * h * ft[i]
        _solve(M, piv, K[2])
        for i in range(n):  # stage 4
            ys[i] = y[i] + _A41 * K[0, i] + _A42 * K[1, i] + _A43 * K[2, i]
        system(s + _AL4 * h, ys, p, f, M, ft, False)
        for i in range(n):
            K[3, i] = f[i] + (_C41 * K[0, i] + _C42 * K[1, i] + _C43 * K[2, i]) / h + _G4 * h * ft[i]
        _solve(M, piv, K[3])
        for i in range(n):
            y_new[i] = y[i] + _M1 * K[0, i] + _M2 * K[1, i] + _M3 * K[2, i] + _M4 * K[3, i]
            err[i] = _E1 * K[0, i] + _E2 * K[1, i] + _E3 * K[2, i] + _E4 * K[3, i]
        return True

    return pin(step, system.py_func.__module__, system.py_func.__name__)


pin_module(__name__)
