"""Samples at given reduced times in the adaptive lanes: slip_at and the trajectory, with a fine twin's estimate.

The adaptive lanes of :mod:`sweep.integrate.lanes_adaptive` return the relaxed slip; here every run also records
xi and u = ln psi at its point's own increasing reduced times tau (a row of ``targets``). The state carries tau = int
e^u ds as a third component (docs/physics.md 3a, :mod:`sweep.models.stop`), and a step that would reach the next
sample is taken *in tau*: the same tableau on the same equations divided by dtau/dsigma, from the same state, with
the step tau_target - tau, so that it ends exactly on the sample (no interpolant, no Newton inside a step). Which
steps are taken in tau is a per-lane mode ``m``, a select in the lane loop (each stage's derivative is multiplied
by 1/(dtau/dsigma) or 1), so the loop stays straight-line code and vectorises. The controller's own proposal in
sigma is kept for the step after a sample (a step onto a sample is a clipped step: it neither grows nor replaces
the proposal, unless it is rejected). A step in sigma predicted (linearly) to stop short of the sample but ending
past it (tau is convex in sigma) is retried in tau, its proposal unchanged.

The fine twin takes every step as two half steps, in tau where the run's step is in tau (from its own tau, so that
it too lands on the sample): the samples are then mesh points of both, and the estimate 2 |fine - run| of
:mod:`sweep.integrate.tolerance_ladder` holds there for the reason it holds for the relaxed slip (the fine twin on
the mesh halved is at least twice as accurate). tau is a component of the error norm, relative, as on the per-point
path (:func:`sweep.integrate.stop_point.error_norm`): a sample's slip error includes xi' times the error of tau.

Samples past the transient (E < TAIL_SAFETY TAIL_TIGHTENING rtol, relaxed slip known) come from the closed-form
continuation (:func:`sweep.models.stop.continue_in_closed_form`) of the run and of its twin, each from its own
state, with the continuation's bound in u (:func:`sweep.models.stop.continuation_error`) reported per sample.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..accuracy import TAIL_RTOL, TAIL_TIGHTENING
from ..jitcache import pin, pin_module
from ..models.stop import (
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
from ..solvers import EXPLICIT_METHODS
from ..solvers.controllers import ERR_FLOOR, MAX_FACTOR, MIN_FACTOR, NONFINITE_FACTOR, PI_CONTROLLER, SAFETY
from ..solvers.vmath import exp_f64
from .batch import lanes_batch
from .lanes_adaptive import _LN2, LANE_TWINS, LANES, _combination, _log2_approx, _step_lines
from .stop_point import U_ROUNDING

# lane fields, each LANES wide at offsets F * LANES of one flat array (lanes_adaptive.py: one base pointer)
_K, _A, _B, _SC, _H, _TOL, _ACC, _REJ, _LOGPREV, _EXPO = range(10)
_X, _S, _T, _DX, _DS, _DT, _E = range(10, 17)  # the run: state, derivative in sigma, E
_XF, _SF, _TF, _DXF, _DSF, _DTF, _EF = range(17, 24)  # the fine twin
_TX, _TS, _TT, _TDX, _TDS, _TDT, _TE, _TO = range(24, 32)  # the twin's tentative step, the attempt's max exponent
_TG, _M, _FORCE, _HF = range(32, 36)  # next sample time, mode (1: step in tau), forced tau step, twin's step
_N_FIELDS = 36


def make_rate_t(f):
    """rate_t(xi, s, k, a, b, s_c, m) -> (dxi, ds, dtau, E, largest exponent): the stop equations in sigma with tau
    (dtau/dsigma = w e^u) if m = 0, in tau (each divided by dtau/dsigma) if m = 1; the exponent is max(that of E, u),
    so that e^u beyond EXP_MAX is flagged like E."""
    rate = make_rate(f)
    one = f(1.0)

    @njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
    def rate_t(xi, s, k, a, b, s_c, m):
        dxi, w, E, expo = rate(xi, s, k, a, b, s_c)
        u = s - xi
        dtau = w * exp_f64(u)
        inv = m / dtau + (one - m)  # m is 0 or 1; arithmetic, not a select: LLVM will not speculate a division
        return dxi * inv, w * inv, dtau * inv, E, max(expo, u)

    return pin(rate_t, np.dtype(f).name)


def _sampled_source(tableau, fine, split: int) -> str:
    """Source of attempt_all(st, atol) for the sampled lanes (module docstring): the mode of each lane, the fine
    twin's ``split`` steps in one lane loop written once (as in lanes_adaptive._lane_source), then the run's step,
    its error norm over (xi, u, tau), the accept mask and the controller, all as selects."""
    _, _, b, e = tableau.arrays()
    W = LANES
    field = lambda f: f"st[{f * W} + l]"  # noqa: E731
    X, S, T, H, DT, TG = (field(f) for f in (_X, _S, _T, _H, _DT, _TG))
    tentative = tuple(field(f) for f in (_TX, _TS, _TT, _TDX, _TDS, _TDT))
    lines = [
        "def attempt_all(st, atol):",
        "    for l in range(W):",
        # a step in tau onto the next sample where the controller's step reaches it by the linear prediction, or
        # after a step in sigma that passed it
        f"        m = one if ({TG} - {T} <= {H} * {DT} or {field(_FORCE)} > half) else zero",
        f"        {field(_M)} = m",
        f"        {field(_HF)} = ({TG} - {field(_TF)} if m > half else {H}) * {1.0 / split!r}",
        f"        {', '.join(tentative)}, {field(_TO)} = {field(_XF)}, {field(_SF)}, {field(_TF)}, {field(_DXF)}, "
        f"{field(_DSF)}, {field(_DTF)}, {field(_EXPO)}",
        f"    for _ in range({split}):",
        "        for l in range(W):",
        f"            k, a, bb, s_c = st[l], {field(_A)}, {field(_B)}, {field(_SC)}",
        f"            hf, m, o_max = {field(_HF)}, {field(_M)}, {field(_TO)}",
        *("    " + line for line in _step_lines(fine, "f_", tentative, "hf", False, tau=True)),
        f"            {', '.join(tentative)}, {field(_TE)}, {field(_TO)} = f_xe, f_se, f_te, f_dxe, f_dse, f_dte, "
        "f_Ee, o_max",
        "    for l in range(W):",
        f"        k, a, bb, s_c, m = st[l], {field(_A)}, {field(_B)}, {field(_SC)}, {field(_M)}",
        f"        h = {TG} - {T} if m > half else {H}",
        f"        tol, o_max = {field(_TOL)}, {field(_TO)}",
    ]
    lines += _step_lines(tableau, "", (X, S, T, field(_DX), field(_DS), DT), "h", False, tau=True)
    lines += [
        f"        ex = h * ({_combination(e, 'dx', b.size)})",
        f"        es = h * ({_combination(e, 'ds', b.size)})",
        f"        et = h * ({_combination(e, 'dt', b.size)})",
        # stop_point.error_norm with tau: xi relative with the atol floor, u relative to min(s, max(1, u)), tau
        # relative (zero in a step in tau)
        "        sx = atol + tol * max(abs(x1), abs(xe))",
        "        su = tol * min(abs(se), max(one, abs(se - xe))) + u_rounding * abs(se)",
        "        err2 = third * ((ex / sx) ** 2 + ((es - ex) / su) ** 2 + (et / (tol * te)) ** 2)",
        "        finite = o_max <= exp_max and err2 == err2",
        "        accept = finite and err2 <= one",
        # as 0/1 floats, not booleans: the branches of "and"/"or" around these stopped the vectoriser
        f"        over = (one if te > {TG} else zero) * (one - m) * (one if accept else zero)",
        "        accept = accept and over < half",
        "        log_err2 = _log2_approx(max(err2, floor2))",
        f"        log_prev = {field(_LOGPREV)}",
        "        factor_pi = safety * exp_f64(pi_now * log_err2 + pi_prev * log_prev)",
        "        factor_i = safety * exp_f64(i_now * log_err2)",
        "        factor = min(max_factor, max(min_factor, factor_pi if accept else factor_i))",
        f"        factor = min(factor, one) if ({field(_REJ)} > half or not accept) else factor",
        # the controller's memory and proposal follow the steps in sigma; a rejected step in tau shrinks the
        # proposal from its equivalent in sigma (h / dtau at its start: at most its length, tau being convex)
        f"        {field(_LOGPREV)} = log_err2 if accept and m < half else log_prev",
        f"        h_sigma = h / {DT}",  # outside the select: a division in a branch is not if-converted
        f"        shrunk = (min({H}, h_sigma) if m > half else {H}) * (factor if finite else nonfinite_factor)",
        f"        {H} = {H} if max(over, m * (one if accept else zero)) > half else shrunk",
        f"        {field(_FORCE)} = over",
    ]
    kept = [(_X, "xe", "x1"), (_S, "se", "s1"), (_T, "te", "t1"), (_DX, "dxe", field(_DX)), (_DS, "dse", field(_DS)),
            (_DT, "dte", DT), (_E, "Ee", field(_E))]
    kept += [(f, field(t), field(f)) for f, t in ((_XF, _TX), (_SF, _TS), (_TF, _TT), (_DXF, _TDX), (_DSF, _TDS),
                                                  (_DTF, _TDT), (_EF, _TE))]
    lines += [f"        {field(f)} = {new} if accept else {old}" for f, new, old in kept]
    lines += [f"        {field(_ACC)} = one if accept else zero", f"        {field(_REJ)} = zero if accept else one"]
    return "\n".join(lines) + "\n"


def _attempt(tableau, fine, split: int):
    """attempt_all(st, atol) of the sampled lanes, float64, compiled into sample_runs (generated source has no file
    to cache it by)."""
    f = np.float64
    namespace = {"rate_t": make_rate_t(f), "exp_f64": exp_f64, "_log2_approx": _log2_approx, "W": LANES,
                 "one": f(1.0), "zero": f(0.0), "half": f(0.5), "third": f(1.0 / 3.0), "exp_max": f(EXP_MAX),
                 "u_rounding": f(U_ROUNDING), "safety": f(SAFETY), "max_factor": f(MAX_FACTOR),
                 "min_factor": f(MIN_FACTOR), "nonfinite_factor": f(NONFINITE_FACTOR), "floor2": f(ERR_FLOOR ** 2),
                 "pi_now": f(-_LN2 * PI_CONTROLLER.alpha / (2.0 * (tableau.error_order + 1))),
                 "pi_prev": f(_LN2 * PI_CONTROLLER.beta / (2.0 * (tableau.error_order + 1))),
                 "i_now": f(-_LN2 / (2.0 * (tableau.error_order + 1))), "__name__": __name__}
    source = _sampled_source(tableau, fine, split)
    exec(compile(source, f"<sweep.integrate.lanes_sampled: {tableau.name}>", "exec"), namespace)
    return pin(njit(fastmath=FAST, error_model="numpy")(namespace["attempt_all"]), tableau.name, fine.name, split)


class SampledRuns(NamedTuple):
    """The runs of one call of the sampled lanes: run r solves point ``point[r]`` (of the LanePoints) at the control
    tolerance ``tol[r]`` from the first trial step ``h0[r]``, recording at the increasing reduced times
    ``targets[row[r]]``; the tail test as in :class:`sweep.integrate.lanes_adaptive.AdaptiveRuns` (``atol``),
    samples continued in closed form once E < TAIL_SAFETY TAIL_TIGHTENING ``rtol``; at most ``max_steps`` attempts."""

    point: np.ndarray
    row: np.ndarray
    tol: np.ndarray
    h0: np.ndarray
    targets: np.ndarray
    atol: float
    rtol: float
    max_steps: int


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
        nan = lambda *shape: np.full(shape, np.nan)  # noqa: E731
        return cls(nan(n), nan(n), nan(n), np.zeros(n, np.int8), np.zeros(n, np.int32), nan(n, n_t), nan(n, n_t),
                   nan(n, n_t), nan(n, n_t), np.zeros((n, n_t)), np.full(n, n_t, np.int64))


def make_sampled_lane_kernels(tableau, fine, split: int):
    """(sample_runs, sample_batch) for an embedded explicit pair without FSAL, float64: points in a
    :class:`sweep.integrate.lanes.LanePoints`, runs in a :class:`SampledRuns`, results in a :class:`SampledOutputs`."""
    f = np.float64
    rate_t = make_rate_t(f)
    attempt_all = _attempt(tableau, fine, split)
    W = LANES
    zero, one, inf = 0.0, 1.0, math.inf

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def load(st, lane, k, a, b, s_c, tol, h, target):
        """A run from (xi, s, tau) = 0 into ``lane``, its next sample time ``target``."""
        st[_K * W + lane], st[_A * W + lane], st[_B * W + lane], st[_SC * W + lane] = k, a, b, s_c
        st[_H * W + lane], st[_TOL * W + lane], st[_TG * W + lane] = h, tol, target
        dxi, ds, dtau, E, expo = rate_t(zero, zero, k, a, b, s_c, zero)
        for base in (_X, _XF):  # the run and its twin
            st[(base + _X - _X) * W + lane], st[(base + _S - _X) * W + lane] = zero, zero
            st[(base + _T - _X) * W + lane] = zero
            st[(base + _DX - _X) * W + lane], st[(base + _DS - _X) * W + lane] = dxi, ds
            st[(base + _DT - _X) * W + lane], st[(base + _E - _X) * W + lane] = dtau, E
        st[_EXPO * W + lane] = expo
        st[_ACC * W + lane], st[_REJ * W + lane], st[_LOGPREV * W + lane] = zero, zero, zero
        st[_FORCE * W + lane], st[_M * W + lane] = zero, zero

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def next_target(job, r, j):
        """The time of sample j of run r, inf past the last."""
        row = job.targets[job.row[r]]
        return row[j] if j < row.size else inf

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
                j += 1
            next_j[lane] = j
            load(st, lane, pts.k[p], pts.a[p], pts.b[p], pts.s_c[p], job.tol[r], job.h0[r], next_target(job, r, j))
            lane_run[lane] = r
            return queued + 1
        load(st, lane, one, one, zero, one, one, zero, inf)
        lane_run[lane] = -1
        return queued

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def continue_samples(st, lane, r, j, k, a, bb, job, out):
        """Samples j.. of run r from the closed-form continuation of the run and of its twin, each from its own
        state and relaxed slip, with the continuation's bound on u."""
        row = job.targets[job.row[r]]
        for base, x_inf, x_at, u_at, sign in ((_X, out.xi_inf[r], out.xi_at[r], out.u_at[r], 1.0),
                                              (_XF, out.fine[r], out.xi_fine[r], out.u_fine[r], -1.0)):
            x, s, tau = st[base * W + lane], st[(base + _S - _X) * W + lane], st[(base + _T - _X) * W + lane]
            E = st[(base + _E - _X) * W + lane]
            continue_in_closed_form(k, a, bb, x_inf, s - x, tau, row[j:], x_at[j:], u_at[j:])
            for i in range(j, row.size):
                out.cont_err[r, i] += continuation_error(E, a + 2.0 * bb * (s - x), u_at[i] - (s - x))
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
        for lane in range(W):
            queued = take_next(st, lane, lane_run, next_j, runs, queued, pts, job, out)
            busy += lane_run[lane] >= 0
        while busy > 0:
            attempt_all(st, atol)
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
                    if st[_M * W + lane] > 0.5:  # landed on sample j (run and twin)
                        out.xi_at[r, j], out.xi_fine[r, j], out.u_at[r, j], out.u_fine[r, j] = xi, xf, u, uf
                        j += 1
                        next_j[lane] = j
                        st[_TG * W + lane] = next_target(job, r, j)
                    if not tail_done[lane]:
                        bound = tail_error(k, a, bb, u, E)
                        if bound <= TAIL_SAFETY * (TAIL_RTOL * xi + atol):  # negligible: see TAIL_RTOL
                            out.xi_inf[r], out.fine[r] = xi + tail_slip(k, a, bb, u, E), xf + tail_slip(k, a, bb, uf, Ef)
                            out.tail_err[r] = bound + tail_error(k, a, bb, uf, Ef)
                            tail_done[lane] = True
                    if tail_done[lane] and j < n_t and E < e_continue and Ef < e_continue:
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
                out.steps[r] = n[lane]
                n[lane] = 0
                tail_done[lane] = False
                queued = take_next(st, lane, lane_run, next_j, runs, queued, pts, job, out)
                busy -= lane_run[lane] < 0

    for kernel in (load, next_target, take_next, continue_samples, sample_runs):
        pin(kernel, tableau.name, fine.name, split)
    return sample_runs, pin(lanes_batch(sample_runs, W), tableau.name, fine.name, split)


@functools.cache
def sampled_lane_kernels(method: str):
    """(sample_runs, sample_batch) of an embedded pair of :data:`sweep.solvers.EXPLICIT_METHODS` with its fine twin
    (:data:`sweep.integrate.lanes_adaptive.LANE_TWINS`), built once per process (numba compiles on first call and
    caches on disk): only scenes with sampled times in the adaptive lanes build it."""
    fine, split = LANE_TWINS[method]
    return make_sampled_lane_kernels(EXPLICIT_METHODS[method], EXPLICIT_METHODS[fine], split)


pin_module(__name__)
