"""Relaxed slip in lockstep lanes with an embedded Runge-Kutta pair: every lane keeps its own step and its own
accept/reject decision.

The fixed-step lanes (:mod:`sweep.integrate.lanes`) spend their evaluations evenly along sigma and need a ladder of
runs to find the step and the error; an embedded pair (dp5, dop853) puts the steps where the solution needs them and
reaches tight tolerances with a fraction of the evaluations. Here each of the LANES runs in flight carries its own
step h and control tolerance, and one pass of the lane loops (one loop per stage: :func:`_stage_loops`) is one
*attempt* of every lane: the stages, the embedded error norm, the accept mask and the next step are computed for all
lanes as straight-line code (selects, not branches: a branch in a lane loop stops LLVM's vectoriser), so a rejected
lane simply keeps its state and retries with a smaller step while its neighbours move on. The step factor needs
err^(-1/(q+1)), a power that numba would compute with a scalar libm call; it is taken as exp2 of a cheap log2
(:func:`_log2_approx`, 0.5 % accurate: a step factor needs no more) so that the loop stays vectorised.

Whether the closed-form tail may take over is tested in the vectorised loop that closes an attempt
(:func:`_tail_lines`); the per-lane bookkeeping (finishing a run, refilling its lane) is a short scalar loop, as in
the fixed-step lanes. A run's arithmetic does not depend on which lane or neighbours it had.

The compiled entry point is ``relax_runs`` itself (``nogil``, no calls left in its lane loops), called from Python
threads by :func:`sweep.integrate.batch.lanes_in_threads` rather than from a ``prange`` loop: a kernel compiled in the
process and one loaded from numba's cache then run the same code and give the same bits (docs/design.md,
"Adaptive lanes"). ``load`` and ``take_next`` are inlined into it in numba's IR; the generated attempt and the
right-hand sides it calls ~60 times are compiled by numba once each and inlined by LLVM (``forceinline``,
:func:`_rates`): inlined in numba's IR they took ~2/3 of a cold default run (numba copies a callee's IR at every
call site, block by block, and types and lowers each copy again), for the same machine code.

Error estimate of a point: :mod:`sweep.integrate.tolerance_ladder` (each run's fine twin on the mesh halved, and a
run again at a tighter control tolerance where the estimate exceeds the tolerance).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..accuracy import E_TAIL_MAX, TAIL_RTOL, TAIL_SHARE
from ..jitcache import pin, pin_module
from .batch import lanes_in_threads
from .models.stop import (
    EXP_MAX,
    FAST,
    MAX_STEPS,
    NONFINITE,
    OK,
    TAIL_SAFETY,
    make_rate,
    tail_bound,
    tail_error,
    tail_slip,
)
from .models.stop_inertial import make_correction_rate, tail_correction
from .solvers import EXPLICIT_METHODS
from .solvers.controllers import ERR_FLOOR, MAX_FACTOR, MIN_FACTOR, NONFINITE_FACTOR, PI_CONTROLLER, SAFETY
from .solvers.vmath import exp_f64
from .solvers.vmath import log2_approx as _log2_approx
from .stop_point import U_ROUNDING

LANES = 32
"""Runs in flight per thread: more independent lanes for each stage loop to overlap. Measured (model
"quasistatic", ``execute``, 1 thread, us a point, 8 / 16 / 32 / 64 lanes): default scene 1.13 / 0.97 / 0.91 / 0.98
at rtol 1e-3, 1.80 / 1.51 / 1.38 / 1.49 at 1e-6, 4.61 / 3.70 / 3.31 / 3.52 at 1e-9; its costly corner 2.42 / 2.01 /
1.88 / 2.08, 3.71 / 3.04 / 2.77 / 3.03, 9.58 / 7.63 / 6.86 / 7.31. A run's numbers do not depend on its lane."""

