"""The load-history stepper's parts (docs/physics.md, "Load histories"): the Dormand-Prince step, the peak located
inside a step, the controller's constants and the records' definitions, shared by the drivers that integrate a
point segment by segment through a piecewise-constant load-point velocity (quasi-static:
sweep/integrate/history_dense.py; inertial: sweep/integrate/history_inertial.py).

The equations are those of :mod:`sweep.integrate.models.history` in the state (s, u), s = (mu - mu_d(V))/A. The
stepper is Dormand-Prince 5(4) with local extrapolation and an I controller on the mixed norm
max_i |err_i| / (tol (1 + max(|y_i|, |y_new_i|))); every segment ends exactly at its end (the last step is cut to it).
The run starts from steady sliding at the first segment's velocity with s raised by k x ``perturbation`` (the
driven scene's initial spring stretch z(0), reduced by D0).

Recorded per segment j (the observables' raw material, in units of A):

* ``s_start[j]``, ``s_end[j]``: s at the segment's start and end;
* ``s_peak[j]``: the largest s met in the segment: the step ends, and inside a step where s' = k (r - e^w) turns
  from > 0 to <= 0 the root of s' located by the Illinois method on partial steps from the step's start (each as
  accurate as the accepted step), so that a peak is as accurate as the stepper;
* ``steady[j]``: 1 where the segment ends in steady sliding at its velocity, |w - ln r| and |u + ln r| both
  <= STEADY_TOL (never for a hold).

A point never raises: its status (sweep.status.Status) says ok, max_steps (the scene's step budget, over all
segments, ran out), step_underflow (the step fell below H_FLOOR relative to 1 + the time into the segment: the
equations left the range a double can follow) or, the quasi-static driver only, quasistatic_breakdown: the step
underflowed where the slip velocity is past RUNAWAY_XI_DOT times V (w > W_RUNAWAY): the runaway of a spring softer
than critical, where the quasi-static equations reach v = inf in finite time and inertia is needed (a finite burst
past 1e8 V, e.g. the reslide after a long hold with m2 > 0, is followed and kept); the values recorded are then NaN
from the failing segment on.
"""

from __future__ import annotations

from numba import njit

from ..accuracy import W_RUNAWAY
from ..jitcache import pin_module
from ..status import Status
from .models.history import history_rates
from .solvers.fastmath import FAST

__all__ = ["H_FLOOR", "STEADY_TOL", "W_RUNAWAY"]

OK, MAX_STEPS, STEP_UNDERFLOW = int(Status.OK), int(Status.MAX_STEPS), int(Status.STEP_UNDERFLOW)
BREAKDOWN = int(Status.QUASISTATIC_BREAKDOWN)
H_FLOOR = 1e-14
"""Smallest step relative to 1 + the time into the segment before the point is flagged step_underflow."""
STEADY_TOL = 1e-6
"""A segment ends in steady sliding where |w - ln r| and |u + ln r| are both at most this (in units where the
friction's deviation from its steady value is about A times these)."""
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 5.0
"""The I controller: next step h (SAFETY err^-1/5), the factor clamped to [MIN_FACTOR, MAX_FACTOR]."""

# Dormand-Prince 5(4) (J. R. Dormand, P. J. Prince, J. Comput. Appl. Math. 6 (1980) 19; Hairer-Norsett-Wanner II.5)
A21 = 1 / 5
A31, A32 = 3 / 40, 9 / 40
A41, A42, A43 = 44 / 45, -56 / 15, 32 / 9
A51, A52, A53, A54 = 19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729
A61, A62, A63, A64, A65 = 9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656
B1, B3, B4, B5, B6 = 35 / 384, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84
E1, E3, E4, E5, E6, E7 = (35 / 384 - 5179 / 57600, 500 / 1113 - 7571 / 16695, 125 / 192 - 393 / 640,
                          -2187 / 6784 + 92097 / 339200, 11 / 84 - 187 / 2100, -1 / 40)


@njit(inline="always", fastmath=FAST, error_model="numpy")
def _dp5(s, u, ds1, du1, h, r, k, a, b, law):
    """One Dormand-Prince step of size h from (s, u) with rates (ds1, du1) there: (s_new, u_new, err_s, err_u,
    ds_new, du_new, w_new) (the FSAL rates at the new state and its ln xi')."""
    ds2, du2, _ = history_rates(s + h * A21 * ds1, u + h * A21 * du1, r, k, a, b, law)
    ds3, du3, _ = history_rates(s + h * (A31 * ds1 + A32 * ds2), u + h * (A31 * du1 + A32 * du2), r, k, a, b, law)
    ds4, du4, _ = history_rates(s + h * (A41 * ds1 + A42 * ds2 + A43 * ds3),
                                u + h * (A41 * du1 + A42 * du2 + A43 * du3), r, k, a, b, law)
    ds5, du5, _ = history_rates(s + h * (A51 * ds1 + A52 * ds2 + A53 * ds3 + A54 * ds4),
                                u + h * (A51 * du1 + A52 * du2 + A53 * du3 + A54 * du4), r, k, a, b, law)
    ds6, du6, _ = history_rates(s + h * (A61 * ds1 + A62 * ds2 + A63 * ds3 + A64 * ds4 + A65 * ds5),
                                u + h * (A61 * du1 + A62 * du2 + A63 * du3 + A64 * du4 + A65 * du5), r, k, a, b, law)
    s_new = s + h * (B1 * ds1 + B3 * ds3 + B4 * ds4 + B5 * ds5 + B6 * ds6)
    u_new = u + h * (B1 * du1 + B3 * du3 + B4 * du4 + B5 * du5 + B6 * du6)
    ds7, du7, w7 = history_rates(s_new, u_new, r, k, a, b, law)
    err_s = h * (E1 * ds1 + E3 * ds3 + E4 * ds4 + E5 * ds5 + E6 * ds6 + E7 * ds7)
    err_u = h * (E1 * du1 + E3 * du3 + E4 * du4 + E5 * du5 + E6 * du6 + E7 * du7)
    return s_new, u_new, err_s, err_u, ds7, du7, w7


@njit(fastmath=FAST, error_model="numpy")
def _peak_in_step(s, u, ds, du, h, r, k, a, b, law):
    """The largest s inside a step from (s, u) (rates ds, du, ds > 0) of size h at whose end s' <= 0: s at the root
    of s'(theta) in (0, h), located by the Illinois method on partial steps from the step's start."""
    lo, hi = 0.0, h
    g_lo, g_hi = ds, _dp5(s, u, ds, du, h, r, k, a, b, law)[4]
    best = s
    side = 0
    for _ in range(80):
        theta = (lo * g_hi - hi * g_lo) / (g_hi - g_lo) if g_hi != g_lo else 0.5 * (lo + hi)
        if not lo < theta < hi:
            theta = 0.5 * (lo + hi)
        s_t, u_t, _, _, g_t, _, _ = _dp5(s, u, ds, du, theta, r, k, a, b, law)
        best = max(best, s_t)
        if g_t > 0.0:
            lo, g_lo = theta, g_t
            if side == 1:
                g_hi *= 0.5
            side = 1
        else:
            hi, g_hi = theta, g_t
            if side == -1:
                g_lo *= 0.5
            side = -1
        if hi - lo <= 1e-13 * h:
            break
    return best


pin_module(__name__)
