"""Step-size controllers of the adaptive steppers: one rule, its constants named, no growth after a rejection.

A step of error norm ``err`` (<= 1 accepted) from a method whose error estimate has order q is followed by a step
h * factor,

    factor = clip(SAFETY err^(-alpha/(q+1)) err_prev^(beta/(q+1)), MIN_FACTOR, MAX_FACTOR)

with the previous accepted step's norm err_prev: (alpha, beta) = (1, 0) is the elementary (I) controller,
(0.7, 0.4) Gustafsson's PI controller (Hairer & Wanner II, Sec. IV.2; scipy's ``_ivp`` uses the I form with the
same SAFETY and clip). A rejected step is retried with the I factor (err^(-1/(q+1)), at most 1), or with
NONFINITE_FACTOR where a stage left the finite range (no error norm to go by). After a rejection the next step
may not grow (factor <= 1): the rejected size is a measured upper bound (Hairer, Norsett & Wanner I, Sec. II.4;
scipy's ``_ivp`` does the same).

A controller is a :class:`Controller` record of constants (a numba-compatible named tuple, so a kernel reads its
fields by name at no cost); the functions below are inlined into the drivers (:mod:`sweep.integrate`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit

from ...jitcache import pin_module
from .fastmath import FAST
from .vmath import exp_f64

__all__ = ["Controller", "I_CONTROLLER", "PI_CONTROLLER", "accepted_factor", "accepted_factor_log2", "rejected_factor"]

SAFETY = 0.9
"""The step aims at SAFETY^(q+1) of the tolerance: a margin against the next step's error being larger."""
MIN_FACTOR = 0.2
"""Largest shrinking of a step in one go."""
MAX_FACTOR = 5.0
"""Largest growth of a step in one go."""
ERR_FLOOR = 1e-10
"""Error norms below this count as this (a vanishing estimate would ask for an unbounded step)."""
NONFINITE_FACTOR = 0.25
"""Shrinking of a step whose stages left the finite range (an exponent overflowed, or the linear system of a
Rosenbrock step was singular)."""


class Controller(NamedTuple):
    """Constants of a step-size controller (module docstring)."""

    alpha: float
    beta: float
    safety: float = SAFETY
    min_factor: float = MIN_FACTOR
    max_factor: float = MAX_FACTOR
    nonfinite_factor: float = NONFINITE_FACTOR


I_CONTROLLER = Controller(1.0, 0.0)
"""Elementary controller: factor SAFETY err^(-1/(q+1))."""
PI_CONTROLLER = Controller(0.7, 0.4)
"""Gustafsson's PI controller: smoother step sequences where the I controller oscillates (stability-limited
steps)."""


@njit(inline="always", fastmath=FAST)
def accepted_factor(ctrl, err, err_prev, q, after_reject):
    """(factor of the next step, the norm to pass as err_prev next time) after an accepted step of norm err
    (previous accepted norm err_prev, error order q); the factor is at most 1 when the accepted step came right
    after a rejection."""
    err = max(err, ERR_FLOOR)
    factor = ctrl.safety * err ** (-ctrl.alpha / (q + 1))
    if ctrl.beta != 0.0:
        factor *= err_prev ** (ctrl.beta / (q + 1))
    factor = min(ctrl.max_factor, max(ctrl.min_factor, factor))
    return (min(1.0, factor) if after_reject else factor), err


_LN2 = math.log(2.0)


@njit(inline="always", fastmath=FAST, error_model="numpy")
def accepted_factor_log2(ctrl, lerr, lerr_prev, q, after_reject):
    """:func:`accepted_factor` from log2 of the norms, lerr = log2(max(err, ERR_FLOOR)) and the previous accepted
    step's lerr_prev (the caller's logarithm: the driven drivers take the lanes' 0.5 % one, a step factor needs no
    more): one vectorisable exponential (:func:`sweep.integrate.solvers.vmath.exp_f64`) instead of two ``pow``
    calls (~50 ns a step of the one-point driven driver)."""
    factor = ctrl.safety * exp_f64(_LN2 * (ctrl.beta * lerr_prev - ctrl.alpha * lerr) / (q + 1))
    factor = min(ctrl.max_factor, max(ctrl.min_factor, factor))
    return min(1.0, factor) if after_reject else factor


@njit(inline="always", fastmath=FAST)
def rejected_factor(ctrl, err, q):
    """Factor of the retry of a rejected step of norm err (> 1, or not finite: a stage left the finite range)."""
    if not math.isfinite(err):
        return ctrl.nonfinite_factor
    return min(1.0, max(ctrl.min_factor, ctrl.safety * err ** (-1.0 / (q + 1))))


pin_module(__name__)