# lane fields (each LANES wide, at offsets F * LANES of one flat array: one base pointer, so LLVM proves the lane
# loops free of aliasing)
_K, _A, _B, _SC, _H, _X, _S, _DX, _DS, _E, _EXPO, _TOL, _ACC, _REJ = range(14)
_LOGPREV = 14  # log2 of the previous accepted error norm squared (the PI controller's memory)
_XF, _SF, _DXF, _DSF, _EF = 15, 16, 17, 18, 19  # the fine run: state, derivative, E
_TX, _TS, _TDX, _TDS, _TE, _TO = 20, 21, 22, 23, 24, 25  # the fine run's tentative step, and the attempt's max exponent
_G, _Y, _DY = 26, 27, 28  # with the first-order inertial correction: G = gamma/A, the correction y, dy/dsigma

_LN2 = math.log(2.0)


def _combination(weights, symbol: str, count: int) -> str:
    """"w1 * symbol1 + ..." over the first ``count`` weights, zero weights left out (as literals: see _lane_source)."""
    return " + ".join(f"{float(weights[j])!r} * {symbol}{j + 1}" for j in range(count) if weights[j] != 0.0)


def _step_lines(tableau, p: str, start: tuple[str, ...], h: str, correction: bool, tau: bool = False) -> list[str]:
    """Lines of one step of size ``h`` from the state (x, s) with its derivative (dx, ds) (``start``: four
    expressions), every name prefixed by ``p``: stages {p}x2.., the end state {p}xe, {p}se with its derivative
    {p}dxe, {p}dse, E {p}Ee and exponent {p}oe; o_max takes the largest exponent. With ``correction`` the stages
    also carry y from ({p}y1, {p}dy1), ending in {p}ye, {p}dye.

    With ``tau`` (:mod:`sweep.integrate.lanes_sampled`) the state is (x, s, t) with t = tau, ``start`` six
    expressions (x, s, t, dx, ds, dt), the right-hand side ``rate_t`` and the end's derivative {p}dxe, {p}dse,
    {p}dte."""
    c, A, b, e = tableau.arrays()
    last = b.size - 1 if tableau.fsal else b.size  # stages evaluated before the step's end
    if tau:
        x0, s0, t0, dx0, ds0, dt0 = start
        lines = [f"        {p}x1, {p}s1, {p}t1, {p}dx1, {p}ds1, {p}dt1 = {x0}, {s0}, {t0}, {dx0}, {ds0}, {dt0}"]
        evaluate = "{p}dx{i}, {p}ds{i}, {p}dt{i}, {p}E{i}, {p}o{i} = rate_t({p}x{i}, {p}s{i}, k, a, bb, s_c)"
    else:
        x0, s0, dx0, ds0 = start
        lines = [f"        {p}x1, {p}s1, {p}dx1, {p}ds1 = {x0}, {s0}, {dx0}, {ds0}"]
        evaluate = "{p}dx{i}, {p}ds{i}, {p}E{i}, {p}o{i} = rate({p}x{i}, {p}s{i}, k, a, bb, s_c)"
    for i in range(2, last + 1):
        lines += [f"        {p}x{i} = {p}x1 + {h} * ({_combination(A[i - 1], p + 'dx', i - 1)})",
                  f"        {p}s{i} = {p}s1 + {h} * ({_combination(A[i - 1], p + 'ds', i - 1)})",
                  "        " + evaluate.format(p=p, i=i),
                  f"        o_max = max(o_max, {p}o{i})"]
        if correction:
            lines += [f"        {p}dy{i} = correction_rate({p}x{i}, {p}s{i}, "
                      f"{p}y1 + {h} * ({_combination(A[i - 1], p + 'dy', i - 1)}), k, a, bb, G, {p}ds{i}, {p}E{i}, "
                      f"{p}o{i})"]
    lines += [f"        {p}xe = {p}x1 + {h} * ({_combination(b, p + 'dx', last)})",
              f"        {p}se = {p}s1 + {h} * ({_combination(b, p + 'ds', last)})"]
    if tau:
        lines += [f"        {p}te = {p}t1 + {h} * ({_combination(b, p + 'dt', last)})",
                  f"        {p}dxe, {p}dse, {p}dte, {p}Ee, {p}oe = rate_t({p}xe, {p}se, k, a, bb, s_c)"]
    else:
        lines += [f"        {p}dxe, {p}dse, {p}Ee, {p}oe = rate({p}xe, {p}se, k, a, bb, s_c)"]
    lines += [f"        o_max = max(o_max, {p}oe)"]
    if correction:
        lines += [f"        {p}ye = {p}y1 + {h} * ({_combination(b, p + 'dy', last)})",
                  f"        {p}dye = correction_rate({p}xe, {p}se, {p}ye, k, a, bb, G, {p}dse, {p}Ee, {p}oe)"]
    if tableau.fsal:
        lines += [f"        {p}dx{b.size}, {p}ds{b.size} = {p}dxe, {p}dse"]
        lines += [f"        {p}dt{b.size} = {p}dte"] if tau else []
    return lines


