"""Quasi-static driven points in lockstep lanes (issue 35): every lane its own point, step, accept/reject and cycle
bookkeeping, as the adaptive stop lanes (:mod:`sweep.integrate.lanes_adaptive`) do for the stop scene.

The equations and the rules are those of the one-point driver :mod:`sweep.integrate.driven` (its module docstring):
the quasi-static driven equations in (z, u) with the aging law (docs/physics.md 3b), the error scale
rtol max(largest |z| met, |z_new|, |u_new|), the cycle history cut at the maxima of z, and the regime decision
(:func:`sweep.integrate.driven._decide`). The stepper is Hairer's DOP853 rather than the driver's dp5: its error
norm is dop853.f's, err5^2 / sqrt(err5^2 + 0.01 err3^2) of the max-norms of the fifth- and third-order estimates
(:data:`sweep.integrate.solvers.tableau.DOP853_ER3`), of order 8 in h, with the I controller's exponent 1/8; f at the
step's end (the turn of z', and the next step's first stage) makes twelve evaluations an attempt. The driven stepper's
tolerance is 1e-9 whatever the scene's (:func:`sweep.accuracy.driven_stepper_rtol`), where the eighth order pays:
on the issue grid dp5 with the PI controller took 7.41M evaluations (1.23M attempts), DOP853 with this norm takes
4.14M (0.34M attempts), 2.7-3.6x fewer on the long points near the line, and its amplitudes are closer to a
1e-12 reference (largest error 1.0e-8 against dp5's 7.2e-8; benchmarks/driven_lanes.py). Steps in the slips are
bound by accuracy, not stability (scipy's Radau and BDF at the same tolerance take 1.6-3.5x more steps than its
RK45 there), so an L-stable step would not save any.

What differs from the driver is how the work is laid out. One pass of the lane loops is one *attempt* of every lane:
the eleven stage loops (one loop per stage, for the reason of :func:`sweep.integrate.lanes_adaptive._stage_loops`),
then a closing loop with the error norm, the accept mask, the next step and the commit of the accepted state, all
straight-line code (selects, not branches) that LLVM vectorises. The closing loop also raises a lane's *attention*
flag where the scalar bookkeeping must look: an accepted step across an extremum of z (z' changes sign), past the
runaway threshold W_RUNAWAY, below DECAYED (or, the first time, 0.1) x perturbation, the step budget spent, or a
rejected step below the step floor. Those steps (a few per cycle of some tens) are left uncommitted for the short
scalar loop that follows every attempt: it locates the extremum on the step's dense output (:func:`dense_extremum`:
the stages are still in the lane fields, three more evaluations give DOP853's interpolant of order 7, and Newton on
the exact z' at its states gives the time), books the cycle, decides, and hands a finished lane its next point.
Once no point is queued, the busy lanes are gathered into the first half, then the first quarter, of the lanes and
only those are stepped (:data:`WIDTHS`): a batch ends with its longest points, which then no longer pay for 16
lanes.

Where the arithmetic differs from the one-point driver besides the method: the exponentials of the right-hand side
are :func:`sweep.integrate.solvers.vmath.exp_f64` (<= 2.3e-16 relative, vectorisable; the driver calls libm); the
controller's factor is exp_f64 of :func:`sweep.integrate.solvers.vmath.log2_approx` (0.5 %: a step factor needs no
more). Steps therefore differ from the driver's, and growth rates and amplitudes differ at the tolerance's level
(within their estimates; tests/integrate/test_lanes_driven.py). A point's numbers do not depend on its lane or
neighbours.

Only the quasi-static model with the aging law runs here; the inertial model runs in
:mod:`sweep.integrate.lanes_driven_inertial` (dp5), which shares the cycle bookkeeping (:class:`Bookkeeping`,
:func:`book_state`, :func:`book_maximum`, :func:`book_minimum`) and the lane loop (:func:`make_run_lanes`) with this
module; the slip law runs on the one-point driver.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..accuracy import DECAYED, REBOUND, W_RUNAWAY
from ..jitcache import pin, pin_module
from . import dense_dop853
from .batch import lanes_in_threads
from .driven import (
    BREAKDOWN,
    H_FLOOR,
    H_START,
    HISTORY,
    MAX_STEPS,
    OK,
    STEP_UNDERFLOW,
    DrivenParams,
    Regime,
    _decide,
    _linear_amplitude,
)
from .models.driven import log_velocity_rate
from .solvers import DOP853
from .solvers.controllers import ERR_FLOOR, MAX_FACTOR, MIN_FACTOR, NONFINITE_FACTOR, SAFETY
from .solvers.fastmath import FAST
from .solvers.rosenbrock_step import scratch
from .solvers.tableau import DOP853_ER3
from .solvers.vmath import EXP_MAX, exp_f64
from .solvers.vmath import log2_approx as _log2_approx

__all__ = ["LANES", "DrivenJob", "DrivenPoints", "driven_lanes"]

LANES = 16
"""Points in flight per thread."""

# lane fields, each LANES wide at offset F * LANES of one flat array
_K, _A, _B, _H, _Z, _U, _DZ, _DU, _TAU, _SIZE, _REJ, _ATTN, _ACC = range(13)
_ZE, _UE, _DZE, _DUE, _LWE, _HN, _NSTEP, _TENTH, _WPEAK = range(13, 22)
_STAGES = 22
"""Stage j = 2..12 of the step under way: dz_j at _STAGES + 2 (j - 2), du_j next to it."""
_N_FIELDS = _STAGES + 2 * (DOP853.stages - 1)
_LN2 = math.log(2.0)
_Q1 = 8
"""The controller's exponent is -1/_Q1: DOP853's damped error norm is of order 8 in h (:data:`DOP853_ER3`)."""
_DOP853_STAGES = DOP853.stages
SCRATCH_STAGES = dense_dop853.STAGES
"""Rows of the stage scratch of the scalar loop: a DOP853 step's twelve stages, f at its end and the dense output's
three more stages (:func:`dense_extremum`; the inertial lanes' dp5 steps use seven)."""


@njit(inline="always", fastmath=FAST, error_model="numpy")
def rate(z, u, k, a, b):
    """(z', u', ln xi') of the quasi-static driven equations with the aging law
    (:func:`sweep.integrate.models.driven.make_driven_rhs`), with the vectorisable exponential."""
    lw = k * z - u * (a + b * u) - u
    e = exp_f64(min(lw, EXP_MAX))
    return 1.0 - e, exp_f64(min(-u, EXP_MAX)) - e, lw


def _attempt_source(width: int) -> str:
    """Source of attempt_all(st, rtol, pert, max_steps): one DOP853 attempt of lanes 0..width-1 (module docstring);
    the loop count a literal, so that every width runs the same vector code per lane."""
    _, A, b, e = DOP853.arrays()
    s = DOP853.stages
    W = LANES
    f = lambda field: f"st[{field * W} + l]"  # noqa: E731

    def d(comp: int, j: int) -> str:  # the derivative of stage j (1-based): the first in locals, then stage fields
        return ("dz1", "du1")[comp] if j == 1 else f(_STAGES + 2 * (j - 2) + comp)

    def combo(weights, comp: int, count: int) -> str:
        return " + ".join(f"{float(weights[j])!r} * {d(comp, j + 1)}" for j in range(count) if weights[j] != 0.0)

    head = [f"    for l in range({width}):",
            f"        k, a, bb, h = {f(_K)}, {f(_A)}, {f(_B)}, {f(_H)}",
            f"        z1, u1, dz1, du1 = {f(_Z)}, {f(_U)}, {f(_DZ)}, {f(_DU)}"]
    lines = ["def attempt_all(st, rtol, pert, max_steps):"]
    for i in range(2, s + 1):
        lines += head + [
            f"        zi = z1 + h * ({combo(A[i - 1], 0, i - 1)})",
            f"        ui = u1 + h * ({combo(A[i - 1], 1, i - 1)})",
            "        dzi, dui, lwi = rate(zi, ui, k, a, bb)",
            f"        {f(_STAGES + 2 * (i - 2))}, {f(_STAGES + 2 * (i - 2) + 1)} = dzi, dui"]
    lines += head + [
        f"        ze = z1 + h * ({combo(b, 0, s)})",
        f"        ue = u1 + h * ({combo(b, 1, s)})",
        # the rates at the step's end: the turn of z' below and, once accepted, the next step's first stage
        "        dze, due, lwe = rate(ze, ue, k, a, bb)",
        f"        ez = h * ({combo(e, 0, s)})",
        f"        eu = h * ({combo(e, 1, s)})",
        f"        e3z = h * ({combo(DOP853_ER3, 0, s)})",
        f"        e3u = h * ({combo(DOP853_ER3, 1, s)})",
        f"        size, tau, rej = {f(_SIZE)}, {f(_TAU)}, {f(_REJ)}",
        # NaN anywhere (a stage beyond the exponent clamp) rejects with the non-finite factor
        "        finite = ze == ze and ue == ue and ez == ez and eu == eu and e3z == e3z and e3u == e3u",
        "        scale = rtol * max(size, max(abs(ze), abs(ue)))",
        "        err5 = max(abs(ez), abs(eu)) / scale",
        "        err3 = max(abs(e3z), abs(e3u)) / scale",
        "        den = math.sqrt(err5 * err5 + 0.01 * err3 * err3)",
        "        err = err5 * (err5 / den) if den > zero else zero",
        "        err = err if finite else one",
        "        accept = finite and err <= one",
        "        lerr = _log2_approx(max(err, err_floor))",
        "        grow = safety * exp_f64(i_now * lerr)",
        "        f_acc = min(one if rej > half else max_factor, max(min_factor, grow))",
        "        f_rej = min(one, max(min_factor, grow))",
        "        hn = h * (f_acc if accept else (f_rej if finite else nonfinite_factor))",
        # where the scalar bookkeeping must look (module docstring)
        "        norm = max(abs(ze), abs(ue))",
        "        turn = (dz1 > zero and dze <= zero) or (dz1 < zero and dze >= zero)",
        f"        first_tenth = norm < tenth * pert and {f(_TENTH)} == zero",
        "        event = turn or lwe > w_runaway or norm < decayed * pert or first_tenth",
        f"        n = {f(_NSTEP)} + one",
        "        attn = (accept and event) or n >= max_steps or (not accept and hn < h_floor * (one + tau))",
        "        commit = accept and not attn",
        f"        {f(_NSTEP)} = n",
        f"        {f(_Z)}, {f(_U)} = (ze, ue) if commit else (z1, u1)",
        f"        {f(_DZ)}, {f(_DU)} = (dze, due) if commit else (dz1, du1)",
        f"        {f(_TAU)} = tau + h if commit else tau",
        f"        {f(_SIZE)} = max(size, abs(ze)) if commit else size",
        f"        {f(_WPEAK)} = max({f(_WPEAK)}, lwe) if commit else {f(_WPEAK)}",
        f"        {f(_H)} = h if (accept and attn) else hn",
        f"        {f(_REJ)} = zero if commit else (one if not accept else rej)",
        f"        {f(_ATTN)} = one if attn else zero",
        f"        {f(_ACC)} = one if accept else zero",
        f"        {f(_ZE)}, {f(_UE)}, {f(_DZE)}, {f(_DUE)}, {f(_LWE)} = ze, ue, dze, due, lwe",
        f"        {f(_HN)} = hn",
    ]
    return "\n".join(lines) + "\n"


@njit(fastmath=FAST, error_model="numpy")
def dense_extremum(st, lane, K, y, dy):
    """(theta h, z there): the extremum of z inside lane ``lane``'s accepted, uncommitted DOP853 step (z' changes
    sign), from the step's dense output of order 7 (sweep/integrate/dense_dop853.py): its stages are still in the
    lane fields (stage 1 the start's rates, 2..12 the stage fields, 13 the end's), three more are evaluated here.
    First the root of the interpolant's own slope (Newton kept inside the bracket where it changes sign), then
    Newton on the exact z' = 1 - xi' at the interpolated state (z'' = -xi' (ln xi')'): the time of a flat
    extremum is ill-conditioned in z' (an error dz' moves it by dz'/z''), and the interpolant's slope is a
    derivative of the interpolant, off by ~1e-5 of a period where the exact rate at its state is off by the
    state's error only. Six evaluations an extremum instead of a partial step (twelve) and Newton's own. ``y`` and
    ``dy`` are scratch for a state and its rates (2)."""
    W = LANES
    k, a, b, h = st[_K * W + lane], st[_A * W + lane], st[_B * W + lane], st[_H * W + lane]
    z0, u0 = st[_Z * W + lane], st[_U * W + lane]
    K[0, 0], K[0, 1] = st[_DZ * W + lane], st[_DU * W + lane]
    for j in range(1, _DOP853_STAGES):
        K[j, 0], K[j, 1] = st[(_STAGES + 2 * (j - 1)) * W + lane], st[(_STAGES + 2 * (j - 1) + 1) * W + lane]
    K[12, 0], K[12, 1] = st[_DZE * W + lane], st[_DUE * W + lane]
    for s in range(13, 16):
        zi, ui = z0, u0
        for j in range(s):
            zi += h * dense_dop853.EXTRA_MATRIX[s - 13, j] * K[j, 0]
            ui += h * dense_dop853.EXTRA_MATRIX[s - 13, j] * K[j, 1]
        K[s, 0], K[s, 1], _ = rate(zi, ui, k, a, b)
    Fz = dense_dop853.rows(z0, st[_ZE * W + lane], h, K, 0)
    Fu = dense_dop853.rows(u0, st[_UE * W + lane], h, K, 1)
    rising = K[0, 0] > 0.0  # z' > 0 at the start: a maximum (the slope falls through zero)
    lo, hi = 0.0, 1.0
    theta = K[0, 0] / (K[0, 0] - K[12, 0])
    for _ in range(12):
        _, slope, curvature = dense_dop853.evaluate(theta, z0, Fz)
        if (slope > 0.0) == rising:
            lo = theta
        else:
            hi = theta
        nxt = theta - slope / curvature if curvature != 0.0 else 0.5 * (lo + hi)
        if not lo < nxt < hi:
            nxt = 0.5 * (lo + hi)
        if abs(nxt - theta) < 1e-12:
            theta = nxt
            break
        theta = nxt
    for _ in range(3):
        z, u = dense_dop853.evaluate(theta, z0, Fz)[0], dense_dop853.evaluate(theta, u0, Fu)[0]
        dz, du, lw = rate(z, u, k, a, b)
        y[0], y[1], dy[0], dy[1] = z, u, dz, du
        ddz = -exp_f64(min(lw, EXP_MAX)) * log_velocity_rate(y, dy, DrivenParams(k, a, b, 0.0))
        if ddz == 0.0 or not math.isfinite(ddz):
            break
        delta = -dz / (ddz * h)
        if not 0.0 <= theta + delta <= 1.0:
            break
        theta += delta
        if abs(delta) < 1e-12:
            break
    return theta * h, dense_dop853.evaluate(theta, z0, Fz)[0]


WIDTHS = (LANES, LANES // 2, LANES // 4)
"""Widths of the attempt: once no point is queued, the busy lanes are gathered into the first half (quarter) and
only those are stepped, so that the last long points of a batch do not pay for idle lanes."""


@functools.cache
def _attempt(width: int):
    """attempt_all(st, rtol, pert, max_steps) over ``width`` lanes, compiled (inlined by LLVM into the driver)."""
    namespace = {"rate": rate, "exp_f64": exp_f64, "_log2_approx": _log2_approx, "math": math, "W": LANES, "one": 1.0,
                 "zero": 0.0, "half": 0.5, "tenth": 0.1, "decayed": DECAYED, "w_runaway": W_RUNAWAY,
                 "h_floor": H_FLOOR, "err_floor": ERR_FLOOR, "safety": SAFETY, "max_factor": MAX_FACTOR,
                 "min_factor": MIN_FACTOR, "nonfinite_factor": NONFINITE_FACTOR,
                 "i_now": -_LN2 / _Q1, "__name__": __name__}  # err^(-1/q1) as exp of a multiple of log2
    exec(compile(_attempt_source(width), f"<sweep.integrate.lanes_driven: dop853, {width} lanes>", "exec"), namespace)
    return pin(njit(forceinline=True, fastmath=FAST, error_model="numpy")(namespace["attempt_all"]), "dop853", width)


class DrivenPoints(NamedTuple):
    """Reduced parameters of the flat points (k = chi/A, a = mu1/A, b = m2/A)."""

    k: np.ndarray
    a: np.ndarray
    b: np.ndarray


class DrivenJob(NamedTuple):
    """The points to run (indices into :class:`DrivenPoints` and the outputs) and the scene's settings
    (:class:`sweep.integrate.driven.DrivenSettings`)."""

    point: np.ndarray
    perturbation: float
    rtol: float
    max_cycles: int
    max_steps: int


class Bookkeeping(NamedTuple):
    """Per-lane cycle bookkeeping (scalar: touched at extrema only), shared with the inertial lanes
    (sweep/integrate/lanes_driven_inertial.py)."""

    amp: np.ndarray
    per: np.ndarray
    grow: np.ndarray
    z_min: np.ndarray
    t_max_prev: np.ndarray
    amp_first: np.ndarray
    a_start: np.ndarray
    norm_tenth: np.ndarray
    t_tenth: np.ndarray
    cycles: np.ndarray
    after_rebound: np.ndarray


@njit(inline="always")
def new_bookkeeping(lanes):
    """A :class:`Bookkeeping` for ``lanes`` lanes."""
    return Bookkeeping(np.full((lanes, HISTORY), np.nan), np.full((lanes, HISTORY), np.nan),
                       np.full((lanes, HISTORY), np.nan), np.full(lanes, math.inf), np.full(lanes, np.nan),
                       np.full(lanes, np.nan), np.full(lanes, np.nan), np.full(lanes, np.nan), np.full(lanes, np.nan),
                       np.zeros(lanes, np.int64), np.zeros(lanes, np.bool_))


@njit(inline="always")
def reset_bookkeeping(bk, lane, a_start):
    """Lane ``lane``'s bookkeeping at the start of a point (a_start: the linear amplitude through the start)."""
    for i in range(HISTORY):
        bk.amp[lane, i], bk.per[lane, i], bk.grow[lane, i] = math.nan, math.nan, math.nan
    bk.z_min[lane], bk.t_max_prev[lane], bk.amp_first[lane] = math.inf, math.nan, math.nan
    bk.a_start[lane] = a_start
    bk.norm_tenth[lane], bk.t_tenth[lane], bk.cycles[lane] = math.nan, math.nan, 0
    bk.after_rebound[lane] = False


@njit(inline="always")
def move_bookkeeping(bk, lane, to):
    """Lane ``lane``'s bookkeeping into lane ``to``."""
    for m in range(HISTORY):
        bk.amp[to, m], bk.per[to, m], bk.grow[to, m] = bk.amp[lane, m], bk.per[lane, m], bk.grow[lane, m]
    bk.z_min[to], bk.t_max_prev[to], bk.amp_first[to] = bk.z_min[lane], bk.t_max_prev[lane], bk.amp_first[lane]
    bk.a_start[to], bk.norm_tenth[to], bk.t_tenth[to] = bk.a_start[lane], bk.norm_tenth[lane], bk.t_tenth[lane]
    bk.cycles[to], bk.after_rebound[to] = bk.cycles[lane], bk.after_rebound[lane]


@njit(inline="always")
def finish(out, i, regime, status, grow, per, amplitude, cycles, steps, w_peak):
    """Point i's outputs."""
    out.regime[i], out.status[i], out.growth_rate[i], out.period[i] = regime, status, grow, per
    out.amplitude[i], out.cycles[i], out.steps[i], out.peak_w[i] = amplitude, cycles, steps, w_peak


@njit(inline="always", fastmath=FAST, error_model="numpy")
def book_state(bk, lane, i, out, lw1, norm, tau, h, pert, steps, w_peak):
    """The one-point driver's tests of an accepted state (ln xi' lw1, max-norm ``norm``, at tau + h): runaway past
    W_RUNAWAY, steady below DECAYED x perturbation (point i finished: True), the first state below 0.1 x
    perturbation noted."""
    grow, per, cycles = bk.grow[lane], bk.per[lane], bk.cycles[lane]
    if lw1 > W_RUNAWAY:
        finish(out, i, Regime.RUNAWAY, BREAKDOWN, grow[-1], per[-1], math.nan, cycles, steps, w_peak)
        return True
    if norm < DECAYED * pert:
        if not math.isfinite(grow[-1]):
            grow[-1] = math.log(norm / bk.norm_tenth[lane]) / (tau + h - bk.t_tenth[lane])
        finish(out, i, Regime.STEADY, OK, grow[-1], per[-1], 0.0, cycles, steps, w_peak)
        return True
    if norm < 0.1 * pert and not math.isfinite(bk.t_tenth[lane]):
        bk.norm_tenth[lane], bk.t_tenth[lane] = norm, tau + h
    return False


@njit(inline="always", fastmath=FAST, error_model="numpy")
def book_maximum(bk, lane, i, out, z_top, t_peak, pert, max_cycles, steps, w_peak):
    """A maximum of z (z_top at t_peak): a cycle ends unless it is a rebound (the one-point driver's rules and
    decision); True where point i is finished."""
    amp, per, grow = bk.amp[lane], bk.per[lane], bk.grow[lane]
    rebound = 0.5 * (z_top - bk.z_min[lane]) < REBOUND * amp[-1]
    if not rebound and bk.z_min[lane] < math.inf and math.isfinite(bk.t_max_prev[lane]):
        cycles = bk.cycles[lane] + 1
        bk.cycles[lane] = cycles
        for m in range(HISTORY - 1):
            amp[m], per[m], grow[m] = amp[m + 1], per[m + 1], grow[m + 1]
        amp[-1], per[-1] = 0.5 * (z_top - bk.z_min[lane]), t_peak - bk.t_max_prev[lane]
        grow[-1] = math.log(amp[-1] / amp[-2]) / per[-1] if amp[-2] > 0.0 else math.nan
        if cycles == 1:
            bk.amp_first[lane] = amp[-1]
        regime = _decide(amp, grow, pert, bk.amp_first[lane], bk.a_start[lane], cycles)
        if regime != Regime.UNDECIDED:
            amplitude = 0.0 if regime == Regime.STEADY else amp[-1]
            finish(out, i, regime, OK, grow[-1], per[-1], amplitude, cycles, steps, w_peak)
            return True
        if cycles >= max_cycles:
            finish(out, i, Regime.UNDECIDED, OK, grow[-1], per[-1], math.nan, cycles, steps, w_peak)
            return True
    if not rebound:
        bk.t_max_prev[lane] = t_peak
    bk.after_rebound[lane] = rebound
    return False


@njit(inline="always")
def book_minimum(bk, lane, z_new):
    """A minimum of z (the lower one where the maximum between was a rebound)."""
    bk.z_min[lane] = min(bk.z_min[lane], z_new) if bk.after_rebound[lane] else z_new


def make_run_lanes(attempts, widths, look, load, idle, n_fields: int, attn: int, n: int, variant: tuple):
    """run_lanes(pts, job, runs, out): the lane loop (module docstring) over ``attempts`` (one per :data:`WIDTHS`),
    the scalar ``look`` of a lane whose attention flag is up, ``load(st, bk, lane, pts, i, pert)`` of point i and
    ``idle(st, bk, lane, pert)`` of an idle dummy, ``n_fields`` lane fields (the attention flag at ``attn``) and
    ``n`` state components (the scratch of the scalar extremum search)."""
    attempt_full, attempt_mid, attempt_last = attempts
    W, MID, LAST = widths

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def gather(st, bk, lane_point, width):
        """Move the busy lanes among 0..width-1 into the first ones; the others become idle dummies."""
        to = 0
        for lane in range(width):
            if lane_point[lane] < 0:
                continue
            if lane != to:
                for f in range(n_fields):
                    st[f * W + to] = st[f * W + lane]
                move_bookkeeping(bk, lane, to)
                lane_point[to], lane_point[lane] = lane_point[lane], -1
            to += 1

    @njit(cache=True, nogil=True, fastmath=FAST, error_model="numpy")
    def run_lanes(pts, job, runs, out):
        """The points job.point[runs] to their regimes, into ``out`` (a DrivenOutputs over all points)."""
        st = np.zeros(n_fields * W)
        bk = new_bookkeeping(W)
        lane_point = np.full(W, -1, np.int64)
        pert, rtol = job.perturbation, job.rtol
        max_steps = float(job.max_steps)
        y0, y1, ys, yt = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        err_v, dyt = np.empty(n), np.empty(n)
        K = np.empty((SCRATCH_STAGES, n))
        work = scratch(n)
        queued, busy = 0, 0
        for lane in range(W):
            if queued < runs.size:
                i = job.point[runs[queued]]
                load(st, bk, lane, pts, i, pert)
                lane_point[lane] = i
                queued += 1
                busy += 1
            else:
                idle(st, bk, lane, pert)
        width = W
        while busy > 0:
            while queued == runs.size and width > LAST and busy <= (MID if width == W else LAST):
                gather(st, bk, lane_point, width)
                width = MID if width == W else LAST
                for lane in range(busy, width):  # idle dummies in the freed lanes (never looked at)
                    idle(st, bk, lane, pert)
            if width == W:
                attempt_full(st, rtol, pert, max_steps)
            elif width == MID:
                attempt_mid(st, rtol, pert, max_steps)
            else:
                attempt_last(st, rtol, pert, max_steps)
            for lane in range(width):
                if st[attn * W + lane] == 0.0:
                    continue
                i = lane_point[lane]
                if i < 0:  # an idle dummy: restart it, never look
                    idle(st, bk, lane, pert)
                    continue
                if not look(st, bk, lane, i, job, out, y0, y1, K, ys, yt, err_v, work, dyt):
                    continue
                if queued < runs.size:
                    i = job.point[runs[queued]]
                    load(st, bk, lane, pts, i, pert)
                    lane_point[lane] = i
                    queued += 1
                else:
                    idle(st, bk, lane, pert)
                    lane_point[lane] = -1
                    busy -= 1

    pin(gather, *variant)
    return pin(run_lanes, *variant)


@functools.cache
def _make_kernels():
    W = LANES

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def load_values(st, bk, lane, k, a, b, pert):
        st[_K * W + lane], st[_A * W + lane], st[_B * W + lane] = k, a, b
        st[_Z * W + lane], st[_U * W + lane] = pert, 0.0
        dz, du, _ = rate(pert, 0.0, k, a, b)
        st[_DZ * W + lane], st[_DU * W + lane] = dz, du
        st[_H * W + lane] = H_START / (1.0 + k)
        st[_TAU * W + lane], st[_SIZE * W + lane] = 0.0, pert
        st[_REJ * W + lane], st[_NSTEP * W + lane], st[_TENTH * W + lane] = 0.0, 0.0, 0.0
        st[_WPEAK * W + lane] = -math.inf
        reset_bookkeeping(bk, lane, _linear_amplitude(DrivenParams(k, a, b, 0.0), pert))

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def load(st, bk, lane, pts, i, pert):
        load_values(st, bk, lane, pts.k[i], pts.a[i], pts.b[i], pert)

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def idle(st, bk, lane, pert):
        load_values(st, bk, lane, 1.0, 0.5, 0.0, pert)  # an idle dummy (steady sliding, stable)

    @njit(fastmath=FAST, error_model="numpy")
    def look(st, bk, lane, i, job, out, y0, y1, K, ys, yt, err_v, work, dyt):
        """The scalar bookkeeping of a lane whose attention flag is up (the driver's loop body after the error
        test); True where the point is finished (its outputs written)."""
        pert = job.perturbation
        tau, h = st[_TAU * W + lane], st[_H * W + lane]
        steps = int(st[_NSTEP * W + lane])
        grow, per = bk.grow[lane], bk.per[lane]
        w_peak = st[_WPEAK * W + lane]
        if st[_ACC * W + lane] == 0.0:  # rejected: below the step floor, or the budget spent
            if st[_H * W + lane] < H_FLOOR * (1.0 + tau):
                finish(out, i, Regime.UNDECIDED, STEP_UNDERFLOW, grow[-1], per[-1], math.nan, bk.cycles[lane], steps,
                       w_peak)
                return True
        else:
            ze, ue, dz1, lw1 = st[_ZE * W + lane], st[_UE * W + lane], st[_DZE * W + lane], st[_LWE * W + lane]
            w_peak = max(w_peak, lw1)
            if book_state(bk, lane, i, out, lw1, max(abs(ze), abs(ue)), tau, h, pert, steps, w_peak):
                return True
            if math.isfinite(bk.t_tenth[lane]):
                st[_TENTH * W + lane] = 1.0
            dz = st[_DZ * W + lane]
            if dz > 0.0 and dz1 <= 0.0:  # a maximum of z: a cycle ends
                dt, z_top = dense_extremum(st, lane, K, yt, dyt)
                if book_maximum(bk, lane, i, out, z_top, tau + dt, pert, job.max_cycles, steps, w_peak):
                    return True
            elif dz < 0.0 and dz1 >= 0.0:  # a minimum of z
                book_minimum(bk, lane, dense_extremum(st, lane, K, yt, dyt)[1])
            # the accepted step, committed
            st[_Z * W + lane], st[_U * W + lane] = ze, ue
            st[_DZ * W + lane], st[_DU * W + lane] = dz1, st[_DUE * W + lane]
            st[_TAU * W + lane] = tau + h
            st[_SIZE * W + lane] = max(st[_SIZE * W + lane], abs(ze))
            st[_WPEAK * W + lane] = w_peak
            st[_H * W + lane] = st[_HN * W + lane]
            st[_REJ * W + lane] = 0.0
        if steps >= job.max_steps:
            finish(out, i, Regime.UNDECIDED, MAX_STEPS, grow[-1], per[-1], math.nan, bk.cycles[lane], steps, w_peak)
            return True
        return False

    variant = ("aging", "quasistatic", W)
    for kernel in (load_values, load, idle, look):
        pin(kernel, *variant)
    run_lanes = make_run_lanes(tuple(_attempt(w) for w in WIDTHS), WIDTHS, look, load, idle, _N_FIELDS, _ATTN, 2,
                               variant)
    return run_lanes, lanes_in_threads(run_lanes, W)


def driven_lanes():
    """(run_lanes, run_batch): quasi-static driven points with the aging law in lanes. run_batch(pts, job, groups,
    out) runs every point of ``job`` (:class:`DrivenJob`, over :class:`DrivenPoints`) into ``out``
    (:class:`sweep.integrate.driven.DrivenOutputs`, indexed by point) in ``groups`` strided groups on
    numba.get_num_threads() threads (:func:`sweep.integrate.batch.lanes_in_threads`)."""
    return _make_kernels()


pin_module(__name__)
