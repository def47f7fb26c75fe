"""Step ladder of the fixed-step lanes: per-point step choice and an error estimate that checks its own premise.

A fixed-step run of order p at step h has the error e(h) = C h^p + o(h^p) once h is small enough (asymptotic), and
a Richardson pair (runs at steps h_b > h_c) then estimates the error of the finer run as

    e(h_c) ~ (x_c - x_b) / (r^p - 1),   r = h_b / h_c                                       (HW I, II.4)

But a pair cannot tell whether it is asymptotic: on the stop model the error is often a sum of parts of opposite
sign with different step dependence (a stiff start, the creep manifold), and |x_c - x_b| can then be smaller than
the error itself (measured: 0.8x at chi/A = 1e4, mu1/A = -3, m2/A = 0.5). A third run settles it: with steps
h_a > h_b > h_c the differences of an asymptotic ladder have the ratio

    (x_c - x_b) / (x_b - x_a) = (h_b^p - h_c^p) / (h_a^p - h_b^p),                          (1)

and with the order q in place of p for an error C h^q. Each point climbs down a ladder:

1. a pilot pair at 2 h0, h0 (h0 from the plan's rule) measures the point's own error constant;
2. the next step is chosen from it to meet TARGET x (rtol |xi| + atol), between h/MAX_RATIO and h/MIN_RATIO;
3. with three runs, eq. (1) is solved for the observed order q; if p - ORDER_WINDOW <= q <= p + ORDER_WINDOW the
   ladder is asymptotic and the estimate is SHARP_GAIN |x_c - x_b| / (r^q - 1) (about twice the true error: at
   the steps the plan takes, RK4 on the stop model shows orders from ~3.5 to 4, which the fixed p = 4 would
   turn into estimates 0.6x the error); otherwise the ladder is not asymptotic and the estimate
   is CONSERVATIVE_GAIN max(|x_b - x_a|, |x_c - x_b|); either way, a point whose estimate exceeds its tolerance
   takes the next rung (at most MAX_RUNS runs in all, none where rounding alone exceeds the tolerance), chosen
   from that estimate.

With a step given by the user (Scene(step=h)) the ladder is fixed: 4h, 2h, h, and the run at h is returned.
The estimate adds the closed-form tail bound (2x) and rounding (:func:`rounding_error`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from ..accuracy import CONSERVATIVE_GAIN, MAX_RATIO, MAX_RUNS, MIN_RATIO, ORDER_WINDOW, SHARP_GAIN, TARGET
from .models.stop import MAX_STEPS, NONFINITE, OK

NEWTON_ITERATIONS = 6

Runner = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
"""run(points, steps) -> (xi_inf, tail bound, status, steps taken), one run per entry."""


class LadderResult(NamedTuple):
    """Per point: the returned (finest) run's value, its error estimate, status, steps and step size, the runs
    taken and the steps of all of them (``work``). A record of arrays: the compiled pass of the tolerance ladder
    (tolerance_ladder._judge) writes into it."""

    xi: np.ndarray
    error: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    step: np.ndarray
    runs: np.ndarray
    work: np.ndarray


def ratio_of_differences(q, h_a, h_b, h_c):
    """(x_c - x_b) / (x_b - x_a) of a ladder whose error is C h^q (eq. 1); decreasing in q."""
    return (1.0 - (h_c / h_b) ** q) / ((h_a / h_b) ** q - 1.0)


def observed_order(d_ab, d_bc, h_a, h_b, h_c, p):
    """Order q solving eq. (1) for the differences d_ab = x_b - x_a, d_bc = x_c - x_b, where it lies within
    ORDER_WINDOW of p; NaN where it does not. Newton's method on the logarithm of eq. (1), which is decreasing and
    nearly linear in q, from q = p (NEWTON_ITERATIONS: q to ~1e-10 inside the window; a bisection costs ~10x
    more numpy work per point, comparable to the runs themselves at coarse steps)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        log_measured = np.log(d_bc / d_ab)
    log_c, log_a = np.log(h_c / h_b), np.log(h_a / h_b)
    q = np.full(log_measured.shape, float(p))
    for _ in range(NEWTON_ITERATIONS):
        cq, aq = np.exp(q * log_c), np.exp(q * log_a)
        residual = np.log1p(-cq) - np.log(aq - 1.0) - log_measured
        slope = -cq * log_c / (1.0 - cq) - aq * log_a / (aq - 1.0)
        q = np.clip(q - residual / slope, p - 2.0 * ORDER_WINDOW, p + 2.0 * ORDER_WINDOW)
    with np.errstate(invalid="ignore"):
        solved = np.abs(np.log(ratio_of_differences(q, h_a, h_b, h_c)) - log_measured) < 1e-6
    return np.where(solved & (np.abs(q - p) <= ORDER_WINDOW), q, np.nan)