def controller_lines(field, logprev: int, rej: int, h: int) -> list[str]:
    """Generated lines of a lane loop's accept decision and next step, from the attempt's error norm squared
    ``err2`` and largest exponent ``o_max``; ``field(f)`` names lane field f, ``logprev``, ``rej`` and ``h`` are the
    fields of the previous accepted norm's log2, the last rejection and the step (shared by the sampled lanes,
    sweep/integrate/lanes_sampled.py)."""
    return [
        # an exponent beyond EXP_MAX anywhere in the attempt (exp is clamped there) or a NaN: no norm to go by
        "        finite = o_max <= exp_max and err2 == err2",
        "        accept = finite and err2 <= one",
        "        log_err2 = _log2_approx(max(err2, floor2))",
        # accepted: Gustafsson's PI factor from this and the previous accepted norm (smooth steps where they are
        # stability-limited, as on the creep manifold); rejected: the I factor, at most 1
        f"        log_prev = {field(logprev)}",
        "        factor_pi = safety * exp_f64(pi_now * log_err2 + pi_prev * log_prev)",
        "        factor_i = safety * exp_f64(i_now * log_err2)",
        "        factor = min(max_factor, max(min_factor, factor_pi if accept else factor_i))",
        f"        factor = min(factor, one) if ({field(rej)} > half or not accept) else factor",
        f"        {field(logprev)} = log_err2 if accept else log_prev",
        f"        {field(h)} = h * (factor if finite else nonfinite_factor)",
    ]


_OM = 29  # the attempt's largest exponent so far (the stage loops keep it per lane)
_DONE = 30  # 1 where the attempt was accepted and the closed-form tail may take over (:func:`_tail_lines`)
_STAGES = 31
"""First of the stage fields: stage j >= 2 of the step under way at _STAGES + width (j - 2) (:func:`_stage_width`;
:func:`_stage_loops`)."""


def _stage_width(correction: bool) -> int:
    """Fields per stage of :func:`_stage_loops`: dx_j, ds_j, and with the correction dy_j, the stage's E_j and
    exponent, and its state x_j, s_j."""
    return 7 if correction else 2


def _evaluated(tableau) -> int:
    """Stages evaluated before a step's end (FSAL tableaux: the last stage is the end's derivative)."""
    return len(tableau.b) - 1 if tableau.fsal else len(tableau.b)


def _stage_fields(tableau, correction: bool) -> int:
    """Number of stage fields of :func:`_stage_loops` for ``tableau``."""
    return _stage_width(correction) * (_evaluated(tableau) - 1)


def _stage_sum(weights, comp: int, count: int, first: tuple[str, ...], width: int, last: int) -> str:
    """sum_j weights_j d_j over stages j = 1..count, component ``comp`` (0: x, 1: s, 2: y) of each stage's
    derivative: the first stage's is first[comp], stages 2..last are in the stage fields (``width`` per stage), a
    later one is the end's (FSAL: dxe, dse, dye). Zero weights are left out; the weights are written as literals."""
    def derivative(j: int) -> str:
        if j == 1:
            return first[comp]
        if j <= last:
            return f"st[{(_STAGES + width * (j - 2) + comp) * LANES} + l]"
        return ("dxe", "dse", "dye")[comp]

    return " + ".join(f"{float(weights[j])!r} * {derivative(j + 1)}" for j in range(count) if weights[j] != 0.0)


