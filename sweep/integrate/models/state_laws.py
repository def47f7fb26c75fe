"""State laws: how the contact age evolves (docs/physics.md 7). One function per law, chosen by name.

Every law is written as the rate of u = ln psi in reduced time tau, from the slip velocity xi' and ln E, where
E = xi' psi (so ln E = ln xi' + u):

    aging (the paper's eq. 2, Dieterich):   u' = e^-u - xi'            (psi' = 1 - xi' psi)
    slip  (Ruina 1983):                      u' = -xi' ln E             (psi' = -xi' psi ln(xi' psi))

The models compose a law into their right-hand sides at compile time (:mod:`sweep.integrate.models.stop`,
:mod:`sweep.integrate.models.driven`). Both laws have the same steady state (E = 1) and the same linearisation about steady
sliding, so the same Hopf line. The aging law alone has the identity xi + u = s in contact-age time s, which the
fast stop paths (one state, closed-form tail, lanes) rely on.

Adding a law: a function here, an entry in :data:`STATE_LAWS`, and the scene accepts its name.
"""

from __future__ import annotations

import math

from numba import njit

from ...jitcache import pin_module
from ..solvers.fastmath import FAST
from ..solvers.vmath import EXP_MAX

__all__ = ["STATE_LAWS", "aging", "slip"]


@njit(inline="always", fastmath=FAST, error_model="numpy")
def aging(xi_dot, u, ln_E):
    """u' of the aging law: e^-u - xi' (the age grows at rest, psi' = 1; e^-u clamped at e^EXP_MAX)."""
    return math.exp(min(-u, EXP_MAX)) - xi_dot


@njit(inline="always", fastmath=FAST, error_model="numpy")
def slip(xi_dot, u, ln_E):
    """u' of the slip law: -xi' ln E (the state evolves only with slip: no healing at rest)."""
    return -xi_dot * ln_E


STATE_LAWS = {"aging": aging, "slip": slip}
"""Every state law by name (Scene.state_law)."""

pin_module(__name__)
