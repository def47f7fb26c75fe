"""Samples at given reduced times in the adaptive lanes: slip_at and the trajectory, with a fine twin's estimate.

The adaptive lanes of :mod:`sweep.integrate.lanes_adaptive` return the relaxed slip; here every run also records
xi and u = ln psi at its point's own increasing reduced times tau (a row of ``targets``). The state carries tau = int
e^u ds as a third component (docs/physics.md 3a, :mod:`sweep.integrate.models.stop`), tau is a component of the error
norm,
relative, as on the per-point path (:func:`sweep.integrate.stop_point.error_norm`), where psi is wanted (the
trajectory; :class:`SampledRuns` for slip_at alone), and the steps are the controller's alone: samples never
shorten a step. Each accepted step carries DOP853's continuous extension of order 7
(:mod:`sweep.integrate.dense_dop853`: three more stages, in the same lane loop, straight-line code); a sample inside
the step is the interpolant at the theta where its tau part equals the sample's time (Newton on the polynomial, in
the scalar per-lane loop: no more evaluations of the equations).

The fine twin takes every step as two half steps, each with its own continuous extension, and finds the sample on
its own interpolant at its own tau. The estimate 2 |fine - run| of :mod:`sweep.integrate.tolerance_ladder` then
bounds the run's error at a sample for the reason it bounds it at the end (the premise that the twin is at least
twice as accurate): the interpolant's error, O(h^8) like the step's own, is 2^8 times smaller on the halved mesh.
(Measured first and replaced: steps clipped in tau so as to land on every sample, 1 attempt a sample: 82 us for a
200-sample curve at rtol 1e-6, where the estimate was 1e-11 relative, 5x below the per-point path's cost.)

Samples past the transient (E < TAIL_SAFETY TAIL_TIGHTENING rtol, relaxed slip known) come from the closed-form
continuation (:func:`sweep.integrate.models.stop.continue_in_closed_form`) of the run and of its twin, each from its own
state, with the continuation's bound in u (:func:`sweep.integrate.models.stop.continuation_error`) reported per sample.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..accuracy import SAMPLES_PER_EFOLD, TAIL_RTOL, TAIL_TIGHTENING, TAU_INTEGRATED, THETA_MISS
from ..jitcache import pin, pin_module
from .batch import lanes_batch
from .dense_dop853 import EXTRA_A, INTERPOLATOR_POWER, D
from .lanes_adaptive import _LN2, LANE_TWINS, _combination, _log2_approx, _step_lines, controller_lines
from .models.stop import (
    EXP_MAX,
    FAST,
    MAX_STEPS,
    NONFINITE,
    OK,
    TAIL_SAFETY,
    continuation_error,
    continue_in_closed_form,
    make_rate,
    tail_error,
    tail_slip,
)
from .solvers import EXPLICIT_METHODS
from .solvers.controllers import ERR_FLOOR, MAX_FACTOR, MIN_FACTOR, NONFINITE_FACTOR, PI_CONTROLLER, SAFETY
from .solvers.vmath import exp_f64
from .stop_point import U_ROUNDING

LANES = 16
"""Runs in flight per thread (the relaxed-slip lanes take 32: lanes_adaptive.LANES; here, with the dense output's
fields, 32 were not faster on a 1,000-point trajectory scene: 24.2-25.7 against 23.6-23.9 us a point)."""

# lane fields, each LANES wide at offsets F * LANES of one flat array (lanes_adaptive.py: one base pointer)
_K, _A, _B, _SC, _H, _TOL, _ACC, _REJ, _LOGPREV, _EXPO = range(10)
_X, _S, _T, _DX, _DS, _DT, _E = range(10, 17)  # the run: state, derivative in sigma, E
_XF, _SF, _TF, _DXF, _DSF, _DTF, _EF = range(17, 24)  # the fine twin
_TX, _TS, _TT, _TDX, _TDS, _TDT, _TE, _TO = range(24, 32)  # the twin's tentative step, the attempt's max exponent
_PIECE = 3 * (INTERPOLATOR_POWER + 1)
"""Fields of one step's interpolant: per component (xi, s, tau) the rows F0..F6 of dense_dop853 (1) and y0."""
_RUN, _HALF = 32, 32 + _PIECE  # the run's interpolant; the twin's, first half step (the second follows it)
_N_FIELDS = _HALF + 2 * _PIECE
_COMPONENTS = ("x", "s", "t")
NEWTON_MAX = 8
"""Newton iterations at most for a sample's theta (:func:`sample_in_piece`)."""


