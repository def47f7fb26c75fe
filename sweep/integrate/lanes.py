"""Relaxed slip only (the common large sweep): fixed-step runs in lockstep lanes that LLVM vectorises.

Each thread keeps LANES runs (a run = one point at one fixed step in sigma) in flight in a structure of arrays
and advances all of them by one step of the tableau at a time. Every loop over the lanes is straight-line code
(the exp of :mod:`sweep.integrate.solvers.vmath`, no division checks), so it compiles to SIMD instructions, 8 float64 or
16 float32 lanes per AVX-512 instruction; the per-lane bookkeeping (tail test, refilling a finished lane with the
next run) is a short scalar loop in float64. A finished lane takes the next run at once, so lanes never wait
for each other; the arithmetic of a run does not depend on which lane or neighbours it had.

All lane fields live in one flat array at offsets that are multiples of LANES: with a single base pointer and
constant distances LLVM proves the lane loops free of aliasing and vectorises them without runtime checks.
The kernels are built per float type (:func:`make_lane_kernels`); float32 halves the register width per lane and
keeps about 7 digits (the plan allows it for rtol >= 1e-5 only, and says so).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..jitcache import pin, pin_module
from .batch import lanes_batch
from .models.stop import EXP_MAX, FAST, MAX_STEPS, NONFINITE, OK, TAIL_SAFETY, make_rate, tail_error, tail_slip
from .models.stop_inertial import make_correction_rate, tail_correction
from .models.stop_stiff import make_stiff_rate
from .solvers import METHODS, RosenbrockTableau

LANES = 16
"""Runs in flight per thread (8 and 32 measured within 10 %: benchmarks/throughput.py)."""
CHECK_EVERY = 4
"""A run's tail test and status checks come every CHECK_EVERY steps of its own (so a run's result does not depend
on its lane): the scalar per-lane test costs about a fifth of a step, the up to CHECK_EVERY - 1 extra steps only
make the run more accurate. The exponent of E is kept as a running maximum, so none beyond EXP_MAX is missed."""
_P = 5  # per-lane parameters k, a, b, s_c, h
_X, _S = 5, 6  # state xi, s
_E, _EXPO = 7, 8  # E at the step's end, and the largest exponent met since the run was loaded
_STAGE = 9  # the derivative at the step's start: dxi, ds
_G, _Y, _DY = 11, 12, 13  # with the first-order inertial correction: G = gamma/A, the correction y, dy at the start


def _explicit_step(f, tableau, correction: bool = False):
    """step_all(st) for a four-stage explicit tableau whose stage i uses stage i-1 only (a_ij = 0 for
    j != i-1, e.g. classical RK4), with the coefficients as compile-time constants: a loop over stages with
    run-time offsets into the lane arrays defeats LLVM's vectoriser (measured 22 ns per evaluation instead of 4.5).
    Other explicit tableaux run through the per-point kernel (integrate/stop_point.py). With ``correction`` the
    first-order inertial correction y (:func:`sweep.integrate.models.stop_inertial.make_correction_rate`) is a third
    component of the same step (:func:`_step_source`: the plain kernel is unchanged)."""
    rate = make_rate(f)
    correction_rate = make_correction_rate(f)
    W = LANES
    c, A, b, _ = tableau.arrays()
    if b.size != 4 or np.any(np.tril(A, -2) != 0):
        raise ValueError(f"{tableau.name}: the lane kernel needs a four-stage tableau with a_ij = 0 for j < i - 1")
    a21, a32, a43 = f(A[1, 0]), f(A[2, 1]), f(A[3, 2])
    b1, b2, b3, b4 = (f(x) for x in b)
    namespace = {"rate": rate, "correction_rate": correction_rate, "a21": a21, "a32": a32, "a43": a43, "b1": b1,
                 "b2": b2, "b3": b3, "b4": b4, "W": W, "__name__": __name__}
    exec(compile(_step_source(correction), f"<sweep.integrate.lanes: {tableau.name}>", "exec"), namespace)
    # not cached itself (generated source has no file): compiled into relax_runs, which is
    step_all = njit(fastmath=FAST, error_model="numpy")(namespace["step_all"])
    return pin(step_all, f.__name__, tableau.name, correction)


_STEP = f"""
def step_all(st):
    \"\"\"One step of every lane; the derivative at the step's start is in the _STAGE fields.\"\"\"
    for l in range(W):
        k, a, bb, s_c, h = st[l], st[W + l], st[2 * W + l], st[3 * W + l], st[4 * W + l]
        x0, s0, d1x, d1s = st[{_X} * W + l], st[{_S} * W + l], st[{_STAGE} * W + l], st[{_STAGE + 1} * W + l]
        x2, s2 = x0 + a21 * h * d1x, s0 + a21 * h * d1s
        d2x, d2s, E2, o2 = rate(x2, s2, k, a, bb, s_c)
        x3, s3 = x0 + a32 * h * d2x, s0 + a32 * h * d2s
        d3x, d3s, E3, o3 = rate(x3, s3, k, a, bb, s_c)
        x4, s4 = x0 + a43 * h * d3x, s0 + a43 * h * d3s
        d4x, d4s, E4, o4 = rate(x4, s4, k, a, bb, s_c)
        x1 = x0 + h * (b1 * d1x + b2 * d2x + b3 * d3x + b4 * d4x)
        s1 = s0 + h * (b1 * d1s + b2 * d2s + b3 * d3s + b4 * d4s)
        d5x, d5s, E, o5 = rate(x1, s1, k, a, bb, s_c)
        st[{_X} * W + l], st[{_S} * W + l], st[{_STAGE} * W + l], st[{_STAGE + 1} * W + l] = x1, s1, d5x, d5s
        st[{_E} * W + l], st[{_EXPO} * W + l] = E, max(max(max(o2, o3), max(o4, o5)), st[{_EXPO} * W + l])