def _stage_loops(tableau, start: tuple[str, ...], h: str, o_start: str, correction: bool, end: list[str]
                 ) -> list[str]:
    """Lines of one step of size ``h`` from the state fields ``start`` (x, s, dx, ds[, y, dy]) as a sequence of lane
    loops, one per stage: each loop reads the earlier stages' derivatives from the stage fields and writes its own.

    Why one loop per stage: a step written as one lane loop is one long chain of dependent operations per lane (each
    stage needs the one before, and every evaluation an exp, a square root and a division); its vectorised
    iterations are too long for the processor to overlap two of them, so the loop ran at the latency of that chain. A
    stage loop is short, and its iterations (groups of lanes) are independent: they overlap. Measured on the
    relaxed-slip lanes (dop853 with its twin, 1 thread): 1.2-1.27x faster on the default scene and its costly corner
    (benchmarks/peers.py; docs/design.md). The last loop evaluates the step's end: locals x1, s1, xe, se, dxe, dse,
    Ee and o_max (the largest exponent since ``o_start``; with ``correction`` also y1, ye, dye) are then defined
    for the lines ``end`` that close it.

    With ``correction`` every stage's y is computed in one loop after the stage (x, s) loops, which also store each
    stage's E, exponent and state (x_j, s_j) for it (read back, not recomputed from the stage sums); one y loop, not
    one per stage: the stages' exponentials do not wait on y, so they overlap within it (model "auto" over
    "quasistatic", 2e5 default-scene points, 1 thread: 1.23-1.24 -> 1.14-1.16 of run_sweep). The (x, s) loops are
    then the plain kernel's, and a point that model="auto" leaves quasi-static gets the numbers of model="quasistatic"
    bit for bit (tests/integrate/test_lanes_adaptive.py; benchmarks/throughput.py checks its steps). With y in the (x,
    s) loops
    the rounding of xi moved (the contraction into FMAs differed), and 9 of the default scene's 20,000 points took
    other steps."""
    _, A, b, _ = tableau.arrays()
    last = _evaluated(tableau)
    width = _stage_width(correction)
    W = LANES
    field = lambda f: f"st[{f * W} + l]"  # noqa: E731
    first = tuple(start[i] for i in ((2, 3, 5) if correction else (2, 3)))

    def combination(weights, comp: int, count: int) -> str:
        return _stage_sum(weights, comp, count, first, width, last)

    head = ["    for l in range(W):",
            f"        k, a, bb, s_c, h = st[l], {field(_A)}, {field(_B)}, {field(_SC)}, {h}",
            f"        x1, s1 = {start[0]}, {start[1]}"]
    lines = []
    for i in range(2, last + 1):
        at = lambda c: field(_STAGES + width * (i - 2) + c)  # noqa: E731, B023
        stage = [f"        xi = x1 + h * ({combination(A[i - 1], 0, i - 1)})",
                 f"        si = s1 + h * ({combination(A[i - 1], 1, i - 1)})"]
        lines += head + stage + [
            "        dxi, dsi, Ei, oi = rate(xi, si, k, a, bb, s_c)",
            f"        {at(0)}, {at(1)} = dxi, dsi",
            f"        {field(_OM)} = max({o_start if i == 2 else field(_OM)}, oi)"]
        if correction:
            lines[-1:-1] = [f"        {at(3)}, {at(4)}, {at(5)}, {at(6)} = Ei, oi, xi, si"]
    if correction:  # every stage's y in one loop after the (x, s) loops: its exponentials do not wait on y
        lines += head + [f"        G, y1 = {field(_G)}, {start[4]}"]
        for i in range(2, last + 1):
            at = lambda c: field(_STAGES + width * (i - 2) + c)  # noqa: E731, B023
            y_i = f"y1 + h * ({combination(A[i - 1], 2, i - 1)})"
            lines += [f"        {at(2)} = correction_rate({at(5)}, {at(6)}, {y_i}, k, a, bb, G, {at(1)}, {at(3)}, "
                      f"{at(4)})"]
    lines += head + [
        f"        xe = x1 + h * ({combination(b, 0, last)})",
        f"        se = s1 + h * ({combination(b, 1, last)})",
        "        dxe, dse, Ee, oe = rate(xe, se, k, a, bb, s_c)",
        f"        o_max = max({field(_OM) if last > 1 else o_start}, oe)"]
    if correction:
        lines += [f"        G, y1 = {field(_G)}, {start[4]}",
                  f"        ye = y1 + h * ({combination(b, 2, last)})",
                  "        dye = correction_rate(xe, se, ye, k, a, bb, G, dse, Ee, oe)"]
    return lines + end