def make_rate_t(f):
    """rate_t(xi, s, k, a, b, s_c) -> (dxi, ds, dtau, E, largest exponent): the stop equations in sigma with tau,
    dtau/dsigma = w e^u; the exponent is max(that of E, u), so that e^u beyond EXP_MAX is flagged like E."""
    rate = make_rate(f)

    @njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
    def rate_t(xi, s, k, a, b, s_c):
        dxi, w, E, expo = rate(xi, s, k, a, b, s_c)
        u = s - xi
        return dxi, w, w * exp_f64(u), E, max(expo, u)

    return pin(rate_t, np.dtype(f).name)


def _dense_lines(p: str, h: str, piece: str, n_stages: int) -> list[str]:
    """Lines that store the interpolant of the step just taken (names prefixed by ``p``, stages 1..n_stages and
    the end's derivative {p}d?e, as _step_lines leaves them) into the fields at ``piece`` (an expression of the
    first field's offset, times LANES added by the caller's field()): the three extra stages of dense_dop853 and
    the rows F0..F6 of its (1), per component, then y0."""
    stage = lambda c, j: f"{p}d{c}{j + 1}" if j < n_stages else f"{p}d{c}e" if j == n_stages else f"{p}d{c}x{j}"  # noqa: E731
    lines = []
    for s_, row in EXTRA_A.items():
        for c in ("x", "s"):
            terms = " + ".join(f"{v!r} * {stage(c, j)}" for j, v in row.items())
            lines.append(f"        {p}{c}x{s_} = {p}{c}1 + {h} * ({terms})")
        lines += [f"        {p}dxx{s_}, {p}dsx{s_}, {p}dtx{s_}, _, {p}ox{s_} = "
                  f"rate_t({p}xx{s_}, {p}sx{s_}, k, a, bb, s_c)",
                  f"        o_max = max(o_max, {p}ox{s_})"]
    for i, c in enumerate(_COMPONENTS):
        at = lambda r: f"st[{piece} + {(i * (INTERPOLATOR_POWER + 1) + r) * LANES} + l]"  # noqa: E731, B023
        lines += [f"        {p}F0{c} = {p}{c}e - {p}{c}1",
                  f"        {at(0)} = {p}F0{c}",
                  f"        {at(1)} = {h} * {stage(c, 0)} - {p}F0{c}",
                  f"        {at(2)} = 2.0 * {p}F0{c} - {h} * ({stage(c, n_stages)} + {stage(c, 0)})"]
        for r, row in enumerate(D):
            terms = " + ".join(f"{v!r} * {stage(c, j)}" for j, v in row.items())
            lines.append(f"        {at(3 + r)} = {h} * ({terms})")
        lines.append(f"        {at(INTERPOLATOR_POWER)} = {p}{c}1")
    return lines