"""
_CORRECTION = f"""
        G, y0, d1y = st[{_G} * W + l], st[{_Y} * W + l], st[{_DY} * W + l]
        d2y = correction_rate(x2, s2, y0 + a21 * h * d1y, k, a, bb, G, d2s, E2, o2)
        d3y = correction_rate(x3, s3, y0 + a32 * h * d2y, k, a, bb, G, d3s, E3, o3)
        d4y = correction_rate(x4, s4, y0 + a43 * h * d3y, k, a, bb, G, d4s, E4, o4)
        y1 = y0 + h * (b1 * d1y + b2 * d2y + b3 * d3y + b4 * d4y)
        st[{_Y} * W + l], st[{_DY} * W + l] = y1, correction_rate(x1, s1, y1, k, a, bb, G, d5s, E, o5)
"""


def _step_source(correction: bool) -> str:
    """Source of the explicit lanes' step_all, with the correction's stages written into the same lane loop when
    asked for. Generated, not branched: a run-time branch in the lane loop, or the shared part moved into an inlined
    function, defeats LLVM's vectoriser (measured: the plain default-scene sweep 3-4x slower), and written out
    twice the stage loop would have two copies to keep in step."""
    return _STEP + (_CORRECTION if correction else "")


def _rosenbrock_step(f, tableau):
    """step_all(st) for a four-stage Rosenbrock tableau whose stage 4 reuses stage 3's f (Shampine's ROS4
    structure), on the scalar form in s of :mod:`sweep.integrate.models.stop_stiff`: three exponentials per step (stages
    2 and 3 and the step's end; E at the start is the previous step's end, kept in the _E field)."""
    rate, step_factor = make_stiff_rate(f)
    W = LANES
    a, c = np.array(tableau.a), np.array(tableau.c)
    if tableau.stages != 4 or np.any(a[3] != a[2]) or tableau.alpha_x[3] != tableau.alpha_x[2]:
        raise ValueError(f"{tableau.name}: the lane kernel needs four stages with stage 4 reusing stage 3's f")
    one = f(1.0)
    inv_gamma = f(1.0 / tableau.gamma)
    a21, a31, a32 = f(a[1, 0]), f(a[2, 0]), f(a[2, 1])
    c21, c31, c32, c41, c42, c43 = f(c[1, 0]), f(c[2, 0]), f(c[2, 1]), f(c[3, 0]), f(c[3, 1]), f(c[3, 2])
    al2, al3 = f(tableau.alpha_x[1]), f(tableau.alpha_x[2])
    gx1, gx2, gx3, gx4 = (f(x) for x in tableau.gamma_x)
    m1, m2, m3, m4 = (f(x) for x in tableau.m)

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def step_all(st):
        """One Rosenbrock step of every lane, of size H = h w(s, u) in s."""
        for l in range(W):
            k, a, bb, s_c, h = st[l], st[W + l], st[2 * W + l], st[3 * W + l], st[4 * W + l]
            x0, s0, E0 = st[_X * W + l], st[_S * W + l], st[_E * W + l]
            u0 = s0 - x0
            g0 = a + (bb + bb) * u0
            H = h * step_factor(s0, g0, bb, s_c)
            iH = one / H
            d = one / (inv_gamma * iH - E0 * (g0 - k))  # (1/(gamma H) - J)^-1
            ft = -g0 * E0  # dE/ds
            u1 = d * (E0 + H * gx1 * ft)
            E2, o2 = rate(x0 + a21 * u1, s0 + al2 * H, k, a, bb)
            u2 = d * (E2 + H * gx2 * ft + c21 * iH * u1)
            E3, o3 = rate(x0 + a31 * u1 + a32 * u2, s0 + al3 * H, k, a, bb)
            u3 = d * (E3 + H * gx3 * ft + iH * (c31 * u1 + c32 * u2))
            u4 = d * (E3 + H * gx4 * ft + iH * (c41 * u1 + c42 * u2 + c43 * u3))
            x1 = x0 + m1 * u1 + m2 * u2 + m3 * u3 + m4 * u4
            s1 = s0 + H
            E1, o4 = rate(x1, s1, k, a, bb)
            st[_X * W + l], st[_S * W + l] = x1, s1
            st[_E * W + l], st[_EXPO * W + l] = E1, max(max(max(o2, o3), o4), st[_EXPO * W + l])

    return pin(step_all, f.__name__, tableau.name)


class LanePoints(NamedTuple):
    """Per-point arrays of the lane kernels (flat over the plan's points): reduced k = chi/A, a = mu1/A, b = m2/A,
    the early time scale s_c and G = gamma/A (read only by the kernels with the correction)."""

    k: np.ndarray
    a: np.ndarray
    b: np.ndarray
    s_c: np.ndarray
    G: np.ndarray


class LaneRuns(NamedTuple):
    """The runs of one lane call: run r solves point ``point[r]`` at the fixed step ``h[r]`` in sigma; the tail test's
    tolerances and the step limit are common to all."""

    point: np.ndarray
    h: np.ndarray
    rtol: float
    atol: float
    max_steps: int


class LaneOutputs(NamedTuple):
    """Per-run outputs: relaxed slip, its closed-form tail's error bound, first-order inertial correction (empty for
    the kernels without it), status and steps taken."""

    xi_inf: np.ndarray
    tail_err: np.ndarray
    correction: np.ndarray
    status: np.ndarray
    steps: np.ndarray


def make_lane_kernels(dtype, tableau, correction: bool = False):
    """(relax_runs, relax_batch) compiled for ``dtype`` (np.float64 or np.float32) and a fixed-step tableau
    (explicit: :func:`_explicit_step`; Rosenbrock: :func:`_rosenbrock_step`); with ``correction`` (explicit only)
    each run also carries the first-order inertial correction of its relaxed slip, written to
    ``LaneOutputs.correction`` (from ``LanePoints.G``; both are ignored by the kernels without it)."""
    if correction and isinstance(tableau, RosenbrockTableau):
        raise ValueError(f"{tableau.name}: the first-order correction rides in the explicit lanes only")
    f = np.dtype(dtype).type
    rate = make_rate(f)
    correction_rate = make_correction_rate(f)
    zero, one, exp_max = f(0.0), f(1.0), f(EXP_MAX)
    W = LANES
    step_all = (_rosenbrock_step(f, tableau) if isinstance(tableau, RosenbrockTableau)
                else _explicit_step(f, tableau, correction))
    n_fields = _DY + 1 if correction else _STAGE + 2

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def load(st, lane, k, a, b, s_c, G, h):
        st[lane], st[W + lane], st[2 * W + lane], st[3 * W + lane], st[4 * W + lane] = k, a, b, s_c, h
        st[_X * W + lane], st[_S * W + lane] = zero, zero
        dxi, ds, E, expo = rate(zero, zero, k, a, b, s_c)
        st[_STAGE * W + lane], st[(_STAGE + 1) * W + lane], st[_E * W + lane] = dxi, ds, E
        st[_EXPO * W + lane] = expo
        if correction:
            st[_G * W + lane], st[_Y * W + lane] = G, zero
            st[_DY * W + lane] = correction_rate(zero, zero, zero, k, a, b, G, ds, E, expo)

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def take_next(st, lane, lane_run, runs, queued, pts, job):
        """Load the next queued run into ``lane`` (or, with the queue exhausted, a harmless dummy point that the
        lane computes while idle, marked -1); returns the new queue position."""
        if queued < runs.size:
            r = runs[queued]
            p = job.point[r]
            load(st, lane, f(pts.k[p]), f(pts.a[p]), f(pts.b[p]), f(pts.s_c[p]), f(pts.G[p]) if correction else zero,
                 f(job.h[r]))
            lane_run[lane] = r
            return queued + 1
        load(st, lane, one, one, zero, one, zero, zero)
        lane_run[lane] = -1
        return queued

    @njit(cache=True, fastmath=FAST, error_model="numpy")
    def relax_runs(pts, job, runs, out):
        """Solve the runs ``runs`` (indices into the :class:`LaneRuns` ``job``, whose points index the
        :class:`LanePoints` ``pts``) to their relaxed slip, into the :class:`LaneOutputs` ``out`` (and, in the
        kernels with the correction, its first-order inertial correction into ``out.correction``)."""
        st = np.zeros(n_fields * W, dtype=f)
        lane_run = np.full(W, -1, np.int64)
        n = np.zeros(W, np.int64)
        queued, busy = 0, 0
        rtol, atol, max_steps = job.rtol, job.atol, job.max_steps
        for lane in range(W):
            queued = take_next(st, lane, lane_run, runs, queued, pts, job)
            busy += lane_run[lane] >= 0
        while busy > 0:
            step_all(st)
            for lane in range(W):
                r = lane_run[lane]
                if r < 0:
                    continue
                n[lane] += 1
                if n[lane] % CHECK_EVERY != 0 and n[lane] < max_steps:
                    continue
                p = job.point[r]
                k, a, bb = pts.k[p], pts.a[p], pts.b[p]
                xi, u = float(st[_X * W + lane]), float(st[_S * W + lane] - st[_X * W + lane])
                E = float(st[_E * W + lane])
                bound = tail_error(k, a, bb, u, E)
                if st[_EXPO * W + lane] > exp_max or not math.isfinite(xi):
                    out.xi_inf[r], out.status[r] = math.nan, NONFINITE
                elif bound <= TAIL_SAFETY * (rtol * xi + atol):
                    out.xi_inf[r], out.tail_err[r], out.status[r] = xi + tail_slip(k, a, bb, u, E), bound, OK
                    if correction:  # NaN or inf where it overflowed: the caller's fallback; xi_inf stands
                        out.correction[r] = tail_correction(k, a, bb, pts.G[p], u, E, float(st[_Y * W + lane]))
                elif n[lane] >= max_steps:
                    out.xi_inf[r], out.status[r] = math.nan, MAX_STEPS
                else:
                    continue
                out.steps[r] = n[lane]
                n[lane] = 0
                queued = take_next(st, lane, lane_run, runs, queued, pts, job)
                busy -= lane_run[lane] < 0

    for kernel in (load, take_next, relax_runs):
        pin(kernel, f.__name__, tableau.name, correction)
    return relax_runs, pin(lanes_batch(relax_runs, W), f.__name__, tableau.name, correction)


@functools.cache
def lane_kernels(dtype: np.dtype, method: str, correction: bool = False):
    """(relax_runs, relax_batch) for a float type and a fixed-step method of :data:`sweep.integrate.solvers.METHODS`,
    with
    or without the first-order inertial correction (built once per process; numba compiles on first call and
    caches on disk)."""
    return make_lane_kernels(np.dtype(dtype), METHODS[method], correction)


pin_module(__name__)
