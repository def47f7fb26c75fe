"""Driven scene (docs/physics.md 3b): the right-hand sides, quasi-static or inertial, for any state law.

The drive keeps moving at V. In reduced time tau, with the spring stretch z = tau - xi and u = ln psi,

    A ln(xi' psi) = chi z - dmu(psi)   =>   w = ln xi' = (chi z - mu1 u - m2 u^2)/A - u,
    z' = 1 - e^w,    u' = state law (aging: e^-u - e^w; slip: -e^w (w + u); sweep/integrate/models/state_laws.py),

an autonomous system in (z, u) whose fixed point z = u = 0 is steady sliding. The log-velocity w is a function of
the state, so the slip velocity is never a state variable: stick phases (w << 0) and slip phases (w >> 0) are the
same smooth equations.

With inertia (gamma = V^2/(g D0) > 0) the Newton equation gamma xi'' = chi z - dmu(psi) - A ln(xi' psi) makes
w = ln xi' a third state, w' = ((chi z - dmu)/A - u - w) e^-w A/gamma, relaxing at the rate A/(gamma xi')
(:func:`stiffness`): stiff for small gamma/A and in the stick phases of stick-slip. :func:`inertial_system` gives
the analytic 3x3 Jacobian (aging law) for the Rosenbrock steps the driver takes there (sweep/integrate/driven.py).

Parameters travel as a :class:`DrivenParams` record: k = chi/A, a = mu1/A, b = m2/A, g = gamma/A (0: quasi-static).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

from ...jitcache import pin, pin_module
from ..solvers.fastmath import FAST
from ..solvers.vmath import EXP_MAX

__all__ = ["DrivenParams", "inertial_system", "log_velocity_rate", "make_driven_rhs", "make_slaved_rhs", "stiffness"]


class DrivenParams(NamedTuple):
    """Reduced parameters of one driven point."""

    k: float
    """chi/A, reduced stiffness over A."""
    a: float
    """mu1(V)/A."""
    b: float
    """m2/A."""
    g: float
    """gamma/A (0 for the quasi-static model)."""


def make_driven_rhs(law, inertia: bool = False):
    """rhs(y, p, dy) -> ln xi' of the driven equations with the state law ``law``
    (sweep/integrate/models/state_laws.py).
    Quasi-static (``inertia`` False, p.g = 0): the state is y = (z, u) and ln xi' is the force balance
    k z - a u - b u^2 - u itself. Inertial (p.g > 0): y = (z, u, w), w = ln xi' a state with
    w' = (balance - w) e^-w / g. Exponents are clamped at EXP_MAX (an overflowing stage is rejected by the driver's
    error test instead)."""
    if inertia:

        @njit(fastmath=FAST, error_model="numpy")
        def rhs(y, p, dy):
            z, u, w = y[0], y[1], y[2]
            balance = p.k * z - u * (p.a + p.b * u) - u
            e = math.exp(min(w, EXP_MAX))
            dy[0], dy[1], dy[2] = 1.0 - e, law(e, u, w + u), (balance - w) * math.exp(min(-w, EXP_MAX)) / p.g
            return w

    else:

        @njit(fastmath=FAST, error_model="numpy")
        def rhs(y, p, dy):
            z, u = y[0], y[1]
            lw = p.k * z - u * (p.a + p.b * u) - u
            e = math.exp(min(lw, EXP_MAX))
            dy[0], dy[1] = 1.0 - e, law(e, u, lw + u)
            return lw

    return pin(rhs, law.py_func.__name__, "inertial" if inertia else "quasistatic")


def make_slaved_rhs(law):
    """rhs(y, p, dy) -> w of the inertial equations (p.g > 0, aging law: the one with an inertial model) on their
    slow manifold, to second order in the inertial term P = gamma xi''/A = g e^w w' = balance - w. Where the stiff
    mode relaxes far faster than the slow ones, w is a function of (z, u) (the manifold) with
    g e^w (w_z z' + w_u u') = balance - w, solved by iteration from w0 = balance (each iterate one order of g closer):

        w1 = balance - g e^w0 D0,               D0 = dw0/dtau = k z' - c u'  at w0,      c = a + 2 b u + 1,
        w2 = balance - g e^w1 D1,               D1 = dw1/dtau = w1_z z' + w1_u u'  at w1,

    with w1_z = k - g e^w0 (k D0 + dD0/dz), w1_u = -c - g e^w0 (-c D0 + dD0/du) (z' = 1 - e^w, u' = e^-u - e^w).
    w2 is off the manifold by O(P^3) (w1 by O(P^2): the first-order form allowed |P| <= 3e-4..1e-3 within 3e-8 of
    the full system, the second 1e-2, :data:`sweep.accuracy.SLAVED_INERTIA`). y = (z, u, w) as in the inertial model,
    but w is no state here: dy[2] = 0 and the driver writes the returned w into y[2] after each accepted step
    (sweep/integrate/driven.py). The same explicit stepper as the quasi-static model then runs the stick phases and
    the slip's ends, where the full system would need RODAS3 at h A/(gamma xi') up to 1e14, or dp5 held at its
    stability limit."""
    if law.py_func.__name__ != "aging":
        raise ValueError(f"the slaved inertial form is written for the aging law, not {law.py_func.__name__!r}")

    @njit(fastmath=FAST, error_model="numpy")
    def rhs(y, p, dy):
        k, a, b, g = p.k, p.a, p.b, p.g
        z, u = y[0], y[1]
        w0 = k * z - u * (a + b * u) - u
        c = a + 2.0 * b * u + 1.0
        e0, e_u = math.exp(min(w0, EXP_MAX)), math.exp(min(-u, EXP_MAX))
        du0 = e_u - e0  # u' at w0
        d0 = k * (1.0 - e0) - c * du0
        d0_z = k * e0 * (c - k)
        d0_u = k * c * e0 - 2.0 * b * du0 + c * e_u - c * c * e0
        w1 = w0 - g * e0 * d0
        w1_z = k - g * e0 * (k * d0 + d0_z)
        w1_u = -c - g * e0 * (d0_u - c * d0)
        e1 = math.exp(min(w1, EXP_MAX))
        w = w0 - g * e1 * (w1_z * (1.0 - e1) + w1_u * (e_u - e1))
        e = math.exp(min(w, EXP_MAX))
        dy[0], dy[1], dy[2] = 1.0 - e, e_u - e, 0.0
        return w

    return pin(rhs, law.py_func.__name__, "slaved")


@njit(inline="always", fastmath=FAST, error_model="numpy")
def log_velocity_rate(y, dy, p):
    """d(ln xi')/dtau at state y with rates dy: the balance's rate k z' - (a + 2 b u) u' - u' (quasi-static, p.g = 0),
    the state's own rate w' (inertial)."""
    if p.g == 0.0:
        return p.k * dy[0] - (p.a + 2.0 * p.b * y[1]) * dy[1] - dy[1]
    return dy[2]


@njit(inline="always", fastmath=FAST, error_model="numpy")
def inertial_system(s, y, p, f, J, ft, jacobian):
    """The inertial driven equations (aging law, p.g > 0) with their Jacobian in (z, u, w), for the stiff phases
    (:func:`sweep.integrate.solvers.rosenbrock_step.make_rodas3_step`; autonomous: df/dtau = 0)."""
    k, a, b, g = p
    z, u, w = y[0], y[1], y[2]
    balance = k * z - u * (a + b * u) - u
    e, e_u, c = math.exp(min(w, EXP_MAX)), math.exp(min(-u, EXP_MAX)), math.exp(min(-w, EXP_MAX)) / g
    f[0], f[1], f[2] = 1.0 - e, e_u - e, (balance - w) * c
    if jacobian:
        J[0, 0], J[0, 1], J[0, 2] = 0.0, 0.0, -e
        J[1, 0], J[1, 1], J[1, 2] = 0.0, -e_u, -e
        J[2, 0], J[2, 1], J[2, 2] = k * c, -(a + 2.0 * b * u + 1.0) * c, -(1.0 + balance - w) * c
        ft[0], ft[1], ft[2] = 0.0, 0.0, 0.0


@njit(inline="always", fastmath=FAST, error_model="numpy")
def stiffness(y, p):
    """|dw'/dw| of the inertial equations: the rate of the stiff mode A/(gamma xi') (0 without inertia)."""
    if p.g == 0.0:
        return 0.0
    z, u, w = y[0], y[1], y[2]
    balance = p.k * z - u * (p.a + p.b * u) - u
    return abs(1.0 + balance - w) * math.exp(min(-w, EXP_MAX)) / p.g


pin_module(__name__)