def _sampled_source(tableau, fine, split: int) -> str:
    """Source of attempt_all(st, atol, tau_weight, norm, twin) for the sampled lanes (module docstring): the fine
    twin's ``split`` steps (none where ``twin`` is false) in one lane loop written once (as in
    lanes_adaptive._lane_source), each storing its interpolant, then the run's step and interpolant, its error norm
    over (xi, u, and tau with the weight ``tau_weight``; ``norm`` = 1 / (2 + tau_weight)), the accept mask and the PI
    controller, as selects."""
    _, _, b, e = tableau.arrays()
    n = b.size
    W = LANES
    field = lambda f: f"st[{f * W} + l]"  # noqa: E731
    tentative = tuple(field(f) for f in (_TX, _TS, _TT, _TDX, _TDS, _TDT))
    lines = [
        "def attempt_all(st, atol, tau_weight, norm, twin):",
        "    for l in range(W):",
        f"        {', '.join(tentative)}, {field(_TO)} = {field(_XF)}, {field(_SF)}, {field(_TF)}, {field(_DXF)}, "
        f"{field(_DSF)}, {field(_DTF)}, {field(_EXPO)}",
        f"    for half in range({split} if twin else 0):",
        "        for l in range(W):",
        f"            k, a, bb, s_c = st[l], {field(_A)}, {field(_B)}, {field(_SC)}",
        f"            hf, o_max = {1.0 / split!r} * {field(_H)}, {field(_TO)}",
        *("    " + line for line in _step_lines(fine, "f_", tentative, "hf", False, tau=True)),
        *("    " + line for line in _dense_lines("f_", "hf", f"{_HALF * W} + half * {_PIECE * W}", n)),
        f"            {', '.join(tentative)}, {field(_TE)}, {field(_TO)} = f_xe, f_se, f_te, f_dxe, f_dse, f_dte, "
        "f_Ee, o_max",
        "    for l in range(W):",
        f"        k, a, bb, s_c, h = st[l], {field(_A)}, {field(_B)}, {field(_SC)}, {field(_H)}",
        f"        tol, o_max = {field(_TOL)}, {field(_TO)}",
    ]
    lines += _step_lines(tableau, "", tuple(field(f) for f in (_X, _S, _T, _DX, _DS, _DT)), "h", False, tau=True)
    lines += _dense_lines("", "h", str(_RUN * W), n)
    lines += [
        f"        ex = h * ({_combination(e, 'dx', n)})",
        f"        es = h * ({_combination(e, 'ds', n)})",
        f"        et = h * ({_combination(e, 'dt', n)})",
        # stop_point.error_norm with tau: xi relative with the atol floor, u relative to min(s, max(1, u)), tau
        # relative where psi is sampled (tau_weight 1, norm 1/3; 0 and 1/2 for slip alone: SampledRuns)
        "        sx = atol + tol * max(abs(x1), abs(xe))",
        "        su = tol * min(abs(se), max(one, abs(se - xe))) + u_rounding * abs(se)",
        "        err2 = norm * ((ex / sx) ** 2 + ((es - ex) / su) ** 2 + tau_weight * (et / (tol * te)) ** 2)",
        *controller_lines(field, _LOGPREV, _REJ, _H),  # as in lanes_adaptive._lane_source
    ]
    kept = [(_X, "xe", "x1"), (_S, "se", "s1"), (_T, "te", "t1"), (_DX, "dxe", "dx1"), (_DS, "dse", "ds1"),
            (_DT, "dte", "dt1"), (_E, "Ee", field(_E))]
    kept += [(f, field(t), field(f)) for f, t in ((_XF, _TX), (_SF, _TS), (_TF, _TT), (_DXF, _TDX), (_DSF, _TDS),
                                                  (_DTF, _TDT), (_EF, _TE))]
    lines += [f"        {field(f)} = {new} if accept else {old}" for f, new, old in kept]
    lines += [f"        {field(_ACC)} = one if accept else zero", f"        {field(_REJ)} = zero if accept else one"]
    return "\n".join(lines) + "\n"


def _rate_t_call(f):
    """rate_t as a function that numba compiles once and LLVM inlines at each of the attempt's ~30 calls
    (``forceinline``, as lanes_adaptive._rates: the same machine code as numba's ``inline="always"``); inlined in
    numba's IR, the copies made attempt_all ~25 s of compile, ~10 s so (2 cores, NUMBA_CACHE_DIR empty)."""
    rate_t = make_rate_t(f)

    @njit(forceinline=True, fastmath=FAST, error_model="numpy")
    def rate_t_call(xi, s, k, a, b, s_c):
        return rate_t(xi, s, k, a, b, s_c)

    return pin(rate_t_call, np.dtype(f).name)