def _lane_source(tableau, correction: bool, fine=None, split: int = 2) -> str:
    """Source of attempt_all(st, atol) for an explicit tableau, its coefficients written in as literals (a loop over
    stages with run-time offsets defeats the vectoriser). One attempt is a step h of the returned (coarse) run and,
    before it in the same pass, ``split`` steps h/split of the fine run with the tableau ``fine`` (default: the same)
    along the same mesh (:mod:`sweep.integrate.tolerance_ladder`); the coarse step's embedded estimate decides for
    both. Each step is a sequence of lane loops, one per stage (:func:`_stage_loops`). FSAL tableaux reuse their
    last stage as the next step's first; the others spend one evaluation at the step's end, which the tail test needs
    anyway. With ``correction`` the first-order inertial correction y
    (:func:`sweep.integrate.models.stop_inertial.make_correction_rate`) is a third component of the coarse run's
    stages; it
    does not enter the error norm (it is needed to model_tol only, and rides on steps chosen for xi at rtol).
    Generated, not branched, for the reason of :func:`sweep.integrate.lanes._step_source`."""
    _, _, b, e = tableau.arrays()
    W = LANES
    field = lambda f: f"st[{f * W} + l]"  # noqa: E731
    fine = tableau if fine is None else fine
    tentative = (field(_TX), field(_TS), field(_TDX), field(_TDS))
    lines = [
        "def attempt_all(st, atol):",
        # the fine twin's steps first, into tentative fields: its stage loops written once and run ``split`` times
        "    for l in range(W):",
        f"        {', '.join(tentative)}, {field(_TO)} = {field(_XF)}, {field(_SF)}, {field(_DXF)}, {field(_DSF)}, "
        f"{field(_EXPO)}",
        f"    for _ in range({split}):",
        *("    " + line for line in _stage_loops(
            fine, tentative, f"{1.0 / split!r} * {field(_H)}", field(_TO), False,
            [f"        {', '.join(tentative)}, {field(_TE)}, {field(_TO)} = xe, se, dxe, dse, Ee, o_max"])),
    ]

    def error(comp: int) -> str:  # the embedded estimate, the first stage's derivative from the locals dx1, ds1
        return _stage_sum(e, comp, b.size, ("dx1", "ds1"), _stage_width(correction), _evaluated(tableau))

    close = [
        f"        tol, dx1, ds1 = {field(_TOL)}, {field(_DX)}, {field(_DS)}",
        f"        ex = h * ({error(0)})",
        f"        es = h * ({error(1)})",
        # the norm of stop_point.error_norm: xi relative with the atol floor, u = s - xi relative to min(s, max(1, u))
        "        sx = atol + tol * max(abs(x1), abs(xe))",
        "        su = tol * min(abs(se), max(one, abs(se - xe))) + u_rounding * abs(se)",
        "        err2 = half * ((ex / sx) ** 2 + ((es - ex) / su) ** 2)",
        *controller_lines(field, _LOGPREV, _REJ, _H),
    ]
    kept = [(_X, "xe", "x1"), (_S, "se", "s1"), (_DX, "dxe", "dx1"), (_DS, "dse", "ds1"), (_E, "Ee", field(_E)),
            (_XF, field(_TX), field(_XF)), (_SF, field(_TS), field(_SF)), (_DXF, field(_TDX), field(_DXF)),
            (_DSF, field(_TDS), field(_DSF)), (_EF, field(_TE), field(_EF))]
    if correction:
        kept += [(_Y, "ye", "y1"), (_DY, "dye", field(_DY))]
    close += [f"        {field(f)} = {new} if accept else {old}" for f, new, old in kept]
    close += [f"        {field(_ACC)} = one if accept else zero", f"        {field(_REJ)} = zero if accept else one"]
    close += _tail_lines(field)
    start = (field(_X), field(_S), field(_DX), field(_DS)) + ((field(_Y), field(_DY)) if correction else ())
    lines += _stage_loops(tableau, start, field(_H), field(_TO), correction, close)
    return "\n".join(lines) + "\n"


