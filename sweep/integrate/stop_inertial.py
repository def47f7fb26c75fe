"""Stop scene with inertia, and the first-order inertial correction of the quasi-static model: the driver.

Model x stepper x controller: the systems of :mod:`sweep.integrate.models.stop_inertial` (docs/physics.md 3a) with their
analytic Jacobians, the RODAS3 step of :mod:`sweep.integrate.solvers.rosenbrock_step`, the elementary controller of
:mod:`sweep.integrate.solvers.controllers`; inertia is handed over to the quasi-static form once negligible
(HANDOVER_FRACTION rtol, sweep/accuracy.py), and the quasi-static phase ends in the closed-form tail.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..accuracy import HANDOVER_FRACTION
from ..jitcache import pin_module
from ..status import Status
from .models.stop import tail_is_accurate, tail_slip
from .models.stop_inertial import inertia_negligible, inertial_system, quasistatic_system, tail_correction
from .solvers import RODAS3
from .solvers.controllers import I_CONTROLLER, MIN_FACTOR, accepted_factor, rejected_factor
from .solvers.fastmath import FAST
from .solvers.rosenbrock_step import make_rodas3_step, scratch

__all__ = ["relax", "RELAX_KEYS"]

RELAX_KEYS = ("xi_inf", "correction", "status", "steps", "s_handover")
"""The outputs of :func:`relax_points`."""

OK, MAX_STEPS, NONFINITE = int(Status.OK), int(Status.MAX_STEPS), int(Status.NONFINITE)
STEP_UNDERFLOW = int(Status.STEP_UNDERFLOW)
H_START = 1e-3
"""First step in s, times min(1, G, 1/k): the initial layer lasts s ~ G, the stiff start 1/k."""
H_FLOOR = 8.0 * 2.220446049250313e-16
"""Smallest step in s, relative to s, before a point is flagged step_underflow (a few ulps: below it s + h
stops moving). Relative, not absolute: where a fast rebound (k/G large) drops xi' towards 0, ln(xi' psi) has a
log singularity that the steps resolve down to ~1e-16 near s ~ 0.05, and then grow again."""
CONTROLLER = I_CONTROLLER._replace(nonfinite_factor=MIN_FACTOR)
"""The elementary controller of sweep/integrate/solvers/controllers.py (a stage that overflowed: the step is divided
by 5)."""
ORDER = RODAS3.order_hat
"""Order of RODAS3's embedded error estimate (the controller's exponent is 1/(ORDER + 1))."""

inertial_step = make_rodas3_step(inertial_system)
quasistatic_step = make_rodas3_step(quasistatic_system)


@njit(cache=True, fastmath=FAST, error_model="numpy")
def relax(k, a, b, G, inertial, rtol, atol, max_steps):
    """Relaxed slip of one stop point with the inertial model (``inertial``) or the quasi-static one with its
    first-order inertial correction; k = chi/A, a = mu1/A, b = m2/A, G = gamma/A > 0.

    Returns (xi_inf, y_inf, status, steps, s_handover): y_inf the first-order correction (0 for the inertial model),
    s_handover the contact-age time at which inertia was dropped (0 for the quasi-static model).
    """
    y, y_new, err_v = np.zeros(2), np.empty(2), np.empty(2)  # (xi, q) inertial, (xi, y) quasi-static
    work = scratch(2)
    s = 0.0
    phase_inertial = inertial
    p_inertial, p_quasi = (k, a, b, G), (k, a, b, 0.0 if inertial else G)
    h = H_START * min(1.0, G, 1.0 / k)
    eps = HANDOVER_FRACTION * rtol
    s_handover = 0.0
    steps, err_prev, rejected = 0, 1.0, False
    while steps < max_steps:
        steps += 1
        if phase_inertial:
            done = inertial_step(s, y, h, p_inertial, y_new, err_v, work)
            err2 = abs(err_v[1]) / rtol
        else:
            done = quasistatic_step(s, y, h, p_quasi, y_new, err_v, work)
            err2 = abs(err_v[1]) / (rtol * max(abs(y[1]), abs(y_new[1])) + atol * G)
        err = max(abs(err_v[0]) / (rtol * max(abs(y[0]), abs(y_new[0])) + atol), err2)
        if not (done and math.isfinite(err) and math.isfinite(y_new[0]) and math.isfinite(y_new[1])):
            h *= rejected_factor(CONTROLLER, math.nan, ORDER)  # an overflow in a stage: retry smaller
            rejected = True
            if h < H_FLOOR * s:
                return math.nan, math.nan, NONFINITE, steps, s_handover
            continue
        if err > 1.0:
            h *= rejected_factor(CONTROLLER, err, ORDER)
            rejected = True
            if h < H_FLOOR * s:
                return math.nan, math.nan, STEP_UNDERFLOW, steps, s_handover
            continue
        s += h
        y[0], y[1] = y_new[0], y_new[1]
        factor, err_prev = accepted_factor(CONTROLLER, err, err_prev, ORDER, rejected)
        h *= factor
        rejected = False
        xi = y[0]
        if phase_inertial:
            if inertia_negligible(s, xi, y[1], k, a, b, G, eps):
                phase_inertial, y[1], s_handover = False, 0.0, s
            continue
        u = s - xi
        E = math.exp(-(k * xi + u * (a + b * u)))
        if tail_is_accurate(k, a, b, u, E, rtol * xi + atol):
            return (xi + tail_slip(k, a, b, u, E), tail_correction(k, a, b, p_quasi[3], u, E, y[1]), OK, steps,
                    s_handover)
    return math.nan, math.nan, MAX_STEPS, steps, s_handover


pin_module(__name__)