def _attempt(tableau, fine, split: int):
    """attempt_all(st, atol, tau_weight, norm, twin) of the sampled lanes, float64, compiled into sample_runs (generated
    source has no file to cache it by)."""
    f = np.float64
    namespace = {"rate_t": _rate_t_call(f), "exp_f64": exp_f64, "_log2_approx": _log2_approx, "W": LANES,
                 "one": f(1.0), "zero": f(0.0), "half": f(0.5), "exp_max": f(EXP_MAX),
                 "u_rounding": f(U_ROUNDING), "safety": f(SAFETY), "max_factor": f(MAX_FACTOR),
                 "min_factor": f(MIN_FACTOR), "nonfinite_factor": f(NONFINITE_FACTOR), "floor2": f(ERR_FLOOR ** 2),
                 "pi_now": f(-_LN2 * PI_CONTROLLER.alpha / (2.0 * (tableau.error_order + 1))),
                 "pi_prev": f(_LN2 * PI_CONTROLLER.beta / (2.0 * (tableau.error_order + 1))),
                 "i_now": f(-_LN2 / (2.0 * (tableau.error_order + 1))), "__name__": __name__}
    source = _sampled_source(tableau, fine, split)
    exec(compile(source, f"<sweep.integrate.lanes_sampled: {tableau.name}>", "exec"), namespace)
    return pin(njit(fastmath=FAST, error_model="numpy")(namespace["attempt_all"]), tableau.name, fine.name, split)


@njit(cache=True, fastmath=FAST, error_model="numpy")
def newton_step_for(rtol):
    """The Newton step on a sample's theta below which it has converged: quadratic convergence leaves ~ its square
    (times |tau''/tau'| <~ 3 over a step), so sqrt(THETA_MISS rtol) leaves ~1e-4 rtol, at most 1e-8 (what is left
    then is rounding): one iteration fewer than a fixed 1e-8 at rtol >= 1e-8."""
    return max(1e-8, math.sqrt(THETA_MISS * rtol))


@njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
def _basis(theta):
    """The polynomials of dense_dop853 (1) written out, y = y0 + sum_r F_r P_r(theta): P0 = theta, then alternately
    times (1 - theta) and theta (P1 = theta (1 - theta), P2 = theta^2 (1 - theta), ...), with their derivatives."""
    a, b = theta, 1.0 - theta
    p0, d0 = a, 1.0
    p1, d1 = p0 * b, d0 * b - p0
    p2, d2 = p1 * a, d1 * a + p1
    p3, d3 = p2 * b, d2 * b - p2
    p4, d4 = p3 * a, d3 * a + p3
    p5, d5 = p4 * b, d4 * b - p4
    p6, d6 = p5 * a, d5 * a + p5
    return (p0, p1, p2, p3, p4, p5, p6), (d0, d1, d2, d3, d4, d5, d6)


@njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
def _combine(st, offset, P):
    """sum_r F_r P_r of the component stored at st[offset + r LANES] (F0..F6)."""
    return (st[offset] * P[0] + st[offset + LANES] * P[1] + st[offset + 2 * LANES] * P[2]
            + st[offset + 3 * LANES] * P[3] + st[offset + 4 * LANES] * P[4] + st[offset + 5 * LANES] * P[5]
            + st[offset + 6 * LANES] * P[6])


@njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
def sample_in_piece(st, piece, lane, target, theta, theta_step):
    """(xi, u, theta, dtau/dtheta there) where the tau part of the interpolant stored at field ``piece`` equals
    ``target``: Newton on theta from the guess ``theta`` (the previous sample's Newton step continued, or the run's
    theta for the twin). tau is increasing in sigma; a target just outside [0, 1], where the twin's tau differs from
    the run's by their errors, is reached by the polynomial continued that far. Converged once a Newton step is below
    ``theta_step`` (:func:`newton_step_for`): what is left is of the order of its square."""
    base = piece * LANES + lane
    comp = (INTERPOLATOR_POWER + 1) * LANES
    t_row = base + 2 * comp
    miss0 = st[t_row + INTERPOLATOR_POWER * LANES] - target
    dt = 0.0
    for _ in range(NEWTON_MAX):
        P, dP = _basis(theta)
        dt = _combine(st, t_row, dP)
        if not dt > 0.0:
            break
        step = (miss0 + _combine(st, t_row, P)) / dt
        theta -= step
        if abs(step) <= theta_step:
            break
    P, _ = _basis(theta)
    x = st[base + INTERPOLATOR_POWER * LANES] + _combine(st, base, P)
    s = st[base + comp + INTERPOLATOR_POWER * LANES] + _combine(st, base + comp, P)
    return x, s - x, theta, dt


