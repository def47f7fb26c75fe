"""Stop scene with inertia, and the first-order inertial correction of the quasi-static model: the driver.

Model x stepper x controller: the systems of :mod:`sweep.integrate.models.stop_inertial` (docs/physics.md 3a) with their
analytic Jacobians, the RODAS3 step of :mod:`sweep.integrate.solvers.rosenbrock_step`, the elementary controller of
:mod:`sweep.integrate.solvers.controllers`. The inertial phase steps the state (s, xi, q) in the plunge-resolving time
sigma (ds/dsigma = w <= 1, the model's docstring), so that the end of an inertial swing, where xi' falls by up to
e^(-sqrt(chi gamma)/A) in a span of s far below the resolution of s, takes a few hundred steps instead of a step
underflow; inertia is handed over to the quasi-static form once negligible (HANDOVER_FRACTION rtol,
sweep/accuracy.py), which steps xi in s and ends in the closed-form tail.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..accuracy import HANDOVER_FRACTION
from ..jitcache import pin_module
from ..status import Status
from .models.stop import tail_is_accurate, tail_slip
from .models.stop_inertial import (
    PLUNGE_WEIGHT,
    S_WEIGHT,
    inertia_negligible,
    inertial_system,
    quasistatic_system,
    tail_correction,
    time_rate,
)
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
"""First step in sigma (= s at the start, where w = 1), times min(1, G, 1/k): the initial layer lasts s ~ G, the
stiff start 1/k."""
H_FLOOR = 8.0 * 2.220446049250313e-16
"""A few ulps. Quasi-static phase: the smallest step in s, relative to s, before a point is flagged step_underflow
(below it s + h stops moving). Inertial phase: a rejected step that moves no state by more than this (relative;
:func:`stalled`) flags it; the size of the step in sigma says nothing there (the system is autonomous in sigma)."""
CONTROLLER = I_CONTROLLER._replace(nonfinite_factor=MIN_FACTOR)
"""The elementary controller of sweep/integrate/solvers/controllers.py (a stage that overflowed: the step is divided
by 5)."""
ORDER = RODAS3.order_hat
"""Order of RODAS3's embedded error estimate (the controller's exponent is 1/(ORDER + 1))."""

inertial_step = make_rodas3_step(inertial_system)
quasistatic_step = make_rodas3_step(quasistatic_system)


@njit(inline="always", fastmath=FAST, error_model="numpy")
def stalled(z, z_new):
    """Whether a rejected step of the inertial phase from z = (s, xi, q) to z_new moved no state by more than
    H_FLOOR relative (q relative to max(|q|, 1)): a step too small to move the state it is to resolve."""
    return (abs(z_new[0] - z[0]) <= H_FLOOR * abs(z[0]) and abs(z_new[1] - z[1]) <= H_FLOOR * abs(z[1])
            and abs(z_new[2] - z[2]) <= H_FLOOR * max(abs(z[2]), 1.0))


@njit(cache=True, fastmath=FAST, error_model="numpy")
def relax(k, a, b, G, inertial, rtol, atol, max_steps):
    """Relaxed slip of one stop point with the inertial model (``inertial``) or the quasi-static one with its
    first-order inertial correction; k = chi/A, a = mu1/A, b = m2/A, G = gamma/A > 0.

    Returns (xi_inf, y_inf, status, steps, s_handover): y_inf the first-order correction (0 for the inertial model),
    s_handover the contact-age time at which inertia was dropped (0 for the quasi-static model).
    """
    z, z_new, err_z = np.zeros(3), np.empty(3), np.empty(3)  # inertial phase: (s, xi, q) in sigma
    y, y_new, err_v = np.zeros(2), np.empty(2), np.empty(2)  # quasi-static phase: (xi, y) in s
    work3, work2 = scratch(3), scratch(2)
    s, sigma = 0.0, 0.0
    phase_inertial = inertial
    p_inertial, p_quasi = (k, a, b, G, PLUNGE_WEIGHT, S_WEIGHT), (k, a, b, 0.0 if inertial else G)
    h = H_START * min(1.0, G, 1.0 / k)  # in sigma = s at the start (w = 1 there)
    eps = HANDOVER_FRACTION * rtol
    s_handover = 0.0
    steps, err_prev, rejected = 0, 1.0, False
    while steps < max_steps:
        steps += 1
        if phase_inertial:
            done = inertial_step(0.0, z, h, p_inertial, z_new, err_z, work3)  # autonomous
            err = max(abs(err_z[0]) / (rtol * max(z[0], z_new[0]) + atol),
                      abs(err_z[1]) / (rtol * max(abs(z[1]), abs(z_new[1])) + atol), abs(err_z[2]) / rtol)
            finite = math.isfinite(z_new[0]) and math.isfinite(z_new[1]) and math.isfinite(z_new[2])
            t = sigma  # the sigma spent so far: the scale of the floor of a step whose stages overflowed
        else:
            done = quasistatic_step(s, y, h, p_quasi, y_new, err_v, work2)
            err2 = abs(err_v[1]) / (rtol * max(abs(y[1]), abs(y_new[1])) + atol * G)
            err = max(abs(err_v[0]) / (rtol * max(abs(y[0]), abs(y_new[0])) + atol), err2)
            finite = math.isfinite(y_new[0]) and math.isfinite(y_new[1])
            t = s
        if not (done and math.isfinite(err) and finite):
            h *= rejected_factor(CONTROLLER, math.nan, ORDER)  # an overflow in a stage: retry smaller
            rejected = True
            if h < H_FLOOR * t:
                return math.nan, math.nan, NONFINITE, steps, s_handover
            continue
        if err > 1.0:
            h *= rejected_factor(CONTROLLER, err, ORDER)
            rejected = True
            if (stalled(z, z_new) if phase_inertial else h < H_FLOOR * s):
                return math.nan, math.nan, STEP_UNDERFLOW, steps, s_handover
            continue
        factor, err_prev = accepted_factor(CONTROLLER, err, err_prev, ORDER, rejected)
        rejected = False
        if phase_inertial:
            sigma += h
            h *= factor
            z[0], z[1], z[2] = z_new[0], z_new[1], z_new[2]
            if inertia_negligible(z[0], z[1], z[2], k, a, b, G, eps):
                phase_inertial, s_handover = False, z[0]
                s, y[0], y[1] = z[0], z[1], 0.0
                h *= time_rate(z, p_inertial)  # the next step in s: the last one's span in s
            continue
        s += h
        h *= factor
        y[0], y[1] = y_new[0], y_new[1]
        xi = y[0]
        u = s - xi
        E = math.exp(-(k * xi + u * (a + b * u)))
        if tail_is_accurate(k, a, b, u, E, rtol * xi + atol):
            return (xi + tail_slip(k, a, b, u, E), tail_correction(k, a, b, p_quasi[3], u, E, y[1]), OK, steps,
                    s_handover)
    return math.nan, math.nan, MAX_STEPS, steps, s_handover


pin_module(__name__)