def _tail_lines(field) -> list[str]:
    """Generated lines, in the lane loop that closes an attempt: whether the closed-form tail may take over from the
    accepted state (its error bound, :func:`sweep.integrate.models.stop.tail_bound`, below TAIL_SAFETY (atol +
    TAIL_RTOL |xi|)
    or TAIL_SHARE |x_fine - x|), into the lane field _DONE. Tested here, in the vectorised loop, rather than in the
    scalar bookkeeping that follows every attempt: there its two divisions and branches cost ~10 % of an attempt."""
    x, E = field(_X), field(_E)
    return [
        f"        g_tail = a + two * bb * ({field(_S)} - {x})",
        f"        bound = tail_bound(k, g_tail, {E})",
        f"        negligible = max(tail_safety * (tail_rtol * {x} + atol), tail_share * abs({field(_XF)} - {x}))",
        f"        {field(_DONE)} = one if (accept and g_tail > zero and {E} <= e_tail_max and bound <= negligible) "
        "else zero",
    ]


@functools.cache
def _rates(f):
    """(rate, correction_rate) for float type f as functions that numba compiles once each and LLVM inlines at
    every call (``forceinline``: LLVM's always-inline attribute), the same arithmetic as numba's ``inline="always"``
    with the same fastmath flags, so the same machine code. Inlined in numba's IR instead, each of the attempt's ~60
    calls was a copy to type and lower: relax_runs with the correction compiled in ~35 s, of a cold default run's
    ~38 s (2 cores, NUMBA_CACHE_DIR empty), and in ~9-12 s so, with the attempt itself inlined the same way
    (benchmarks/cold_start.py)."""
    rate, correction_rate = make_rate(f), make_correction_rate(f)

    @njit(forceinline=True, fastmath=FAST, error_model="numpy")
    def rate_call(xi, s, k, a, b, s_c):
        return rate(xi, s, k, a, b, s_c)

    @njit(forceinline=True, fastmath=FAST, error_model="numpy")
    def correction_rate_call(xi, s, y, k, a, b, G, w, E, expo):
        return correction_rate(xi, s, y, k, a, b, G, w, E, expo)

    return pin(rate_call, np.dtype(f).name), pin(correction_rate_call, np.dtype(f).name)


def _attempt(f, tableau, correction: bool, fine, split: int):
    """attempt_all(st, atol) compiled for float type f (float64 only for now) and ``tableau``; ``atol`` is the
    absolute floor of xi in the error norm."""
    rate, correction_rate = _rates(f)
    namespace = {"rate": rate, "correction_rate": correction_rate, "exp_f64": exp_f64,
                 "_log2_approx": _log2_approx, "W": LANES, "one": f(1.0), "zero": f(0.0), "half": f(0.5),
                 "tail_bound": tail_bound, "two": f(2.0), "e_tail_max": f(E_TAIL_MAX), "tail_safety": f(TAIL_SAFETY),
                 "tail_rtol": f(TAIL_RTOL), "tail_share": f(TAIL_SHARE),
                 "exp_max": f(EXP_MAX), "u_rounding": f(U_ROUNDING), "safety": f(SAFETY), "max_factor": f(MAX_FACTOR),
                 "min_factor": f(MIN_FACTOR), "nonfinite_factor": f(NONFINITE_FACTOR), "floor2": f(ERR_FLOOR ** 2),
                 # err^(-alpha/(q+1)) err_prev^(beta/(q+1)) with err = sqrt(err2): exp2 of multiples of log2(err2)
                 "pi_now": f(-_LN2 * PI_CONTROLLER.alpha / (2.0 * (tableau.error_order + 1))),
                 "pi_prev": f(_LN2 * PI_CONTROLLER.beta / (2.0 * (tableau.error_order + 1))),
                 "i_now": f(-_LN2 / (2.0 * (tableau.error_order + 1))), "__name__": __name__}
    source = _lane_source(tableau, correction, fine, split)
    exec(compile(source, f"<sweep.integrate.lanes_adaptive: {tableau.name}>", "exec"), namespace)
    # not cached itself (generated source has no file): inlined by LLVM into relax_runs, which is (_rates: numba
    # copied this body's IR once per block when it inlined it, ~8 s of its compile)
    return pin(njit(forceinline=True, fastmath=FAST, error_model="numpy")(namespace["attempt_all"]), tableau.name,
               fine.name, split, correction)


