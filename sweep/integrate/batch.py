"""Every batch loop of the engine: a parallel loop over a flat batch of points with explicit outputs, one per driver.

This module is where the target of the computation lives: today numba's CPU threads (``prange``), and Python
threads around a ``nogil`` kernel for the adaptive lanes (:func:`lanes_in_threads`: why, there); a GPU target
(one thread per point or lane) would be a second set of these loops, calling the same per-point drivers of
:mod:`sweep.integrate`. A point's arithmetic never depends on the other points of its batch, so results do not
depend on the batch, its order or the number of threads.

Two numba constraints shape the loops: the parallel loop itself can neither build named tuples nor write through
a record's arrays (numba 0.6x loses such writes silently), so each point's work and writes happen in a per-point
function called from the loop (:func:`_solve_into`, :func:`_relax_into`, :func:`_store`).
"""

from __future__ import annotations

import concurrent.futures as cf
import functools
import math
import threading
from typing import NamedTuple

import numba
import numpy as np
from numba import njit, prange

from ..accuracy import GENERAL_ESTIMATE_GAIN, TIGHTER
from ..jitcache import pin, pin_module
from ..status import Status
from .driven import DrivenParams, cached, point_kernel
from .models.stop import StopParams
from .solvers.fastmath import FAST
from .stop_inertial import relax
from .stop_point import FractionTimes, StopOutputs, TimeSamples, solve_stop_point
from .stop_slip import relax_slip

__all__ = ["RelaxOutputs", "RelaxPoints", "StopOutputs", "driven_batch", "lanes_batch", "lanes_in_threads",
           "relax_batch", "relax_points", "slip_batch", "stop_batch"]

OK, NO_FINITE_LIMIT = int(Status.OK), int(Status.NO_FINITE_LIMIT)


@njit(cache=True, fastmath=FAST, error_model="numpy")
def _solve_into(i, method, points, finite, tol, max_steps, tau_samples, obs_tau, fractions, out):
    """Point i of :func:`stop_batch`, written into ``out`` (a function of its own: numba's parfors can neither build
    named tuples nor write through a record's arrays inside the parallel loop itself)."""
    if not finite[i] and out.xi_at.shape[1] == 0:
        out.xi_inf[i], out.xi_inf_err[i], out.status[i], out.steps[i] = math.nan, math.nan, NO_FINITE_LIMIT, 0
        out.tau_at_fraction[i, :] = math.nan
        out.tau_at_fraction_err[i, :] = math.nan
        return
    targets = np.concatenate((tau_samples, obs_tau[i]))
    order_t = np.argsort(targets, kind="mergesort")
    n_t = targets.size
    xs, us, xe, ue = np.full(n_t, math.nan), np.full(n_t, math.nan), np.full(n_t, math.nan), np.full(n_t, math.nan)
    r = solve_stop_point(method, points.h[i], StopParams(points.k[i], points.a[i], points.b[i], points.s_c[i], False),
                         tol, max_steps, finite[i], TimeSamples(targets[order_t], xs, us, xe, ue),
                         FractionTimes(fractions, out.tau_at_fraction[i], out.tau_at_fraction_err[i]))
    out.xi_inf[i], out.xi_inf_err[i], out.status[i], out.steps[i] = r.xi_inf, r.xi_inf_err, r.status, r.steps
    for j in range(n_t):
        out.xi_at[i, order_t[j]], out.u_at[i, order_t[j]] = xs[j], us[j]
        out.xi_at_err[i, order_t[j]], out.u_at_err[i, order_t[j]] = xe[j], ue[j]


