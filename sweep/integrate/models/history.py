"""Load-history scene (docs/physics.md, "Load histories"): the quasi-static right-hand side under a piecewise-constant
load-point velocity, for the aging and the slip law.

Reduced as in the driven scene (xi = x/D0, tau = V t/D0, psi = V phi/D0, u = ln psi, V the grid's velocity), with the
load point moving at r V (r = the segment's ``V_ratio``) and the friction measured from the steady state at V in
units of A, s = (mu - mu_d(V))/A = chi z/A (z the reduced spring stretch beyond its length at rest):

    force balance (paper eq. 1, 6, quasi-static):  w = ln xi' = s - a u - b u^2 - u,    a = mu1(V)/A, b = m2/A
    spring (dmu/dt = k_lab (v_lp - v), k_lab = K/(M g)):   s' = k (r - e^w),             k = chi/A
    state law (sweep/integrate/models/state_laws.py):       aging u' = e^-u - e^w;  slip u' = -e^w (w + u)

Steady sliding at r V: u = -ln r, w = ln r, s = -a ln r + b (ln r)^2. The log-velocity w is a function of the state,
so a hold (r = 0, w -> -inf) and a reslide are the same smooth equations.

With inertia (G = gamma/A > 0, gamma = V^2/(g D0); Newton's law M x'' = K (x_lp - x) - M g mu(x', phi), PHYSICS.md 7)
s is the spring's force, the friction the laboratory measures, and the slider's friction lags it by the inertial
term: G xi'' = s - a u - b u^2 - u - w = P, so w = ln xi' becomes a third state,

    w' = P e^-w / G,    s' = k (r - e^w),    u' = e^-u - e^w (aging)

relaxing at the rate e^-w/G (stiff for small G and at small slip velocity, in every hold):
:func:`inertial_history_system` gives the rates and the analytic Jacobian for Rosenbrock steps.
"""

from __future__ import annotations

import math

from numba import njit

from ...jitcache import pin_module
from ..solvers.fastmath import FAST
from ..solvers.vmath import EXP_MAX

__all__ = ["AGING", "SLIP", "LAW_CODES", "history_rates", "inertial_history_system", "steady_state"]

AGING, SLIP = 0, 1
LAW_CODES = {"aging": AGING, "slip": SLIP}
"""State law name (Scene.state_law) -> the integer the kernels branch on."""


@njit(inline="always", fastmath=FAST, error_model="numpy")
def history_rates(s, u, r, k, a, b, law):
    """(s', u', w) at the state (s, u) under the load-point velocity ratio r (module docstring; exponents clamped at
    EXP_MAX so that an overflowing stage is rejected by the step's error test instead of raising)."""
    w = s - u * (a + b * u) - u
    e = math.exp(min(w, EXP_MAX))
    ds = k * (r - e)
    if law == SLIP:
        du = -e * (w + u)
    else:
        du = math.exp(min(-u, EXP_MAX)) - e
    return ds, du, w


@njit(inline="always", fastmath=FAST, error_model="numpy")
def inertial_history_system(t, y, p, f, J, ft, jacobian):
    """The inertial history equations (aging law) in y = (s, u, w) with p = (k, a, b, G, r): rates into f and, when
    ``jacobian``, df/dy into J (autonomous: ft = 0), for sweep.integrate.solvers.rosenbrock_step.make_rodas3_step."""
    k, a, b, g, r = p
    s, u, w = y[0], y[1], y[2]
    balance = s - u * (a + b * u) - u
    e, e_u, c = math.exp(min(w, EXP_MAX)), math.exp(min(-u, EXP_MAX)), math.exp(min(-w, EXP_MAX)) / g
    f[0], f[1], f[2] = k * (r - e), e_u - e, (balance - w) * c
    if jacobian:
        J[0, 0], J[0, 1], J[0, 2] = 0.0, 0.0, -k * e
        J[1, 0], J[1, 1], J[1, 2] = 0.0, -e_u, -e
        J[2, 0], J[2, 1], J[2, 2] = c, -(a + 2.0 * b * u + 1.0) * c, -(1.0 + balance - w) * c
        ft[0], ft[1], ft[2] = 0.0, 0.0, 0.0


@njit(inline="always", fastmath=FAST, error_model="numpy")
def steady_state(r, a, b):
    """(s, u) of steady sliding at the load-point velocity r V (r > 0): u = -ln r, s = -a ln r + b (ln r)^2."""
    lr = math.log(r)
    return -a * lr + b * lr * lr, -lr


pin_module(__name__)
