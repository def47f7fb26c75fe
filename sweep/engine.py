"""Engine: run a plan's points through the compiled kernel in chunks, in parallel, with progress.

The numba layer (``stop_batch``) knows nothing of xarray: it fills preallocated flat arrays, one point
written once by one thread. The costly points cluster in one corner of the grid (small K/M with mu1 < 0) and
numba's prange splits a batch into equal contiguous shares, so the points are visited in a fixed
pseudo-random order: every chunk, and every thread's share of it, then mixes cheap and costly points
(2 threads: 1.2x -> 1.96x speed-up on the default scene). Results do not depend on the order. Sweeps of the
relaxed slip alone go through ``relax_batch`` instead (two points in flight per thread, models/stop_lanes.py).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numba
import numpy as np
from numba import njit, prange

from .models.stop import NO_FINITE_LIMIT, solve_stop_point
from .models.stop_lanes import relax_in_lanes
from .plan import Plan, make_plan
from .progress import Progress
from .scene import Scene

__all__ = ["RawResult", "estimate_seconds", "execute", "warm_up"]

FRACTIONS = np.array([0.5, 0.9])
"""Fractions of the relaxed slip whose times are reported as t50 and t90."""
ORDER_SEED = 20261121


@njit(parallel=True, cache=True)
def stop_batch(k, a, b, s_c, finite, h, max_steps, rtol, atol, tau_samples, obs_tau, want_fractions,
               xi_inf, status, steps, xi_at, u_at, tau_at_fraction):
    """Solve a flat batch of stop points. obs_tau[i, :] are point i's extra reduced times (slip_at)."""
    fractions = FRACTIONS if want_fractions else np.empty(0)
    for i in prange(k.size):
        if not finite[i] and xi_at.shape[1] == 0:
            xi_inf[i], status[i], steps[i] = math.nan, NO_FINITE_LIMIT, 0
            tau_at_fraction[i, :] = math.nan
            continue
        targets = np.concatenate((tau_samples, obs_tau[i]))
        order = np.argsort(targets, kind="mergesort")
        xs, us = np.full(targets.size, math.nan), np.full(targets.size, math.nan)
        st, x, n = solve_stop_point(k[i], a[i], b[i], h[i], s_c[i], max_steps, finite[i], rtol, atol,
                                    targets[order], xs, us, fractions, tau_at_fraction[i])
        xi_inf[i], status[i], steps[i] = x, st, n
        for j in range(targets.size):
            xi_at[i, order[j]] = xs[j]
            u_at[i, order[j]] = us[j]


@njit(parallel=True, cache=True)
def relax_batch(k, a, b, s_c, finite, h, max_steps, rtol, atol, groups, xi_inf, status, steps):
    """xi_inf-only batch: strided groups of points, each group stepped in lanes by one thread. Few, large
    groups keep both lanes busy (a group's last point runs alone); four per thread still balance the load."""
    groups = min(groups, k.size)
    for g in prange(groups):
        relax_in_lanes(k, a, b, h, s_c, finite, max_steps, rtol, atol, np.arange(g, k.size, groups), xi_inf,
                       status, steps)


@dataclass
class RawResult:
    """Flat per-point outputs of the kernel (numpy only), in reduced units."""

    xi_inf: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    xi_at: np.ndarray
    u_at: np.ndarray
    tau_at_fraction: np.ndarray
    seconds: float


def _obs_tau(scene: Scene) -> np.ndarray:
    """Reduced times tau = V t / D0 of the slip_at observations, per flat point."""
    t = np.asarray(scene.t_obs if "slip_at" in scene.observables else (), dtype=float)
    tau_v = scene.V[:, None] * t[None, :] / scene.params.D0
    return np.broadcast_to(tau_v[None, :, :], (*scene.shape, t.size)).reshape(scene.n_points, t.size)


def execute(scene: Scene, plan: Plan, indices: np.ndarray | None = None, progress: bool | None = None,
            chunk_size: int | None = None) -> RawResult:
    """Run ``plan`` over the points ``indices`` (default: all) of ``scene``; returns flat outputs."""
    idx = np.arange(plan.n_points) if indices is None else np.asarray(indices)
    obs_tau = _obs_tau(scene)
    n_t = plan.tau_samples.size + obs_tau.shape[1]
    n = idx.size
    out = RawResult(np.full(n, np.nan), np.zeros(n, np.int8), np.zeros(n, np.int32),
                    np.full((n, n_t), np.nan), np.full((n, n_t), np.nan), np.full((n, 2), np.nan), 0.0)
    want_fractions = bool({"t50", "t90"} & set(scene.observables))
    relaxed_slip_only = n_t == 0 and not want_fractions
    atol = scene.atol["xi_inf"]
    n_chunks = max(1, math.ceil(n / (chunk_size or 4096)))
    order = np.random.default_rng(ORDER_SEED).permutation(n)
    t0 = time.perf_counter()
    with Progress(n, enabled=progress) as bar:
        for sel in np.array_split(order, n_chunks):
            g = idx[sel]
            per_point = (plan.k[g], plan.a[g], plan.b[g], plan.s_c[g], plan.finite[g], plan.step[g])
            parts = [np.empty(sel.size), np.empty(sel.size, np.int8), np.empty(sel.size, np.int32)]
            if relaxed_slip_only:
                relax_batch(*per_point, plan.max_steps, scene.rtol, atol, 4 * numba.get_num_threads(), *parts)
            else:
                parts += [np.empty((sel.size, n_t)), np.empty((sel.size, n_t)), np.empty((sel.size, 2))]
                stop_batch(*per_point, plan.max_steps, scene.rtol, atol, plan.tau_samples,
                           np.ascontiguousarray(obs_tau[g]), want_fractions, *parts)
            for dest, part in zip((out.xi_inf, out.status, out.steps, out.xi_at, out.u_at, out.tau_at_fraction),
                                  parts):
                dest[sel] = part
            bar.update(sel.size)
    out.seconds = time.perf_counter() - t0
    return out


def warm_up(scene: Scene, plan: Plan) -> float:
    """Compile the kernel (or load it from numba's on-disk cache) on one point; returns the seconds taken."""
    t0 = time.perf_counter()
    execute(scene, plan, np.arange(1), progress=False)
    return time.perf_counter() - t0


def estimate_seconds(scene: Scene, plan: Plan | None = None, sample: int = 256) -> tuple[float, float]:
    """Estimate the wall time of the whole sweep by timing a strided pilot subsample.

    Returns (estimated seconds, mean steps per point of the pilot). The kernel is warmed up first, and the
    pilot (milliseconds long) is timed three times, keeping the fastest, so that a passing hiccup of the
    machine does not inflate the estimate.
    """
    plan = plan or make_plan(scene)
    stride = max(1, plan.n_points // sample)
    pilot = np.arange(0, plan.n_points, stride)
    warm_up(scene, plan)
    runs = [execute(scene, plan, pilot, progress=False) for _ in range(3)]
    seconds = min(r.seconds for r in runs)
    return seconds * plan.n_points / pilot.size, float(runs[0].steps.mean())
