"""State laws: how the contact age evolves (docs/physics.md 7). One function per law, chosen by name.

Every law is written as the rate of u = ln psi in reduced time tau, from the slip velocity xi' and ln E, where
E = xi' psi (so ln E = ln xi' + u):

    aging (the paper's eq. 2, Dieterich):   u' = e^-u - xi'            (psi' = 1 - xi' psi)
    slip  (Ruina 1983):                      u' = -xi' ln E             (psi' = -xi' psi ln(xi' psi))

The models compose a law into their right-hand sides at compile time (:mod:`sweep.integrate.models.stop`,
:mod:`sweep.integrate.models.driven`). Both laws have the same steady state (E = 1) and the same linearisation about
steady
sliding, so the same Hopf line. The aging law alone has the identity xi + u = s in contact-age time s, which the
fast stop paths (one state, closed-form tail, lanes) rely on.

:data:`STATE_LAWS` is the registry the package dispatches on: a law's entry (:class:`StateLaw`) holds its rate, whether
it has the aging identity (the fast stop paths), which kernel family computes its stop's relaxed slip (None: the stop
protocol refuses it), whether an inertial model exists for it, and where its relaxed slip is finite. Adding a law: a
function here and an entry in :data:`STATE_LAWS` (:func:`register`); the driven scene and the Hopf line then accept
it (quasi-static), and each protocol refuses what it cannot run with the list of what it can.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ...jitcache import pin_module
from ..solvers.fastmath import FAST
from ..solvers.vmath import EXP_MAX

__all__ = ["STATE_LAWS", "StateLaw", "aging", "register", "slip"]


@njit(inline="always", fastmath=FAST, error_model="numpy")
def aging(xi_dot, u, ln_E):
    """u' of the aging law: e^-u - xi' (the age grows at rest, psi' = 1; e^-u clamped at e^EXP_MAX)."""
    return math.exp(min(-u, EXP_MAX)) - xi_dot


@njit(inline="always", fastmath=FAST, error_model="numpy")
def slip(xi_dot, u, ln_E):
    """u' of the slip law: -xi' ln E (the state evolves only with slip: no healing at rest)."""
    return -xi_dot * ln_E


@dataclass(frozen=True)
class StateLaw:
    """One state law's entry in :data:`STATE_LAWS`."""

    name: str
    rate: object
    """The compiled u' = f(xi', u, ln E) (inlined into the right-hand sides that compose it)."""
    aging_identity: bool
    """xi + u = s in contact-age time s: the stop's one-state paths, closed-form tail and lanes apply."""
    stop_family: str | None
    """The kernel family that computes the stop's relaxed slip (sweep.run.compile_notice.COLD_COMPILE_S); None: no
    stop kernel, the stop protocol refuses the law."""
    inertial: bool
    """An inertial model exists for the law (stop and driven)."""
    finite_at_zero_m2: bool
    """The relaxed slip is finite for m2 = 0 with mu1 > 0 (always finite for m2 > 0, never for m2 < 0)."""

    def finite_relaxed_slip(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Where the relaxed slip is finite, from a = mu1/A and b = m2/A (docs/physics.md 6 and 7.3)."""
        if self.finite_at_zero_m2:
            return (b > 0) | ((b == 0) & (a > 0))
        return b > 0


STATE_LAWS: dict[str, StateLaw] = {
    "aging": StateLaw("aging", aging, aging_identity=True, stop_family="relaxed-slip engine", inertial=True,
                      finite_at_zero_m2=True),
    "slip": StateLaw("slip", slip, aging_identity=False, stop_family="slip-law stop", inertial=False,
                     finite_at_zero_m2=False),
}
"""Every state law by name (Scene.state_law)."""


def register(law: StateLaw) -> None:
    """Add ``law`` to :data:`STATE_LAWS` (a built-in law cannot be replaced)."""
    if law.name in STATE_LAWS and STATE_LAWS[law.name] != law:
        raise ValueError(f"state law {law.name!r} is already registered")
    STATE_LAWS[law.name] = law

pin_module(__name__)