class AdaptiveRuns(NamedTuple):
    """The runs of one call: run r solves point ``point[r]`` with local control tolerance ``tol[r]`` from the first
    trial step ``h0[r]`` in sigma, until the closed-form tail's bound is below TAIL_SAFETY (atol + TAIL_RTOL |xi|), as
    on the per-point path, or below TAIL_SHARE |x_fine - x|, a small share of the run's own estimate (a tail bound at
    the tolerance, as in the fixed-step lanes, dominated the estimate where the true error is far below it); at most
    ``max_steps`` attempts per run. ``atol`` is also the floor of xi in the error norm."""

    point: np.ndarray
    tol: np.ndarray
    h0: np.ndarray
    atol: float
    max_steps: int


class AdaptiveOutputs(NamedTuple):
    """Per-run outputs of the adaptive lanes: relaxed slip of the run (coarse) and of its fine twin on the same mesh
    halved, the sum of their closed-form tails' error bounds, the first-order inertial correction (empty for the
    kernels without it), status and attempts (rejected ones included; each attempt is one step and two half steps)."""

    xi_inf: np.ndarray
    fine: np.ndarray
    tail_err: np.ndarray
    correction: np.ndarray
    status: np.ndarray
    steps: np.ndarray

    @classmethod
    def empty(cls, n: int, correction: bool) -> AdaptiveOutputs:
        nan = lambda size: np.full(size, np.nan)  # noqa: E731
        return cls(nan(n), nan(n), nan(n), nan(n if correction else 0), np.zeros(n, np.int8), np.zeros(n, np.int32))