class SampledRuns(NamedTuple):
    """The runs of one call of the sampled lanes: run r solves point ``point[r]`` (of the LanePoints) at the control
    tolerance ``tol[r]`` from the first trial step ``h0[r]``, recording at the increasing reduced times
    ``targets[row[r]]``; the tail test as in :class:`sweep.integrate.lanes_adaptive.AdaptiveRuns` (``atol``),
    samples continued in closed form once E < TAIL_SAFETY TAIL_TIGHTENING ``rtol``; at most ``max_steps`` attempts.
    ``with_psi``: psi (u = ln psi) is wanted at the samples, and tau enters the error norm. Without it (slip_at
    alone) the steps are those of xi and u, which the slip at a given time needs: tau's relative error, in the
    norm, set the steps of the tail, 1.3x the cost of a fit's forward solve for the same slip estimates; with psi
    wanted it must stay, or psi's estimates fell below its error (1.18e-5 against 1.01e-5, rtol 1e-4).
    ``twin``: whether the fine twin runs beside the run. Without it (a caller that needs the values only: the fit's
    iterations, sweep.fit.stack) the run costs ~0.6x and everything of the twin (its relaxed slip and samples) is
    NaN: no estimate can be formed. The run's numbers are those it has beside its twin, except where the twin's
    exponent rejected an attempt (the attempt's largest exponent spans both) or the twin's E delayed the switch to
    the closed-form continuation (tests/integrate/test_lanes_sampled.py)."""

    point: np.ndarray
    row: np.ndarray
    tol: np.ndarray
    h0: np.ndarray
    targets: np.ndarray
    atol: float
    rtol: float
    max_steps: int
    with_psi: bool
    twin: bool = True


class SampledOutputs(NamedTuple):
    """Per run: the relaxed slip of the run and of its twin, their tails' summed bound, status, attempts (as
    AdaptiveOutputs); per run and sample (in the order of its targets row): xi and u of the run and of the twin, the
    continuation's bound on u (summed over both; 0 for integrated samples); the first continued sample."""

    xi_inf: np.ndarray
    fine: np.ndarray
    tail_err: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    xi_at: np.ndarray
    xi_fine: np.ndarray
    u_at: np.ndarray
    u_fine: np.ndarray
    cont_err: np.ndarray
    first_continued: np.ndarray

    @classmethod
    def empty(cls, n: int, n_t: int) -> SampledOutputs:
        """Outputs for n runs of n_t samples; the sampled arrays are left uninitialised (every sample of every run
        is written: NaN where its run failed), each is a pass over n x n_t numbers less (a 200-sample forward solve
        spent about a third of its time in such passes around the kernel)."""
        nan = lambda *shape: np.full(shape, np.nan)  # noqa: E731
        blank = lambda: np.empty((n, n_t))  # noqa: E731
        return cls(nan(n), nan(n), nan(n), np.zeros(n, np.int8), np.zeros(n, np.int32), blank(), blank(), blank(),
                   blank(), blank(), np.full(n, n_t, np.int64))