def richardson(d_bc, h_b, h_c, q):
    """Richardson estimate of the error of the finer run of a pair whose error is C h^q."""
    return np.abs(d_bc) / ((h_b / h_c) ** q - 1.0)


def next_step(h, estimate, tol, p):
    """Step of the next rung: aims at TARGET tol from a run at step h with error ``estimate``."""
    with np.errstate(divide="ignore"):
        ratio = (TARGET * tol / estimate) ** (1.0 / p)
    return h * np.clip(ratio, 1.0 / MAX_RATIO, 1.0 / MIN_RATIO)


def rounding_error(roundoff, steps, x, growth):
    """Bound on the rounding error of a run's result x [same units]: each of the ``steps`` steps rounds at
    ``roundoff`` relative, and a rounding made early grows with the run by up to exp(growth |x|), where ``growth``
    is the rate at which perturbations of xi grow per unit of xi (:func:`sweep.physics.perturbation_growth`; the
    weakening stop amplifies them by mu1/chi, 1e10 at mu1/chi = 1e10, where errors measured over step sizes 1e-7
    apart scatter by 2e-7 relative while a Richardson difference divides that scatter by r^q - 1)."""
    return roundoff * (steps + np.exp(np.minimum(growth * np.abs(x), 700.0))) * np.abs(x)


def climb(run: Runner, points: np.ndarray, h0: np.ndarray, p: int, rtol: float, atol: float, roundoff: float,
          fixed: bool, growth: np.ndarray | float = 0.0) -> LadderResult:
    """Climb the ladder for ``points`` from pilot step ``h0`` (fixed: the user's step, rungs 4h, 2h, h).

    A run that goes non-finite (e.g. a coarse step beyond the stability limit) leaves no difference to estimate
    from; the point then takes the next rung, MAX_RATIO times finer. A run that hits max_steps ends the point
    (finer rungs take more steps still). ``growth`` per point: see :func:`rounding_error`."""
    n = points.size
    h_a, h_b = (4.0 * h0, 2.0 * h0) if fixed else (2.0 * h0, h0.copy())
    x_a, _, s_a, n_a = run(points, h_a)
    x_b, t_b, s_b, n_b = run(points, h_b)
    out = LadderResult(x_b.copy(), np.full(n, np.inf), np.where(s_b != OK, s_b, s_a), n_b.copy(), h_b.copy(),
                       np.full(n, 2, np.int8), n_a.astype(np.int64) + n_b)
    todo = (s_a != MAX_STEPS) & (s_b != MAX_STEPS)
    growth = np.broadcast_to(np.asarray(growth, dtype=float), (n,))
    guess = _finite_or_inf(SHARP_GAIN * richardson(x_b - x_a, h_a, h_b, p) + 2.0 * t_b
                           + rounding_error(roundoff, n_b, x_b, growth))
    h_c = h0.copy() if fixed else next_step(h_b, guess, rtol * np.abs(x_b) + atol, p)
    while todo.any():
        i = np.flatnonzero(todo)
        x_c, t_c, s_c, n_c = run(points[i], h_c[i])
        d_ab, d_bc = x_b[i] - x_a[i], x_c - x_b[i]
        q = observed_order(d_ab, d_bc, h_a[i], h_b[i], h_c[i], p)
        sure = np.isfinite(q)
        rounding = rounding_error(roundoff, n_c, x_c, growth[i])
        estimate = _finite_or_inf(np.where(sure, SHARP_GAIN * richardson(d_bc, h_b[i], h_c[i], np.where(sure, q, p)),
                                           CONSERVATIVE_GAIN * np.maximum(np.abs(d_ab), np.abs(d_bc)))
                                  + 2.0 * t_c + rounding)
        tol_c = rtol * np.abs(x_c) + atol
        out.xi[i], out.error[i], out.steps[i], out.step[i] = x_c, estimate, n_c, h_c[i]
        out.status[i] = np.where(s_c != OK, s_c, np.where(np.isfinite(estimate), OK, NONFINITE))
        out.runs[i] += 1
        out.work[i] += n_c
        # rounding over the tolerance: finer rungs (more steps) cannot help
        more = ((s_c != MAX_STEPS) & ~(estimate <= tol_c) & (rounding <= tol_c) & (out.runs[i] < MAX_RUNS)
                & (not fixed))
        todo[:] = False
        todo[i[more]] = True
        # one rung down for the points that go on
        x_a[i], x_b[i], h_a[i], h_b[i] = x_b[i], x_c, h_b[i], h_c[i]
        h_c[i] = next_step(h_c[i], estimate, tol_c, p)
    out.error[out.status != OK] = np.nan
    return out


def _finite_or_inf(estimate):
    """An estimate that could not be formed (a run went non-finite) is infinite: the point goes on down."""
    return np.where(np.isfinite(estimate), estimate, np.inf)
