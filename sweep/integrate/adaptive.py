"""A generic adaptive march: any right-hand side, any explicit tableau with an embedded pair, any controller.

The system is autonomous with its independent variable as state 0 (rate 1), so an end given on state 0 is met
exactly (the last step is shortened), and an end given on another component is met once it is passed.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..jitcache import pin, pin_module
from ..status import Status
from .solvers.controllers import accepted_factor, rejected_factor
from .solvers.explicit import make_erk_step
from .solvers.fastmath import FAST

__all__ = ["make_march"]

OK, MAX_STEPS, NONFINITE = int(Status.OK), int(Status.MAX_STEPS), int(Status.NONFINITE)
H_FLOOR = 1e-14
"""Smallest step relative to max(1, |state 0|) before the run is flagged nonfinite (a step that keeps failing)."""


def make_march(rhs, n: int, tableau, controller):
    """march(y, p, h, component, end, rtol, atol, max_steps) -> (status, steps, h): advance y (n components, in
    place) with adaptive steps from the trial step h until y[component] >= end (component 0: exactly at end).
    Error norm: max_i |err_i| / (atol + rtol max(|y_i|, |y_new_i|)). Returns the last step size tried (for a run
    that continues), the steps taken (accepted and rejected) and a status (ok, max_steps, nonfinite)."""
    step = make_erk_step(rhs, n, tableau)
    stages, q = tableau.stages, tableau.error_order

    @njit(fastmath=FAST, error_model="numpy")
    def march(y, p, h, component, end, rtol, atol, max_steps):
        K, ys, y_new, err = np.empty((stages, n)), np.empty(n), np.empty(n), np.empty(n)
        err_prev, rejected, steps = 1e-4, False, 0
        rhs(y, p, K[0])
        while y[component] < end:
            if steps >= max_steps:
                return MAX_STEPS, steps, h
            last = component == 0 and y[0] + h >= end
            h_try = end - y[0] if last else h
            step(K, ys, y, h_try, p, y_new, err)
            steps += 1
            norm = 0.0
            for i in range(n):
                norm = max(norm, abs(err[i]) / (atol + rtol * max(abs(y[i]), abs(y_new[i]))))
            if not norm <= 1.0:  # rejected (NaN included)
                h = h_try * rejected_factor(controller, norm, q)
                rejected = True
                if h < H_FLOOR * max(1.0, abs(y[0])):
                    return NONFINITE, steps, h
                continue
            for i in range(n):
                y[i] = y_new[i]
            rhs(y, p, K[0])
            factor, err_prev = accepted_factor(controller, norm, err_prev, q, rejected)
            rejected = False
            if not last:
                h = h_try * factor
            if last:
                y[0] = end
        for i in range(n):
            if not math.isfinite(y[i]):
                return NONFINITE, steps, h
        return OK, steps, h

    return pin(march, rhs.py_func.__module__, rhs.py_func.__qualname__, n, tableau.name)


pin_module(__name__)
