"""Quasi-static stop with the slip law (docs/physics.md 7): the general formulation, without the aging identity.

With the slip law the contact-age time s no longer ties u = ln psi to xi (aging: xi + u = s), so the state has two
components. The relaxed slip is a property of the phase plane alone: with E = xi' psi,

    dxi/ds = E,    du/ds = -E ln E    =>    du/dxi = L(xi, u) = k xi + a u + b u^2      (k = chi/A, a = mu1/A,
                                                                                         b = m2/A)

L >= 0 along the solution from (0, 0) (where L = 0 its rate is k > 0), so u never decreases; for b > 0 it blows up
at a finite xi, and that xi is xi_inf (for b <= 0 there is no finite limit: docs/physics.md 7.3). Two right-hand
sides, both autonomous with the independent variable as state 0 (rate 1):

* :func:`phase_rhs`: y = (xi, u), dy = (1, L), from the start until u is large;
* :func:`inverse_rhs`: the blow-up mapped to a finite end with t = 1/u: dxi/dt = -1/(b + a t + k xi t^2), regular
  at t = 0 while b + a t > 0 (guaranteed by the hand-over point, :func:`handover_u`); y = (r, xi) with
  r = t_e - t running from 0 to t_e = 1/u_e, so that xi at r = t_e is xi_inf exactly.
"""

from __future__ import annotations

from typing import NamedTuple

from numba import njit

from ...jitcache import pin_module
from ..solvers.fastmath import FAST

__all__ = ["SlipStopParams", "handover_u", "inverse_rhs", "phase_rhs"]


class SlipStopParams(NamedTuple):
    """Reduced parameters of one slip-law stop point; ``t_e`` = 1/u at the hand-over (0 before it)."""

    k: float
    a: float
    b: float
    t_e: float


@njit(fastmath=FAST, error_model="numpy")
def phase_rhs(y, p, dy):
    """(dxi/dxi, du/dxi) = (1, L) at y = (xi, u); returns L."""
    L = p.k * y[0] + y[1] * (p.a + p.b * y[1])
    dy[0], dy[1] = 1.0, L
    return L


@njit(fastmath=FAST, error_model="numpy")
def inverse_rhs(y, p, dy):
    """(dr/dr, dxi/dr) = (1, 1/(b + a t + k xi t^2)) at y = (r, xi), t = t_e - r; returns the denominator."""
    t = p.t_e - y[0]
    d = p.b + t * (p.a + p.k * y[1] * t)
    dy[0], dy[1] = 1.0, 1.0 / d
    return d


@njit(cache=True)
def handover_u(a, b):
    """u at which the phase-plane integration hands over to t = 1/u: b u^2 at least twice |a| u there (so
    b + a t >= b/2 > 0 from there on) and u >= 1."""
    return max(1.0, 2.0 * abs(a) / b)


pin_module(__name__)