def make_adaptive_lane_kernels(tableau, fine, split: int, correction: bool = False):
    """(relax_runs, relax_batch) for an embedded explicit pair, float64: points in a
    :class:`sweep.integrate.lanes.LanePoints`, runs in an :class:`AdaptiveRuns`, results in an
    :class:`AdaptiveOutputs`; with ``correction`` each run also carries the first-order inertial correction."""
    f = np.float64
    rate, correction_rate = _rates(f)
    attempt_all = _attempt(f, tableau, correction, fine, split)
    W = LANES
    # the fine twin's stage loops use the same stage fields: room for the larger of the two
    n_fields = _STAGES + max(_stage_fields(tableau, correction), _stage_fields(fine, False))
    zero, one = 0.0, 1.0

    @njit(inline="always", cache=True, fastmath=FAST, error_model="numpy")
    def load(st, lane, k, a, b, s_c, G, tol, h):
        st[_K * W + lane], st[_A * W + lane], st[_B * W + lane], st[_SC * W + lane] = k, a, b, s_c
        st[_H * W + lane], st[_TOL * W + lane] = h, tol
        st[_X * W + lane], st[_S * W + lane] = zero, zero
        dxi, ds, E, expo = rate(zero, zero, k, a, b, s_c)
        st[_DX * W + lane], st[_DS * W + lane], st[_E * W + lane], st[_EXPO * W + lane] = dxi, ds, E, expo
        st[_XF * W + lane], st[_SF * W + lane], st[_DXF * W + lane], st[_DSF * W + lane] = zero, zero, dxi, ds
        st[_EF * W + lane] = E
        st[_ACC * W + lane], st[_REJ * W + lane], st[_LOGPREV * W + lane] = zero, zero, zero
        if correction:
            st[_G * W + lane], st[_Y * W + lane] = G, zero
            st[_DY * W + lane] = correction_rate(zero, zero, zero, k, a, b, G, ds, E, expo)

    @njit(inline="always", cache=True, fastmath=FAST, error_model="numpy")
    def take_next(st, lane, lane_run, runs, queued, pts, job):
        """Load the next queued run into ``lane`` (or, the queue exhausted, an idle dummy marked -1)."""
        if queued < runs.size:
            r = runs[queued]
            p = job.point[r]
            load(st, lane, pts.k[p], pts.a[p], pts.b[p], pts.s_c[p], pts.G[p] if correction else zero, job.tol[r],
                 job.h0[r])
            lane_run[lane] = r
            return queued + 1
        load(st, lane, one, one, zero, one, zero, one, zero)
        lane_run[lane] = -1
        return queued

    @njit(cache=True, nogil=True, fastmath=FAST, error_model="numpy")
    def relax_runs(pts, job, runs, out):
        """Solve the runs ``runs`` of ``job`` to their relaxed slip (and correction) into ``out``."""
        st = np.zeros(n_fields * W)
        lane_run = np.full(W, -1, np.int64)
        n = np.zeros(W, np.int64)
        queued, busy = 0, 0
        atol, max_steps = job.atol, job.max_steps
        for lane in range(W):
            queued = take_next(st, lane, lane_run, runs, queued, pts, job)
            busy += lane_run[lane] >= 0
        while busy > 0:
            attempt_all(st, atol)
            for lane in range(W):
                r = lane_run[lane]
                if r < 0:
                    continue
                n[lane] += 1
                done = st[_DONE * W + lane] != zero  # accepted, and the tail may take over (_tail_lines)
                if not done and n[lane] < max_steps and (st[_ACC * W + lane] == zero or
                                                         math.isfinite(st[_X * W + lane])):
                    continue  # rejected (the lane retries with its smaller step), or not yet in the tail
                p = job.point[r]
                k, a, bb = pts.k[p], pts.a[p], pts.b[p]
                xi, u = st[_X * W + lane], st[_S * W + lane] - st[_X * W + lane]
                E = st[_E * W + lane]
                bound = tail_error(k, a, bb, u, E)
                if not math.isfinite(xi):
                    out.xi_inf[r], out.status[r] = math.nan, NONFINITE
                elif done:
                    xf, uf, Ef = st[_XF * W + lane], st[_SF * W + lane] - st[_XF * W + lane], st[_EF * W + lane]
                    out.xi_inf[r], out.fine[r], out.status[r] = xi + tail_slip(k, a, bb, u, E), \
                        xf + tail_slip(k, a, bb, uf, Ef), OK
                    out.tail_err[r] = bound + tail_error(k, a, bb, uf, Ef)
                    if correction:  # NaN or inf where it overflowed: the caller's fallback; xi_inf stands
                        out.correction[r] = tail_correction(k, a, bb, pts.G[p], u, E, st[_Y * W + lane])
                elif n[lane] >= max_steps:
                    out.xi_inf[r], out.status[r] = math.nan, MAX_STEPS
                else:
                    continue
                out.steps[r] = n[lane]
                n[lane] = 0
                queued = take_next(st, lane, lane_run, runs, queued, pts, job)
                busy -= lane_run[lane] < 0

    for kernel in (load, take_next, relax_runs):
        pin(kernel, tableau.name, fine.name, split, correction)
    return relax_runs, lanes_in_threads(relax_runs, W)


LANE_TWINS = {"dop853": ("dop853", 2)}
"""The fine twin of each coarse method of the adaptive lanes: (its method, steps per coarse step). dop853: itself on
the mesh halved (36 evaluations per attempt). Measured and not kept: dp5 with a dop853 twin on the same mesh (18
evaluations per attempt) took 1.6-3x the attempts for the same estimates, 1.0x the time at rtol 1e-3 and 1.7x at 1e-10
on the default scene."""


@functools.cache
def adaptive_lane_kernels(method: str, correction: bool = False):
    """(relax_runs, relax_batch) of an embedded pair of :data:`sweep.integrate.solvers.EXPLICIT_METHODS` with its fine
    twin
    (:data:`LANE_TWINS`), with or without the first-order inertial correction (built once per process; numba
    compiles on first call and caches on disk)."""
    fine, split = LANE_TWINS[method]
    return make_adaptive_lane_kernels(EXPLICIT_METHODS[method], EXPLICIT_METHODS[fine], split, correction)


pin_module(__name__)