def make_sampled_lane_kernels(tableau, fine, split: int):
    """(sample_runs, sample_batch) for an embedded explicit pair without FSAL, float64: points in a
    :class:`sweep.integrate.lanes.LanePoints`, runs in a :class:`SampledRuns`, results in a :class:`SampledOutputs`."""
    f = np.float64
    rate_t = make_rate_t(f)
    attempt_all = _attempt(tableau, fine, split)
    W = LANES
    zero, one, nan = 0.0, 1.0, math.nan

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def load(st, lane, k, a, b, s_c, tol, h):
        """A run from (xi, s, tau) = 0 into ``lane``."""
        st[_K * W + lane], st[_A * W + lane], st[_B * W + lane], st[_SC * W + lane] = k, a, b, s_c
        st[_H * W + lane], st[_TOL * W + lane] = h, tol
        dxi, ds, dtau, E, expo = rate_t(zero, zero, k, a, b, s_c)
        for base in (_X, _XF):  # the run and its twin
            st[(base + _X - _X) * W + lane], st[(base + _S - _X) * W + lane] = zero, zero
            st[(base + _T - _X) * W + lane] = zero
            st[(base + _DX - _X) * W + lane], st[(base + _DS - _X) * W + lane] = dxi, ds
            st[(base + _DT - _X) * W + lane], st[(base + _E - _X) * W + lane] = dtau, E
        st[_EXPO * W + lane] = expo
        st[_ACC * W + lane], st[_REJ * W + lane], st[_LOGPREV * W + lane] = zero, zero, zero

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def take_next(st, lane, lane_run, next_j, runs, queued, pts, job, out):
        """Load the next queued run into ``lane`` (samples at tau <= 0 recorded at once), or an idle dummy (-1)."""
        if queued < runs.size:
            r = runs[queued]
            p = job.point[r]
            row = job.targets[job.row[r]]
            j = 0
            while j < row.size and row[j] <= 0.0:
                out.xi_at[r, j], out.xi_fine[r, j], out.u_at[r, j], out.u_fine[r, j] = zero, zero, zero, zero
                out.cont_err[r, j] = zero
                j += 1
            next_j[lane] = j
            load(st, lane, pts.k[p], pts.a[p], pts.b[p], pts.s_c[p], job.tol[r], job.h0[r])
            lane_run[lane] = r
            return queued + 1
        load(st, lane, one, one, zero, one, one, zero)
        lane_run[lane] = -1
        return queued

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def continue_samples(st, lane, r, j, k, a, bb, job, out):
        """Samples j.. of run r from the closed-form continuation of the run and of its twin (NaN without one), each
        from its own state and relaxed slip, with the continuation's bound on u."""
        row = job.targets[job.row[r]]
        for base, x_inf, x_at, u_at in ((_X, out.xi_inf[r], out.xi_at[r], out.u_at[r]),
                                        (_XF, out.fine[r], out.xi_fine[r], out.u_fine[r])):
            if base == _XF and not job.twin:
                x_at[j:], u_at[j:] = nan, nan
                continue
            x, s, tau = st[base * W + lane], st[(base + _S - _X) * W + lane], st[(base + _T - _X) * W + lane]
            E = st[(base + _E - _X) * W + lane]
            continue_in_closed_form(k, a, bb, x_inf, s - x, tau, row[j:], x_at[j:], u_at[j:])
            for i in range(j, row.size):
                bound = continuation_error(E, a + 2.0 * bb * (s - x), u_at[i] - (s - x))
                out.cont_err[r, i] = (out.cont_err[r, i] if base == _XF else 0.0) + bound  # run, then + twin
        out.first_continued[r] = j

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def sample_runs(pts, job, runs, out):
        """Solve the runs ``runs`` of ``job`` into ``out``: samples, relaxed slip, status."""
        st = np.zeros(_N_FIELDS * W)
        lane_run = np.full(W, -1, np.int64)
        next_j = np.zeros(W, np.int64)
        tail_done = np.zeros(W, np.bool_)
        n = np.zeros(W, np.int64)
        queued, busy = 0, 0
        atol, max_steps = job.atol, job.max_steps
        e_continue = TAIL_SAFETY * TAIL_TIGHTENING * job.rtol
        theta_step = newton_step_for(job.rtol)
        tau_weight = 1.0 if job.with_psi else 0.0
        norm = 1.0 / (2.0 + tau_weight)
        twin = job.twin
        for lane in range(W):
            queued = take_next(st, lane, lane_run, next_j, runs, queued, pts, job, out)
            busy += lane_run[lane] >= 0
        while busy > 0:
            attempt_all(st, atol, tau_weight, norm, twin)
            for lane in range(W):
                r = lane_run[lane]
                if r < 0:
                    continue
                n[lane] += 1
                if st[_ACC * W + lane] == zero and n[lane] < max_steps:
                    continue  # rejected: the lane retries with its smaller step
                p = job.point[r]
                k, a, bb = pts.k[p], pts.a[p], pts.b[p]
                xi, u, E = st[_X * W + lane], st[_S * W + lane] - st[_X * W + lane], st[_E * W + lane]
                xf, uf, Ef = st[_XF * W + lane], st[_SF * W + lane] - st[_XF * W + lane], st[_EF * W + lane]
                j = next_j[lane]
                n_t = job.targets.shape[1]
                finished = False
                if not math.isfinite(xi):
                    out.status[r], finished = NONFINITE, True
                elif st[_ACC * W + lane] == zero:
                    out.status[r], finished = MAX_STEPS, True
                else:
                    row = job.targets[job.row[r]]
                    t_end, t_mid = st[_T * W + lane], st[(_HALF + 2 * _PIECE - 1) * W + lane]  # the twin's midpoint tau
                    # the first guess of each sample: a Newton step from the previous one's theta with its slope
                    # (from theta = 0 for the first in the step: tau = F0 theta + F1 theta (1 - theta) + ...)
                    theta, t_prev = 0.0, st[(_RUN + 2 * (INTERPOLATOR_POWER + 1) + INTERPOLATOR_POWER) * W + lane]
                    slope = st[(_RUN + 2 * (INTERPOLATOR_POWER + 1)) * W + lane] + st[
                        (_RUN + 2 * (INTERPOLATOR_POWER + 1) + 1) * W + lane]
                    while j < n_t and row[j] <= t_end:  # samples inside this step, from the interpolants
                        guess = theta + (row[j] - t_prev) / slope if slope > 0.0 else 0.5
                        out.xi_at[r, j], out.u_at[r, j], theta, slope = sample_in_piece(st, _RUN, lane, row[j], guess,
                                                                                         theta_step)
                        t_prev = row[j]
                        if twin:
                            second = row[j] > t_mid  # in the twin's second half step
                            out.xi_fine[r, j], out.u_fine[r, j], _, _ = sample_in_piece(
                                st, _HALF + _PIECE if second else _HALF, lane, row[j],
                                2.0 * theta - (1.0 if second else 0.0), theta_step)
                        else:
                            out.xi_fine[r, j], out.u_fine[r, j] = nan, nan
                        out.cont_err[r, j] = zero
                        j += 1
                    next_j[lane] = j
                    if not tail_done[lane]:
                        bound = tail_error(k, a, bb, u, E)
                        if bound <= TAIL_SAFETY * (TAIL_RTOL * xi + atol):  # negligible: see TAIL_RTOL
                            out.xi_inf[r] = xi + tail_slip(k, a, bb, u, E)
                            if twin:
                                out.fine[r] = xf + tail_slip(k, a, bb, uf, Ef)
                                bound += tail_error(k, a, bb, uf, Ef)
                            out.tail_err[r] = bound
                            tail_done[lane] = True
                    if (tail_done[lane] and j < n_t and E < e_continue and (Ef < e_continue or not twin)
                            and (row[j] > TAU_INTEGRATED
                                 or n_t - j < SAMPLES_PER_EFOLD * math.log(row[n_t - 1] / t_end))):
                        continue_samples(st, lane, r, j, k, a, bb, job, out)
                        j = n_t
                        next_j[lane] = j
                    if tail_done[lane] and j >= n_t:
                        out.status[r], finished = OK, True
                    elif n[lane] >= max_steps:
                        out.status[r], finished = MAX_STEPS, True
                if not finished:
                    continue
                if out.status[r] != OK:
                    out.xi_inf[r] = math.nan
                    for i in range(next_j[lane], n_t):  # never reached
                        out.xi_at[r, i], out.xi_fine[r, i], out.u_at[r, i], out.u_fine[r, i] = nan, nan, nan, nan
                        out.cont_err[r, i] = nan
                out.steps[r] = n[lane]
                n[lane] = 0
                tail_done[lane] = False
                queued = take_next(st, lane, lane_run, next_j, runs, queued, pts, job, out)
                busy -= lane_run[lane] < 0

    for kernel in (load, take_next, continue_samples, sample_runs):
        pin(kernel, tableau.name, fine.name, split)
    return sample_runs, pin(lanes_batch(sample_runs, W), tableau.name, fine.name, split)


@functools.cache
def sampled_lane_kernels(method: str):
    """(sample_runs, sample_batch) of an embedded pair of :data:`sweep.integrate.solvers.EXPLICIT_METHODS` with its
    fine twin
    (:data:`sweep.integrate.lanes_adaptive.LANE_TWINS`), built once per process (numba compiles on first call and
    caches on disk): only scenes with sampled times in the adaptive lanes build it."""
    fine, split = LANE_TWINS[method]
    return make_sampled_lane_kernels(EXPLICIT_METHODS[method], EXPLICIT_METHODS[fine], split)


pin_module(__name__)
