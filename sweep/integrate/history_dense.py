"""Load-history driver with dense output (docs/physics.md 7b): the friction of one point at given times of its
history, from the Dormand-Prince 5(4) continuous extension, with the per-segment records of
sweep/integrate/history.py from the same steps; and the batch loop over parameter sets (a history scene's mu_t,
sweep.protocols.history.forward).

The equations, state (s, u), stepper, error norm and controller are those of :mod:`sweep.integrate.history`; the
steps are not shortened to meet the sample times (only each segment's last step is cut to the segment's end). Inside
an accepted step from tau_n of size h the state at tau_n + theta h is Hairer's 4th-order dense output of DOPRI5
(Hairer, Norsett, Wanner, Solving ODEs I, II.6; the coefficients of dopri5.f's CONTD5):

    y(theta) = y_n + theta (dy + (1 - theta) (h f_1 - dy + theta (dy - h f_7 - (h f_1 - dy)
               + (1 - theta) h (d_1 f_1 + d_3 f_3 + d_4 f_4 + d_5 f_5 + d_6 f_6 + d_7 f_7)))),   dy = y_{n+1} - y_n

so that a record of 1e5 samples costs about what the integration costs. A sample on a segment boundary takes the
state at the end of the earlier segment (the state is continuous there; only its rate jumps).

A point never raises: its status (sweep.status.Status) is ok, max_steps, quasistatic_breakdown (runaway) or
step_underflow as in sweep/integrate/history.py; samples from the failing step on are NaN.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..jitcache import pin_module
from . import history as dp
from .history import (
    BREAKDOWN,
    H_FLOOR,
    MAX_FACTOR,
    MAX_STEPS,
    MIN_FACTOR,
    OK,
    SAFETY,
    STEADY_TOL,
    STEP_UNDERFLOW,
    W_RUNAWAY,
    _peak_in_step,
)
from .models.history import history_rates, steady_state
from .solvers.fastmath import FAST

__all__ = ["history_dense_batch", "history_dense_point"]

# dense output of DOPRI5 (dopri5.f, CONTD5)
D1, D3, D4 = -12715105075 / 11282082432, 87487479700 / 32700410799, -10690763975 / 1880347072
D5, D6, D7 = 701980252875 / 199316789632, -1453857185 / 822651844, 69997945 / 29380423


@njit(inline="always", fastmath=FAST, error_model="numpy")
def _stages(s, u, ds1, du1, h, r, k, a, b, law):
    """One Dormand-Prince step of size h from (s, u) with rates (ds1, du1) there: (s_new, u_new, err_s, err_u,
    and the dense-output sums h sum_i d_i f_i for s and u, then the FSAL rates at the new state)."""
    ds2, du2, _ = history_rates(s + h * dp.A21 * ds1, u + h * dp.A21 * du1, r, k, a, b, law)
    ds3, du3, _ = history_rates(s + h * (dp.A31 * ds1 + dp.A32 * ds2), u + h * (dp.A31 * du1 + dp.A32 * du2),
                                r, k, a, b, law)
    ds4, du4, _ = history_rates(s + h * (dp.A41 * ds1 + dp.A42 * ds2 + dp.A43 * ds3),
                                u + h * (dp.A41 * du1 + dp.A42 * du2 + dp.A43 * du3), r, k, a, b, law)
    ds5, du5, _ = history_rates(s + h * (dp.A51 * ds1 + dp.A52 * ds2 + dp.A53 * ds3 + dp.A54 * ds4),
                                u + h * (dp.A51 * du1 + dp.A52 * du2 + dp.A53 * du3 + dp.A54 * du4), r, k, a, b, law)
    ds6, du6, _ = history_rates(s + h * (dp.A61 * ds1 + dp.A62 * ds2 + dp.A63 * ds3 + dp.A64 * ds4 + dp.A65 * ds5),
                                u + h * (dp.A61 * du1 + dp.A62 * du2 + dp.A63 * du3 + dp.A64 * du4 + dp.A65 * du5),
                                r, k, a, b, law)
    s_new = s + h * (dp.B1 * ds1 + dp.B3 * ds3 + dp.B4 * ds4 + dp.B5 * ds5 + dp.B6 * ds6)
    u_new = u + h * (dp.B1 * du1 + dp.B3 * du3 + dp.B4 * du4 + dp.B5 * du5 + dp.B6 * du6)
    ds7, du7, _ = history_rates(s_new, u_new, r, k, a, b, law)
    err_s = h * (dp.E1 * ds1 + dp.E3 * ds3 + dp.E4 * ds4 + dp.E5 * ds5 + dp.E6 * ds6 + dp.E7 * ds7)
    err_u = h * (dp.E1 * du1 + dp.E3 * du3 + dp.E4 * du4 + dp.E5 * du5 + dp.E6 * du6 + dp.E7 * du7)
    dd_s = h * (D1 * ds1 + D3 * ds3 + D4 * ds4 + D5 * ds5 + D6 * ds6 + D7 * ds7)
    return s_new, u_new, err_s, err_u, dd_s, ds7, du7


@njit(inline="always", fastmath=FAST, error_model="numpy")
def _dense(y0, y1, hf1, hf7, dd, theta):
    """Hairer's dense output of DOPRI5 at the fraction theta of a step (module docstring)."""
    dy = y1 - y0
    c3 = hf1 - dy
    c4 = dy - hf7 - c3
    t1 = 1.0 - theta
    return y0 + theta * (dy + t1 * (c3 + theta * (c4 + t1 * dd)))


