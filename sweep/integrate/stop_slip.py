"""Relaxed slip of the quasi-static stop with the slip law (docs/physics.md 7.3): the general two-state path.

Model x stepper x controller: the phase-plane right-hand sides of :mod:`sweep.integrate.models.stop_slip`, dp5 with
the PI
controller through the generic adaptive march (:mod:`sweep.integrate.adaptive`). Phase 1 integrates du/dxi = L
from (0, 0) until u passes :func:`sweep.integrate.models.stop_slip.handover_u`; phase 2 integrates xi in t = 1/u to t
= 0,
where xi is xi_inf. Each point is solved at local tolerances rtol/TIGHTER, rtol/TIGHTER^2 and rtol/TIGHTER^3
(sweep/accuracy.py): the middle value is returned with the estimate GENERAL_ESTIMATE_GAIN x the larger difference to
its neighbours. (The pair alone, |x(rtol/10) - x(rtol/100)|, underestimated where the runs take a few tens of
steps and their errors are not yet proportional to the tolerance: 0.43x the true error at chi/A = 8.5,
mu1/A = -0.24, m2/A = 0.12, rtol 1e-6; tests/integrate/test_slip_law.py.) None of the aging law's fast paths (one
state, closed-form tail, lanes, step ladder) applies.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..jitcache import pin_module
from ..status import Status
from .adaptive import make_march
from .models.stop_slip import SlipStopParams, handover_u, inverse_rhs, phase_rhs
from .solvers import DP5
from .solvers.controllers import PI_CONTROLLER

__all__ = ["relax_slip"]

OK, NO_FINITE_LIMIT = int(Status.OK), int(Status.NO_FINITE_LIMIT)
H_START = 1e-3
"""First trial step in xi of phase 1, times 1/(1 + k + |a|) (the fastest rate of the start)."""

_phase = make_march(phase_rhs, 2, DP5, PI_CONTROLLER)
_inverse = make_march(inverse_rhs, 2, DP5, PI_CONTROLLER)


@njit(cache=True)
def relax_slip(k, a, b, rtol, atol, max_steps):
    """(xi_inf, status, steps) of one point at local tolerance rtol (absolute floor atol); NaN unless ok."""
    if not b > 0.0:
        return math.nan, NO_FINITE_LIMIT, 0
    y = np.zeros(2)
    p = SlipStopParams(k, a, b, 0.0)
    status, steps, h = _phase(y, p, H_START / (1.0 + k + abs(a)), 1, handover_u(a, b), rtol, atol, max_steps)
    if status != OK:
        return math.nan, status, steps
    t_e = 1.0 / y[1]
    z = np.zeros(2)
    z[1] = y[0]
    status2, steps2, _ = _inverse(z, SlipStopParams(k, a, b, t_e), 0.1 * t_e, 0, t_e, rtol, atol, max_steps - steps)
    return (z[1] if status2 == OK else math.nan), status2, steps + steps2



pin_module(__name__)