@njit(parallel=True, nogil=True, cache=True)
def stop_batch(method, points, finite, tol, max_steps, tau_samples, obs_tau, fractions, out):
    """Solve a flat batch of stop points one by one (:func:`solve_stop_point`) into ``out`` (:class:`StopOutputs`):
    ``method`` a :class:`Method`, ``points`` a :class:`StopPoints` record of per-point arrays, ``finite`` whether
    each has a finite relaxed slip, ``tol`` the scene's :class:`Tolerances`, ``tau_samples`` the trajectory's reduced
    times, obs_tau[i, :] point i's extra reduced times (slip_at), ``fractions`` those of t50/t90 (empty: not asked
    for)."""
    for i in prange(finite.size):  # np.int64(i): prange's index is uint64 inside the parallel loop, int64 when
        # the function is first typed; one type, one compile of the per-point function
        _solve_into(np.int64(i), method, points, finite, tol, max_steps, tau_samples, obs_tau, fractions, out)


class RelaxPoints(NamedTuple):
    """Flat per-point inputs of :func:`relax_batch`, float64: k = chi/A, a = mu1/A, b = m2/A, G = gamma/A."""

    k: np.ndarray
    a: np.ndarray
    b: np.ndarray
    G: np.ndarray


class RelaxOutputs(NamedTuple):
    """Flat per-point outputs of :func:`relax_batch` (:func:`relax`'s; the fields are stop_inertial.RELAX_KEYS):
    relaxed slip xi_inf [1], first-order inertial correction [1], status (int8), steps (int64), s_handover [1]."""

    xi_inf: np.ndarray
    correction: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    s_handover: np.ndarray


@njit(cache=True)
def _relax_into(i, points, inertial, rtol, atol, max_steps, out):
    """Point i of :func:`relax_batch`, written into ``out`` (a function of its own, as :func:`_solve_into`)."""
    out.xi_inf[i], out.correction[i], out.status[i], out.steps[i], out.s_handover[i] = relax(
        points.k[i], points.a[i], points.b[i], points.G[i], inertial, rtol, atol, max_steps)


@njit(parallel=True, nogil=True, cache=True)
def relax_batch(points, inertial, rtol, atol, max_steps, out):
    """:func:`relax` over the flat arrays of ``points`` (:class:`RelaxPoints`), in parallel, into ``out``
    (:class:`RelaxOutputs`)."""
    n = points.k.size
    for i in prange(n):  # np.int64(i): as in stop_batch
        _relax_into(np.int64(i), points, inertial, rtol, atol, max_steps, out)


def relax_points(k: np.ndarray, a: np.ndarray, b: np.ndarray, G: np.ndarray, inertial: bool, rtol: float,
                 atol: float, max_steps: int) -> dict[str, np.ndarray]:
    """:func:`relax_batch` with its output arrays: keys xi_inf, correction, status, steps, s_handover."""
    n = np.size(k)
    out = RelaxOutputs(np.full(n, np.nan), np.full(n, np.nan), np.zeros(n, np.int8), np.zeros(n, np.int64),
                       np.zeros(n))
    relax_batch(RelaxPoints(*(np.ascontiguousarray(x, dtype=float) for x in (k, a, b, G))), inertial, rtol, atol,
                max_steps, out)
    return out._asdict()


@njit(parallel=True, nogil=True, cache=True)
def slip_batch(k, a, b, rtol, atol, max_steps, xi_inf, xi_inf_err, status, steps):
    """Every point of the flat arrays k, a, b at three local tolerances (module docstring)."""
    for i in prange(k.size):
        x1, s1, n1 = relax_slip(k[i], a[i], b[i], rtol / TIGHTER, atol / TIGHTER, max_steps)
        x2, s2, n2 = relax_slip(k[i], a[i], b[i], rtol / TIGHTER**2, atol / TIGHTER**2, max_steps)
        x3, s3, n3 = relax_slip(k[i], a[i], b[i], rtol / TIGHTER**3, atol / TIGHTER**3, max_steps)
        xi_inf[i], xi_inf_err[i] = x2, GENERAL_ESTIMATE_GAIN * max(abs(x2 - x1), abs(x3 - x2))
        status[i] = s2 if s2 != OK else (s1 if s1 != OK else s3)
        steps[i] = n2