@njit(fastmath=FAST, error_model="numpy")
def history_dense_point(k, a, b, law, s_kick, ratios, durations, scale, times, tol, max_steps, s_start, s_end, s_peak,
                        steady, s_out):
    """Integrate one point through its segments (``ratios`` r_j; physical ``durations`` [s], reduced by ``scale``
    = V/D0 [1/s]) at the local tolerance ``tol`` from steady sliding at r_0 with s raised by ``s_kick``; writes s at
    the sorted physical ``times`` [s] from the history's start into ``s_out`` (NaN from a failure on, and at times
    past the history's end by more than 1e-12 of its length), fills the per-segment records as
    defined in sweep.integrate.history and returns (status, steps)."""
    n, m = ratios.size, times.size
    for i in range(m):
        s_out[i] = np.nan
    for j in range(n):
        s_start[j], s_end[j], s_peak[j], steady[j] = np.nan, np.nan, np.nan, 0
    s, u = steady_state(ratios[0], a, b)
    s += s_kick
    steps = 0
    h0 = 1e-3 / (1.0 + k + abs(a))
    i = 0  # next sample
    start = 0.0  # physical start of the segment
    total = 0.0
    for j in range(n):
        total += durations[j]
    m_in = m  # the samples within the history
    while m_in > 0 and times[m_in - 1] > total * (1.0 + 1e-12):
        m_in -= 1
    m = m_in
    for j in range(n):
        r, T = ratios[j], durations[j] * scale
        end = start + durations[j]
        final = j == n - 1
        ds, du, w = history_rates(s, u, r, k, a, b, law)
        s_start[j] = s
        peak = s
        while i < m and times[i] <= start and (times[i] < end or final):  # samples at the segment's start
            s_out[i] = s
            i += 1
        h = min(h0, T)  # each segment starts afresh: its velocity jumped
        t = 0.0
        while t < T:
            if steps >= max_steps:
                return MAX_STEPS, steps
            last = h >= T - t
            if last:
                h = T - t
            s_new, u_new, es, eu, dd_s, ds_new, du_new = _stages(s, u, ds, du, h, r, k, a, b, law)
            steps += 1
            err = max(abs(es) / (tol * (1.0 + max(abs(s), abs(s_new)))),
                      abs(eu) / (tol * (1.0 + max(abs(u), abs(u_new)))))
            if not math.isfinite(err) or err > 1.0:
                h *= MIN_FACTOR if not math.isfinite(err) else max(MIN_FACTOR, SAFETY * err ** -0.2)
                if h < H_FLOOR * (1.0 + t):  # where ln xi' is past W_RUNAWAY: the runaway (sweep.integrate.history)
                    return BREAKDOWN if s - u * (a + b * u) - u > W_RUNAWAY else STEP_UNDERFLOW, steps
                continue
            if ds > 0.0 and ds_new <= 0.0:
                peak = max(peak, _peak_in_step(s, u, ds, du, h, r, k, a, b, law))
            t_next = T if last else t + h
            # the samples inside this step (all the rest of the segment's on its last step)
            while i < m and (((times[i] - start) * scale <= t_next) or last) and (times[i] <= end or final):
                theta = min(1.0, max(0.0, ((times[i] - start) * scale - t) / h))
                s_out[i] = _dense(s, s_new, h * ds, h * ds_new, dd_s, theta)
                i += 1
            t = t_next
            s, u, ds, du = s_new, u_new, ds_new, du_new
            peak = max(peak, s)
            if not last:
                h *= min(MAX_FACTOR, max(MIN_FACTOR, SAFETY * max(err, 1e-10) ** -0.2))
        w = history_rates(s, u, r, k, a, b, law)[2]
        s_end[j], s_peak[j] = s, peak
        if r > 0.0 and abs(w - math.log(r)) <= STEADY_TOL and abs(u + math.log(r)) <= STEADY_TOL:
            steady[j] = 1
        start = end
    return OK, steps


@njit(nogil=True, cache=True, fastmath=FAST, error_model="numpy")
def history_dense_batch(k, a, b, law, s_kick, ratios, durations, scale, times, tol, max_steps, s_start, s_end, s_peak,
                        steady, s_out, status, steps):
    """:func:`history_dense_point` for every parameter set i: its k[i], a[i], b[i], s_kick[i], scale[i], segments
    ratios[i, :] and physical durations[i, :] [s]; rows of the records and of s_out. The sample times are shared."""
    for i in range(k.size):
        status[i], steps[i] = history_dense_point(k[i], a[i], b[i], law, s_kick[i], ratios[i], durations[i], scale[i],
                                                  times, tol, max_steps, s_start[i], s_end[i], s_peak[i], steady[i],
                                                  s_out[i])


@njit(nogil=True, cache=True, fastmath=FAST, error_model="numpy")
def history_dense_rows(k, a, b, law, s_kick, ratios, durations, scale, times, time_row, n_times, tol, max_steps,
                       s_start, s_end, s_peak, steady, s_out, status, steps):
    """:func:`history_dense_batch` with sample times of each set's own: set i's are times[time_row[i], :n_times[i]]
    (a table of several records' sorted times [s] from their histories' starts, one a row) and its samples go to
    s_out[i, :n_times[i]] (the rest of the row untouched): a fit's records, each of its own times, in one call."""
    for i in range(k.size):
        n = n_times[i]
        status[i], steps[i] = history_dense_point(k[i], a[i], b[i], law, s_kick[i], ratios[i], durations[i], scale[i],
                                                  times[time_row[i], :n], tol, max_steps, s_start[i], s_end[i],
                                                  s_peak[i], steady[i], s_out[i, :n])


pin_module(__name__)
