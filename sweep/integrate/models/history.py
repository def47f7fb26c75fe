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
"""

from __future__ import annotations

import math

from numba import njit

from ...jitcache import pin_module
from ..solvers.fastmath import FAST
from ..solvers.vmath import EXP_MAX

__all__ = ["AGING", "SLIP", "LAW_CODES", "history_rates", "steady_state"]

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
def steady_state(r, a, b):
    """(s, u) of steady sliding at the load-point velocity r V (r > 0): u = -ln r, s = -a ln r + b (ln r)^2."""
    lr = math.log(r)
    return -a * lr + b * lr * lr, -lr


pin_module(__name__)