@njit(cache=True)
def _store(i, r, out):
    """Point i's result into the output record (a function of its own: numba's parfors lose writes made through a
    record's arrays inside the parallel loop itself)."""
    out.regime[i], out.status[i], out.growth_rate[i], out.period[i] = r.regime, r.status, r.growth_rate, r.period
    out.amplitude[i], out.cycles[i], out.steps[i], out.peak_w[i] = r.amplitude, r.cycles, r.steps, r.peak_w


@functools.cache
def driven_batch(law: str = "aging", inertia: bool = False, slaved: bool = False):
    """batch(points, k, a, b, g, settings: DrivenSettings, out: DrivenOutputs): the points ``points`` (indices into
    the flat arrays k, a, b, g and ``out``) in parallel, one thread per point at a time (a point's arithmetic does
    not depend on the others), with the quasi-static variant of the driven kernel (g = 0) or the one with
    ``inertia`` (``slaved``: on its slow manifold where inertia is small, :func:`point_kernel`). The batch loop is
    where a target other than the CPU threads would plug in."""
    point = point_kernel(law, inertia, slaved)

    @njit(parallel=True, nogil=True, cache=cached(inertia))
    def batch(points, k, a, b, g, settings, out):
        for j in prange(points.size):
            i = points[j]
            _store(i, point(DrivenParams(k[i], a[i], b[i], g[i]), settings), out)

    return pin(batch, law, ("inertial-slaved" if slaved else "inertial") if inertia else "quasistatic")


def lanes_batch(relax_runs, lanes: int):
    """relax_batch(pts, job, groups, out): all runs of ``job`` (sweep/integrate/lanes.py: LanePoints, LaneRuns,
    LaneOutputs) through the lanes kernel ``relax_runs``, in ``groups`` strided groups, each stepped in lanes by one
    thread."""

    @njit(parallel=True, nogil=True, cache=True)
    def relax_batch(pts, job, groups, out):
        groups = max(1, min(groups, job.point.size // lanes))
        for g in prange(groups):
            relax_runs(pts, job, np.arange(g, job.point.size, groups), out)

    return relax_batch


@functools.cache
def _helpers(n: int) -> cf.ThreadPoolExecutor:
    """``n`` helper threads, made once per process (they wait idle between batches)."""
    return cf.ThreadPoolExecutor(n, thread_name_prefix="sweep-lanes")


def lanes_in_threads(relax_runs, lanes: int):
    """relax_batch(pts, job, groups, out) as :func:`lanes_batch`, with the threads in Python: ``relax_runs`` (compiled
    ``nogil``) is the compiled entry point, called once per group from numba.get_num_threads() threads (this one and
    helpers), which take the groups as they come free; with one thread, one call over all runs.

    Why not prange: a process that compiles a kernel runs its callees' own code, one that loads it from numba's
    cache runs the callees as optimised into their caller; with FMA contraction the two round differently (the
    adaptive lanes with one loop per stage: 80 % of the default scene's points differed at ~1e-7 between a cold and
    a warm process, and a resumed or dask run was not bit for bit an uninterrupted one). Called from Python,
    ``relax_runs`` is no one's callee, and its own callees are inlined (``inline="always"``), so every process runs
    the same code."""

    def relax_batch(pts, job, groups, out):
        n = job.point.size
        groups = max(1, min(groups, n // lanes))
        threads = min(numba.get_num_threads(), groups)
        if threads == 1:
            relax_runs(pts, job, np.arange(n), out)
            return
        shares = iter([np.arange(g, n, groups) for g in range(groups)])
        taking = threading.Lock()

        def work() -> None:  # the next group, until none is left
            while True:
                with taking:
                    share = next(shares, None)
                if share is None:
                    return
                relax_runs(pts, job, share, out)

        helping = [_helpers(threads - 1).submit(work) for _ in range(threads - 1)]
        try:
            work()  # this thread is one of the threads
        finally:
            for helper in helping:
                helper.result()  # (waited for also when this thread's groups failed; a helper's error is raised)

    return relax_batch


pin_module(__name__)
