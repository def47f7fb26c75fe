"""Inertial driven points in lockstep lanes (issue 35): model "inertial", and model "auto"'s points whose quasi-static
run broke down, as the quasi-static lanes (:mod:`sweep.integrate.lanes_driven`) run the quasi-static model.

The equations, the steppers and the rules are the one-point driver's with ``slaved`` (:mod:`sweep.integrate.driven`,
its module docstring): the inertial driven equations in (z, u, w = ln xi') with the aging law, on their slow manifold
(w slaved to second order, :func:`sweep.integrate.models.driven.make_slaved_rhs`, steps at SLAVED_TOL x the
tolerance) where the inertial term is small (:data:`sweep.accuracy.SLAVED_INERTIA`, entered within SLAVED_ENTRY),
the full system elsewhere; Dormand-Prince 5(4) with the PI controller, RODAS3 with the I controller where the
inertial mode is stiff (h A/(gamma xi') > STIFF_SWITCH); the local error max(|e|) / (tol max(largest |z| met,
|z_new|, |u_new|, |w_new|)); the cycles cut at the maxima of z; the regime decision.

How the work is laid out is the quasi-static lanes' (one attempt of every lane per pass: six stage loops, then a
closing loop of selects; a short scalar loop over the lanes whose attention flag is up). The lane's model is a mask
``m`` (1 on the manifold, 0 the full system), not a branch: every stage evaluates :func:`rate`, which computes the
manifold's w and the full system's rates and selects per lane (4 exponentials a stage against the quasi-static 2).
The closing loop also switches a lane onto or off the manifold after an accepted step (:func:`settle`, the
driver's test and hand-over). A lane whose next step is stiff raises its attention flag instead of committing: the
scalar loop takes that step with the driver's own RODAS3 step (:func:`sweep.integrate.driven.scalar_parts`), and
books it as the dp5 attention steps are booked (extrema with the driver's Newton on exact partial steps of the
step's own method). On the issue-35 grid ~1.5 % of the steps are stiff, on the deep stick-slip grid ~11 %.

Arithmetic differs from the one-point driver where the quasi-static lanes' does (exp_f64, the 0.5 % log2 of the
controller) and in w' = (balance - w) / (e^w g) (the driver: e^-w from its own exponential): steps differ at the
tolerance's level, and so do growth rates and amplitudes (within their estimates;
tests/integrate/test_lanes_driven_inertial.py). A point's numbers do not depend on its lane or neighbours.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..accuracy import DECAYED, SLAVED_ENTRY, SLAVED_INERTIA, SLAVED_TOL, STIFF_SWITCH, W_RUNAWAY
from ..jitcache import pin, pin_module
from .batch import lanes_in_threads
from .driven import (
    H_FLOOR,
    H_START,
    MAX_STEPS,
    RODAS3_ORDER,
    STEP_UNDERFLOW,
    DrivenParams,
    Regime,
    _slaved_parts,
    scalar_parts,
)
from .lanes_driven import (
    LANES,
    WIDTHS,
    book_maximum,
    book_minimum,
    book_state,
    finish,
    make_run_lanes,
    reset_bookkeeping,
)
from .solvers import DP5
from .solvers.controllers import (
    ERR_FLOOR,
    I_CONTROLLER,
    MAX_FACTOR,
    MIN_FACTOR,
    NONFINITE_FACTOR,
    PI_CONTROLLER,
    SAFETY,
    accepted_factor_log2,
    rejected_factor,
)
from .solvers.fastmath import FAST
from .solvers.vmath import EXP_MAX, exp_f64
from .solvers.vmath import log2_approx as _log2_approx

__all__ = ["InertialPoints", "inertial_lanes"]

# lane fields, each LANES wide at offset F * LANES of one flat array
_K, _A, _B, _G, _H, _Z, _U, _W, _DZ, _DU, _DW, _M, _EW = range(13)
_TAU, _SIZE, _LOGPREV, _REJ, _ATTN, _ACC, _STIFF, _NSTEP, _TENTH, _WPEAK = range(13, 23)
_ZE, _UE, _WE, _DZE, _DUE, _DWE, _LWE, _HN, _LERR = range(23, 32)
_STAGES = 32
"""Stage j = 2..6 of the step under way: dz_j at _STAGES + 3 (j - 2), du_j and dw_j next to it."""
_N_FIELDS = _STAGES + 3 * 5
_LN2 = math.log(2.0)
_Q1 = DP5.error_order + 1
_LOW, _HIGH, _SLOW = SLAVED_INERTIA


class InertialPoints(NamedTuple):
    """Reduced parameters of the flat points (k = chi/A, a = mu1/A, b = m2/A, g = gamma/A > 0)."""

    k: np.ndarray
    a: np.ndarray
    b: np.ndarray
    g: np.ndarray


@njit(inline="always", fastmath=FAST, error_model="numpy")
def rate(z, u, w, m, k, a, b, g):
    """(z', u', w', ln xi', the manifold's w) of the inertial driven equations with the aging law at (z, u, w): on
    the slow manifold where m = 1 (w replaced by the manifold's, w' = 0: the driver's slaved form,
    :func:`sweep.integrate.models.driven.make_slaved_rhs`, written out with the vectorisable exponential), the full
    system (:func:`sweep.integrate.models.driven.make_driven_rhs`) where m = 0."""
    balance = k * z - u * (a + b * u) - u
    c = a + 2.0 * b * u + 1.0
    e0, e_u = exp_f64(min(balance, EXP_MAX)), exp_f64(min(-u, EXP_MAX))
    du0 = e_u - e0
    d0 = k * (1.0 - e0) - c * du0
    d0_z = k * e0 * (c - k)
    d0_u = k * c * e0 - 2.0 * b * du0 + c * e_u - c * c * e0
    w1 = balance - g * e0 * d0
    w1_z = k - g * e0 * (k * d0 + d0_z)
    w1_u = -c - g * e0 * (d0_u - c * d0)
    e1 = exp_f64(min(w1, EXP_MAX))
    ws = balance - g * e1 * (w1_z * (1.0 - e1) + w1_u * (e_u - e1))
    on = m > 0.5
    lw = ws if on else w
    e = exp_f64(min(lw, EXP_MAX))
    dw = 0.0 if on else (balance - w) / (e * g)
    return 1.0 - e, e_u - e, dw, lw, ws


@njit(inline="always", fastmath=FAST, error_model="numpy")
def settle(z, u, w, dz, du, dw, m, ws, k, a, b, g, entry):
    """(w, z', u', w', m, e^w) after an accepted step to (z, u, w) with rates (dz, du, dw) and the manifold's w
    ``ws`` there: the driver's switch (onto the manifold where the inertial term is within SLAVED_INERTIA and
    |ws - w| <= ``entry``, w then moved onto it; off it past twice the bounds, the full system starting from the
    manifold's w)."""
    balance = k * z - u * (a + b * u) - u
    e = exp_f64(min(w, EXP_MAX))
    inertia = max((w - balance) / _LOW, (balance - w) / _HIGH, g * e / _SLOW)
    on = m > 0.5
    switch = inertia > 2.0 if on else (inertia <= 1.0 and abs(ws - w) <= entry)
    enter = switch and not on
    e_s = exp_f64(min(ws, EXP_MAX))
    e_u = exp_f64(min(-u, EXP_MAX))
    w_new = ws if enter else w
    e_new = e_s if enter else e
    dz_new = 1.0 - e_s if enter else dz
    du_new = e_u - e_s if enter else du
    dw_new = 0.0 if enter else ((balance - w) / (e * g) if (switch and on) else dw)
    m_new = (0.0 if on else 1.0) if switch else m
    return w_new, dz_new, du_new, dw_new, m_new, e_new


def _attempt_source(width: int) -> str:
    """Source of attempt_all(st, rtol, pert, max_steps): one dp5 attempt of lanes 0..width-1 (module docstring)."""
    _, A, b, e = DP5.arrays()
    W = LANES
    f = lambda field: f"st[{field * W} + l]"  # noqa: E731
    names = ("z", "u", "w")

    def d(comp: int, j: int) -> str:  # the derivative of stage j (1-based): first in locals, then stage fields
        if j == 1:
            return f"d{names[comp]}1"
        if j == 7:
            return f"d{names[comp]}e"
        return f(_STAGES + 3 * (j - 2) + comp)

    def combo(weights, comp: int, count: int) -> str:
        return " + ".join(f"{float(weights[j])!r} * {d(comp, j + 1)}" for j in range(count) if weights[j] != 0.0)

    head = [f"    for l in range({width}):",
            f"        k, a, bb, g, h, m = {f(_K)}, {f(_A)}, {f(_B)}, {f(_G)}, {f(_H)}, {f(_M)}",
            f"        z1, u1, w1, dz1, du1, dw1 = {f(_Z)}, {f(_U)}, {f(_W)}, {f(_DZ)}, {f(_DU)}, {f(_DW)}"]
    lines = ["def attempt_all(st, rtol, pert, max_steps):"]
    for i in range(2, 7):
        lines += head + [f"        {c}i = {c}1 + h * ({combo(A[i - 1], n, i - 1)})" for n, c in enumerate(names)]
        lines += ["        dzi, dui, dwi, _, _ = rate(zi, ui, wi, m, k, a, bb, g)",
                  f"        {', '.join(f(_STAGES + 3 * (i - 2) + n) for n in range(3))} = dzi, dui, dwi"]
    lines += head + [f"        {c}e = {c}1 + h * ({combo(b, n, 6)})" for n, c in enumerate(names)]
    lines += ["        dze, due, dwe, lwe, wse = rate(ze, ue, we, m, k, a, bb, g)"]
    lines += [f"        e_{c} = h * ({combo(e, n, 7)})" for n, c in enumerate(names)]  # (ew is e^w)
    lines += [
        f"        size, tau, logprev, rej, ew = {f(_SIZE)}, {f(_TAU)}, {f(_LOGPREV)}, {f(_REJ)}, {f(_EW)}",
        # the driver's choice of stepper: RODAS3 (the scalar loop) where the inertial mode would hold dp5 down
        "        stiff = m < half and h * abs(one / (ew * g) + dw1) > stiff_switch",
        "        finite = ze == ze and ue == ue and we == we and e_z == e_z and e_u == e_u and e_w == e_w",
        "        tol = rtol * (slaved_tol if m > half else one)",
        "        err = max(max(abs(e_z), abs(e_u)), abs(e_w)) / (tol * max(max(size, abs(ze)), max(abs(ue), abs(we))))",
        "        err = err if finite else one",
        "        accept = finite and err <= one and not stiff",
        "        lerr = _log2_approx(max(err, err_floor))",
        "        f_pi = min(max_factor, max(min_factor, safety * exp_f64(pi_now * lerr + pi_prev * logprev)))",
        "        f_pi = min(f_pi, one) if rej > half else f_pi",
        "        f_i = min(one, max(min_factor, safety * exp_f64(i_now * lerr)))",
        "        hn = h * (f_pi if accept else (f_i if finite else nonfinite_factor))",
        # where the scalar loop must look (the quasi-static lanes' events; w is the state's third component)
        "        norm = max(max(abs(ze), abs(ue)), abs(lwe))",
        "        turn = (dz1 > zero and dze <= zero) or (dz1 < zero and dze >= zero)",
        f"        first_tenth = norm < tenth * pert and {f(_TENTH)} == zero",
        "        event = turn or lwe > w_runaway or norm < decayed * pert or first_tenth",
        f"        n = {f(_NSTEP)} + (zero if stiff else one)",
        "        attn = stiff or (accept and event) or n >= max_steps or (not accept and hn < h_floor * (one + tau))",
        "        commit = accept and not attn",
        "        wn, dzn, dun, dwn, mn, ewn = settle(ze, ue, lwe, dze, due, dwe, m, wse, k, a, bb, g,"
        " slaved_entry * rtol * size)",
        f"        {f(_NSTEP)} = n",
        f"        {f(_Z)}, {f(_U)}, {f(_W)} = (ze, ue, wn) if commit else (z1, u1, w1)",
        f"        {f(_DZ)}, {f(_DU)}, {f(_DW)} = (dzn, dun, dwn) if commit else (dz1, du1, dw1)",
        f"        {f(_M)}, {f(_EW)} = (mn, ewn) if commit else (m, ew)",
        f"        {f(_TAU)} = tau + h if commit else tau",
        f"        {f(_SIZE)} = max(size, abs(ze)) if commit else size",
        f"        {f(_WPEAK)} = max({f(_WPEAK)}, lwe) if commit else {f(_WPEAK)}",
        f"        {f(_LOGPREV)} = lerr if commit else logprev",
        f"        {f(_H)} = hn if (commit or not (accept or stiff)) else h",
        f"        {f(_REJ)} = zero if commit else (one if not (accept or stiff) else rej)",
        f"        {f(_ATTN)} = one if attn else zero",
        f"        {f(_ACC)} = one if accept else zero",
        f"        {f(_STIFF)} = one if stiff else zero",
        f"        {f(_ZE)}, {f(_UE)}, {f(_WE)}, {f(_DZE)}, {f(_DUE)}, {f(_DWE)} = ze, ue, we, dze, due, dwe",
        f"        {f(_LWE)}, {f(_HN)}, {f(_LERR)} = lwe, hn, lerr",
    ]
    return "\n".join(lines) + "\n"


@functools.cache
def _attempt(width: int):
    """attempt_all(st, rtol, pert, max_steps) over ``width`` lanes, compiled (inlined by LLVM into the driver)."""
    namespace = {"rate": rate, "settle": settle, "exp_f64": exp_f64, "_log2_approx": _log2_approx, "one": 1.0,
                 "zero": 0.0, "half": 0.5, "tenth": 0.1, "decayed": DECAYED, "w_runaway": W_RUNAWAY,
                 "h_floor": H_FLOOR, "err_floor": ERR_FLOOR, "safety": SAFETY, "max_factor": MAX_FACTOR,
                 "min_factor": MIN_FACTOR, "nonfinite_factor": NONFINITE_FACTOR, "stiff_switch": STIFF_SWITCH,
                 "slaved_tol": SLAVED_TOL, "slaved_entry": SLAVED_ENTRY,
                 "pi_now": -_LN2 * PI_CONTROLLER.alpha / _Q1, "pi_prev": _LN2 * PI_CONTROLLER.beta / _Q1,
                 "i_now": -_LN2 / _Q1, "__name__": __name__}
    source = _attempt_source(width)
    exec(compile(source, f"<sweep.integrate.lanes_driven_inertial: dp5, {width} lanes>", "exec"), namespace)
    return pin(njit(forceinline=True, fastmath=FAST, error_model="numpy")(namespace["attempt_all"]), "dp5-inertial",
               width)


@functools.cache
def _make_kernels():
    _, advance, extremum = scalar_parts("aging", True)
    _, _, extremum_s = _slaved_parts("aging")
    W = LANES

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def load_values(st, bk, lane, k, a, b, g, pert):
        st[_K * W + lane], st[_A * W + lane], st[_B * W + lane], st[_G * W + lane] = k, a, b, g
        st[_Z * W + lane], st[_U * W + lane], st[_W * W + lane], st[_M * W + lane] = pert, 0.0, 0.0, 0.0
        dz, du, dw, _, _ = rate(pert, 0.0, 0.0, 0.0, k, a, b, g)
        st[_DZ * W + lane], st[_DU * W + lane], st[_DW * W + lane], st[_EW * W + lane] = dz, du, dw, 1.0
        st[_H * W + lane] = min(H_START / (1.0 + k), 0.1 * g)
        st[_TAU * W + lane], st[_SIZE * W + lane] = 0.0, pert
        st[_LOGPREV * W + lane] = _log2_approx(1e-4)  # the driver's first err_prev
        st[_REJ * W + lane], st[_NSTEP * W + lane], st[_TENTH * W + lane] = 0.0, 0.0, 0.0
        st[_WPEAK * W + lane] = -math.inf
        reset_bookkeeping(bk, lane, pert)  # the driver's _linear_amplitude with inertia

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def load(st, bk, lane, pts, i, pert):
        load_values(st, bk, lane, pts.k[i], pts.a[i], pts.b[i], pts.g[i], pert)

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def idle(st, bk, lane, pert):
        load_values(st, bk, lane, 1.0, 0.5, 0.0, 1.0, pert)  # an idle dummy (never stiff, never slaved)

    @njit(fastmath=FAST, error_model="numpy")
    def stiff_step(st, lane, job, p, y0, K, ys, y_new, err_v, work):
        """The lane's step with the driver's RODAS3 step and I controller; where it is accepted, its end state, rates
        and next step in the lane's tentative fields (as the closing loop leaves a dp5 step)."""
        h = st[_H * W + lane]
        st[_NSTEP * W + lane] += 1.0
        done, _ = advance(True, y0, h, p, K, ys, y_new, err_v, work)
        size = max(st[_SIZE * W + lane], abs(y_new[0]), abs(y_new[1]), abs(y_new[2]))
        err = max(abs(err_v[0]), abs(err_v[1]), abs(err_v[2])) / (job.rtol * size) if done else math.nan
        if not err <= 1.0:  # (NaN included)
            st[_H * W + lane] = h * rejected_factor(I_CONTROLLER, err, RODAS3_ORDER)
            st[_REJ * W + lane], st[_ACC * W + lane] = 1.0, 0.0
            return
        dz, du, dw, lw, _ = rate(y_new[0], y_new[1], y_new[2], 0.0, p.k, p.a, p.b, p.g)
        lerr = _log2_approx(max(err, ERR_FLOOR))
        hn = h * accepted_factor_log2(I_CONTROLLER, lerr, st[_LOGPREV * W + lane], RODAS3_ORDER,
                                      st[_REJ * W + lane] > 0.5)
        st[_ZE * W + lane], st[_UE * W + lane], st[_WE * W + lane] = y_new[0], y_new[1], y_new[2]
        st[_DZE * W + lane], st[_DUE * W + lane], st[_DWE * W + lane], st[_LWE * W + lane] = dz, du, dw, lw
        st[_HN * W + lane], st[_LERR * W + lane], st[_ACC * W + lane] = hn, lerr, 1.0

    @njit(fastmath=FAST, error_model="numpy")
    def look(st, bk, lane, i, job, out, y0, y1, K, ys, yt, err_v, work, dyt):
        """The scalar part of a lane whose attention flag is up: a stiff step, then the driver's loop body after the
        error test; True where the point is finished (its outputs written)."""
        pert = job.perturbation
        tau, h = st[_TAU * W + lane], st[_H * W + lane]
        grow, per = bk.grow[lane], bk.per[lane]
        w_peak = st[_WPEAK * W + lane]
        p = DrivenParams(st[_K * W + lane], st[_A * W + lane], st[_B * W + lane], st[_G * W + lane])
        y0[0], y0[1], y0[2] = st[_Z * W + lane], st[_U * W + lane], st[_W * W + lane]
        stiff = st[_STIFF * W + lane] > 0.5
        if stiff:
            stiff_step(st, lane, job, p, y0, K, ys, yt, err_v, work)
        steps = int(st[_NSTEP * W + lane])
        if st[_ACC * W + lane] == 0.0:  # rejected: below the step floor, or the budget spent
            if st[_H * W + lane] < H_FLOOR * (1.0 + tau):
                finish(out, i, Regime.UNDECIDED, STEP_UNDERFLOW, grow[-1], per[-1], math.nan, bk.cycles[lane], steps,
                       w_peak)
                return True
        else:
            ze, ue, lw1 = st[_ZE * W + lane], st[_UE * W + lane], st[_LWE * W + lane]
            dz1 = st[_DZE * W + lane]
            w_peak = max(w_peak, lw1)
            if book_state(bk, lane, i, out, lw1, max(abs(ze), abs(ue), abs(lw1)), tau, h, pert, steps, w_peak):
                return True
            if math.isfinite(bk.t_tenth[lane]):
                st[_TENTH * W + lane] = 1.0
            dz = st[_DZ * W + lane]
            on = st[_M * W + lane] > 0.5
            turn = (dz > 0.0 and dz1 <= 0.0) or (dz < 0.0 and dz1 >= 0.0)
            if turn:  # an extremum of z, located with the step's own method
                y1[0], y1[1], y1[2] = ze, ue, st[_WE * W + lane]
                if on:
                    dt, z_ext = extremum_s(False, y0, y1, h, dz, dz1, p, K, ys, yt, err_v, work, dyt)
                else:
                    dt, z_ext = extremum(stiff, y0, y1, h, dz, dz1, p, K, ys, yt, err_v, work, dyt)
                if dz > 0.0:  # a maximum of z: a cycle ends
                    if book_maximum(bk, lane, i, out, z_ext, tau + dt, pert, job.max_cycles, steps, w_peak):
                        return True
                else:
                    book_minimum(bk, lane, z_ext)
            # the accepted step, committed, and the switch onto or off the manifold
            size = st[_SIZE * W + lane]
            _, _, _, _, ws = rate(ze, ue, lw1, 1.0, p.k, p.a, p.b, p.g)
            w, dz, du, dw, m, ew = settle(ze, ue, lw1, dz1, st[_DUE * W + lane], st[_DWE * W + lane],
                                          st[_M * W + lane], ws, p.k, p.a, p.b, p.g, SLAVED_ENTRY * job.rtol * size)
            st[_Z * W + lane], st[_U * W + lane], st[_W * W + lane] = ze, ue, w
            st[_DZ * W + lane], st[_DU * W + lane], st[_DW * W + lane] = dz, du, dw
            st[_M * W + lane], st[_EW * W + lane] = m, ew
            st[_TAU * W + lane] = tau + h
            st[_SIZE * W + lane] = max(size, abs(ze))
            st[_WPEAK * W + lane] = w_peak
            st[_LOGPREV * W + lane] = st[_LERR * W + lane]
            st[_H * W + lane] = st[_HN * W + lane]
            st[_REJ * W + lane] = 0.0
        if steps >= job.max_steps:
            finish(out, i, Regime.UNDECIDED, MAX_STEPS, grow[-1], per[-1], math.nan, bk.cycles[lane], steps, w_peak)
            return True
        return False

    variant = ("aging", "inertial-slaved", W)
    for kernel in (load_values, load, idle, stiff_step, look):
        pin(kernel, *variant)
    run_lanes = make_run_lanes(tuple(_attempt(w) for w in WIDTHS), WIDTHS, look, load, idle, _N_FIELDS, _ATTN, 3,
                               variant)
    return run_lanes, lanes_in_threads(run_lanes, W)


def inertial_lanes():
    """(run_lanes, run_batch): inertial driven points with the aging law in lanes (module docstring). run_batch(pts,
    job, groups, out) runs every point of ``job`` (:class:`sweep.integrate.lanes_driven.DrivenJob`, over
    :class:`InertialPoints`) into ``out`` (:class:`sweep.integrate.driven.DrivenOutputs`, indexed by point) in
    ``groups`` strided groups on numba.get_num_threads() threads (:func:`sweep.integrate.batch.lanes_in_threads`)."""
    return _make_kernels()


pin_module(__name__)
