#!/usr/bin/env python
"""Throughput benchmark of the sweep engine, side by side with scipy and a plain-numpy RK4, in one run.

    python benchmarks/throughput.py [--quick] [--out benchmarks/results/throughput.json] [--no-png]

Every engine number goes through the public path (sweep.make_plan + sweep.protocols.stop.chunk.execute, what run_sweep
runs,
or run_sweep itself), so the script does not depend on the kernels' internals. Every point is solved as the
engine always solves it: down its step ladder (sweep/integrate/ladder.py: a pilot pair at 2 h0, h0, then up to three
finer runs at steps chosen from the point's own error; with a step given by the user, Scene(step=h), the fixed
runs 4h, 2h, h), the finest run's result returned with its error estimate, and the timings include every run.
execute's RawResult.steps are the returned run's steps (the per-point distribution below), RawResult.work the
steps of all runs of the point (all step and evaluation counts below; exact on the lanes, 1.5 x steps on the
per-point path). Sections (benchmarks/README.md explains every number):

1. engine      trajectories/s on the default scene (sweep.default_scene(): sample2, 200 x 100, rtol 1e-6),
               warm (one call first, then best of 3), with 1 thread and all threads; steps per point (returned
               run); ns per step and per stage evaluation per core, counting the steps of all runs (work).
2. scipy       solve_ivp's DOP853 and LSODA steppers on a strided subsample of the same grid (corners
               included), given the engine's own formulation (1-D ODE dxi/ds = E in contact-age time, the
               engine's tail test and closed-form tail), each at the loosest scanned tolerance whose max
               relative xi_inf error is <= 1e-6 against the engine at rtol 1e-10; ratio vs the engine. Then
               each method at its chosen tolerance on a uniformly random subsample (64 points, fixed seed):
               an unbiased estimate of scipy's mean cost per trajectory over the grid.
3. numpy       the engine's RK4 with a fixed step (Scene(step=h, method="rk4"): every point's ladder is the
               fixed 4h, 2h, h, the run at h returned; h = the default plan's smallest RK4 pilot step) against
               the same three runs per point (same state-dependent time map, per-run stop) written as lockstep
               numpy, over the grid points the default plan gives to RK4 (points it gives another method, e.g.
               the Rosenbrock stiff points, are left out), both on one core: agreement of numpy's run at h with
               the engine's xi_inf, and cost per RK4 stage evaluation from numpy's own step counts and the
               engine's work (target: engine >= 3x cheaper per evaluation).
4. cold start  a new Python process: import sweep + a 10 x 10 sweep, JIT cache on disk (median of 3).
5. estimate    sweep.protocols.stop.estimate.estimate_seconds vs the measured time, default scene and sample1 100 x 100.

No longer measured (the code it measured is gone or internal): the parallel diagnostic that called the compiled
per-point batch kernel (stop_batch) directly, in grid order and shuffled, to show the load imbalance of a static
prange split. Relaxed-slip sweeps no longer run through that kernel (they run in SIMD lanes, in strided groups
per thread) and its signature is internal; parallel_speedup of the public execute remains.

Writes benchmarks/results/throughput.json (and throughput.png if matplotlib is present); prints a table.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as _dt
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

import _common as common
import numba
import numpy as np
import scipy.special
from scipy.integrate import DOP853, LSODA

import sweep
from sweep import physics
from sweep.integrate.models.stop import E_TAIL_MAX, EXP_MAX, RATE_FLOOR, TAIL_SAFETY
from sweep.integrate.solvers import METHODS
from sweep.protocols.stop.chunk import execute
from sweep.protocols.stop.estimate import estimate_seconds

HERE = Path(__file__).resolve().parent
DEFAULT_OUT = HERE / "results" / "throughput.json"
TARGET_RATIO = 50.0
TARGET_COLD_S = 2.0
TARGET_ESTIMATE = 2.0
TARGET_NUMPY_PER_EVAL = 3.0
ERROR_TARGET = 1e-6
REF_RTOL = 1e-10
RANDOM_POINTS = 64
RANDOM_SEED = 20240611
SQRT_PI = math.sqrt(math.pi)
OK = int(sweep.Status.OK)
OK_LIKE = (OK, int(sweep.Status.ERROR_ABOVE_TOL))  # a value was computed (error_above_tol: estimate > tol)


# ----------------------------------------------------------------------------------------------- helpers

def best_of(fn, repeats):
    """(best wall seconds, wall seconds of every call, last result) of ``repeats`` calls of fn()."""
    _, wall, out = common.timings(fn, repeats)
    return min(wall), wall, out


def percentiles(x) -> dict:
    q = (0, 5, 25, 50, 75, 95, 99, 100)
    return {f"p{p}": float(v) for p, v in zip(q, np.percentile(x, q))}


def subsample_indices(scene: sweep.Scene, n_side: int) -> np.ndarray:
    """Flat indices of an n_side x n_side strided sub-grid that includes all four corners of the grid."""
    nk, nv = scene.shape
    ki = np.unique(np.round(np.linspace(0, nk - 1, n_side)).astype(int))
    vi = np.unique(np.round(np.linspace(0, nv - 1, n_side)).astype(int))
    return (ki[:, None] * nv + vi[None, :]).ravel()


def random_indices(scene: sweep.Scene, n: int, seed: int = RANDOM_SEED) -> np.ndarray:
    """Sorted flat indices of n grid points drawn uniformly without replacement (numpy default_rng(seed))."""
    n_points = scene.shape[0] * scene.shape[1]
    return np.sort(np.random.default_rng(seed).choice(n_points, size=min(n, n_points), replace=False))


def evals_per_step(method: str) -> int:
    """Right-hand-side evaluations per accepted step of a method of sweep.integrate.solvers.METHODS: the stages after
    the
    first, whose derivative is the previous step's end, plus the end derivative (an FSAL tableau's last stage is
    that derivative). A Rosenbrock stage with the same evaluation point as the one before reuses its value
    (Shampine's ROS4: 3 evaluations for 4 stages)."""
    tab = METHODS[method]
    if getattr(tab, "implicit", False):
        return len({(tuple(row), alpha) for row, alpha in zip(tab.a, tab.alpha_x)})
    return tab.stages - (1 if tab.fsal else 0)


def point_methods(plan) -> np.ndarray:
    """The method of every point (a plan may give some points another method than plan.method, e.g. the stiff
    points of an "auto" plan: Plan.point_methods / Plan.point_method where the plan has them)."""
    names = getattr(plan, "point_methods", None)
    if names is None:
        return np.full(plan.n_points, plan.method, dtype=object)
    return np.asarray(names, dtype=object)[plan.point_method]


def point_evals(plan) -> np.ndarray:
    """Right-hand-side evaluations per step of every point's method."""
    names, inverse = np.unique(point_methods(plan).astype(str), return_inverse=True)
    return np.array([evals_per_step(m) for m in names], dtype=np.int64)[inverse.ravel()]


# ------------------------------------------------------------------------------------------- 1. engine

def bench_engine(scene, plan, repeats, n_all):
    n = plan.n_points
    t0 = time.perf_counter()
    first = execute(scene, plan, progress=False)  # loads the kernel from the on-disk cache (or compiles)
    first_s = time.perf_counter() - t0
    out = {"first_call_s": first_s, "method": plan.method, "adaptive": plan.adaptive, "lanes": plan.lanes,
           "dtype": plan.dtype.name}
    runs = {}
    for nt in sorted({1, n_all}):
        numba.set_num_threads(nt)
        cpu, wall, res = common.timings(lambda: execute(scene, plan, progress=False), repeats)
        best = min(wall)
        runs[nt] = (best, res)
        out[f"threads_{nt}"] = {"best_s": best, "all_s": wall, "best_cpu_s": min(cpu), "traj_per_s": n / best,
                                "traj_per_s_per_core": n / best / nt, "us_per_traj_per_core": best * nt / n * 1e6}
    numba.set_num_threads(n_all)
    res = runs[1][1]
    assert np.array_equal(res.xi_inf, first.xi_inf, equal_nan=True), "engine is not deterministic"
    assert np.array_equal(res.xi_inf, runs[n_all][1].xi_inf, equal_nan=True), "result depends on the threads"
    steps, work = res.steps.astype(np.int64), res.work.astype(np.int64)  # returned run; all runs of the ladder
    assert np.all(work >= steps), "RawResult.work below the returned run's steps"
    total = int(steps.sum())
    out["points"] = n
    out["status_counts"] = {sweep.Status(int(c)).name: int(m) for c, m in zip(*np.unique(res.status,
                                                                                          return_counts=True))}
    out["steps_per_point"] = {"mean": float(steps.mean()), "total": total, **percentiles(steps)}
    edges = np.array([0, 50, 100, 200, 500, 1000, 2000, 5000, 10000, 20000, 10**9])
    cnt, _ = np.histogram(steps, edges)
    out["steps_histogram"] = {"edges": edges.tolist(), "counts": cnt.tolist()}
    heavy = steps > 1000
    out["share_of_steps_in_points_over_1000_steps"] = float(steps[heavy].sum() / total)
    out["points_over_1000_steps"] = int(heavy.sum())
    i_max = int(np.argmax(steps))
    ik, iv = np.unravel_index(i_max, scene.shape)
    out["costliest_point"] = {"K_over_M": float(scene.K_over_M[ik]), "V": float(scene.V[iv]),
                              "chi_over_A": float(plan.k[i_max]), "mu1_over_A": float(plan.a[i_max]),
                              "steps": int(steps[i_max]), "xi_inf": float(res.xi_inf[i_max])}
    out["all_runs_steps_per_point"] = {"mean": float(work.mean()), **percentiles(work)}
    evals = point_evals(plan)
    run_steps = int(work.sum())
    stage_evals = int((evals * work).sum())
    methods = point_methods(plan)
    out["ladder"] = {"returned_run_steps_total": total, "all_runs_steps_total": run_steps,
                     "all_runs_over_returned": run_steps / total, "stage_evals_total": stage_evals,
                     "stage_evals_per_step": stage_evals / run_steps,
                     "work_exact": bool(plan.lanes)}  # per-point path: RawResult.work is 1.5 x steps, not counted
    out["by_method"] = {m: {"points": int(np.count_nonzero(methods == m)), "evals_per_step": evals_per_step(m),
                            "returned_run_steps_total": int(steps[methods == m].sum()),
                            "all_runs_steps_total": int(work[methods == m].sum())} for m in dict.fromkeys(methods)}
    for nt in sorted({1, n_all}):
        best = runs[nt][0]
        out[f"threads_{nt}"]["ns_per_step_per_core"] = best * nt / run_steps * 1e9
        out[f"threads_{nt}"]["ns_per_stage_eval_per_core"] = best * nt / stage_evals * 1e9
    out["parallel_speedup"] = runs[1][0] / runs[n_all][0] if n_all > 1 else 1.0
    # the public path (plan + kernels + the choice of model + Dataset) on the same scene, model "auto" as
    # sweep.default_scene() has it. execute runs the quasi-static kernels only (no choice of model); run_sweep
    # solves the points that "auto" gives to the inertial model again with inertia, and their ds["steps"] are the
    # inertial solver's. So like is compared with like: the steps of the points run_sweep left quasi-static
    # (ds["model"] == 0) must be the kernel's, exactly; the inertial points are counted, not compared. (Pinning
    # model="quasistatic" would compare every point, but would no longer time the default scene's run_sweep.)
    best, _, ds = best_of(lambda: sweep.run_sweep(scene, progress=False), repeats)
    quasistatic = ds["model"].values.ravel() == 0
    assert np.array_equal(ds["steps"].values.ravel()[quasistatic], res.steps[quasistatic]), \
        "ds['steps'] differs from the kernel's steps on the points run_sweep left quasi-static"
    out["run_sweep_s_all_threads"] = best
    out["run_sweep_model"] = scene.model
    out["run_sweep_points_by_model"] = {"quasistatic": int(quasistatic.sum()),
                                        "inertial": int((~quasistatic).sum())}
    out["run_sweep_steps_checked_points"] = int(quasistatic.sum())
    return out, res


# ----------------------------------------------------------------------------------- reference values

def reference(scene, idx):
    """The engine at rtol 1e-10 on the points idx (flat); checked against the m2 = 0 closed form."""
    ref_scene = dataclasses.replace(scene, rtol=REF_RTOL)
    res = execute(ref_scene, sweep.make_plan(ref_scene), idx, progress=False)
    assert np.all(res.status == OK), "reference run did not converge everywhere"
    return res


def closed_form_check(scene):
    """Engine at rtol 1e-10 against xi_inf = A ln(chi/m1)/(chi - m1) with m2 = 0 (stable and unstable chi)."""
    p0 = scene.params.replace(m2=0.0)
    K = np.array([1e3, 1e4, 3e5, 1e6])
    sc0 = sweep.Scene(protocol="stop", params=p0, K_over_M=K, V=np.array([1e-6]), rtol=REF_RTOL)
    res = execute(sc0, sweep.make_plan(sc0), progress=False)
    chi = physics.reduced_stiffness(K, p0.D0, p0.g)
    exact = physics.xi_inf_m2zero(chi, p0.A, p0.m1)
    rel = np.abs(res.xi_inf / exact - 1)
    return {"K_over_M": K.tolist(), "chi": np.asarray(chi).tolist(), "xi_inf_engine": res.xi_inf.tolist(),
            "xi_inf_exact": np.asarray(exact).tolist(), "rel_err": rel.tolist(), "max_rel_err": float(rel.max())}


# -------------------------------------------------------------------------------------------- 2. scipy

def scipy_run(cls, plan, idx, rtol, atol, tail_rel, tail_abs):
    out = [common.scipy_point(cls, plan.k[i], plan.a[i], plan.b[i], rtol, atol, tail_rel, tail_abs) for i in idx]
    return (np.array([o[0] for o in out]), np.array([o[1] for o in out]), np.array([o[2] for o in out]))


def bench_scipy(scene, plan, idx, ref_xi, tols, atol_factors, repeats):
    tail_rel, tail_abs = scene.rtol, scene.atol["xi_inf"]  # the engine's own stopping criterion
    methods = {}
    for cls in (DOP853, LSODA):
        scipy_run(cls, plan, idx[:2], 1e-6, 1e-9, tail_rel, tail_abs)  # warm-up
        scan = []
        for af in atol_factors:
            for rt in tols:
                t0 = time.perf_counter()
                xi, st, nfev = scipy_run(cls, plan, idx, rt, rt * af, tail_rel, tail_abs)
                dt = time.perf_counter() - t0
                err = float(np.max(np.abs(xi / ref_xi - 1)))
                scan.append({"rtol": rt, "atol": rt * af, "atol_over_rtol": af, "max_rel_err": err,
                             "ms_per_traj": dt / idx.size * 1e3, "mean_steps": float(st.mean()),
                             "mean_nfev": float(nfev.mean()), "max_nfev": int(nfev.max())})
        # per atol family: the loosest rtol from which on every tighter scanned rtol also meets the target
        choices = []
        for af in atol_factors:
            fam = [r for r in scan if r["atol_over_rtol"] == af]  # loose -> tight
            ok = [r["max_rel_err"] <= ERROR_TARGET for r in fam]
            first = next((j for j in range(len(fam)) if all(ok[j:])), None)
            if first is not None:
                choices.append(fam[first])
        if not choices:
            methods[cls.__name__] = {"scan": scan, "chosen": None}
            continue
        choice = min(choices, key=lambda r: r["ms_per_traj"])
        run = lambda cls=cls, rt=choice["rtol"], at=choice["atol"]: scipy_run(cls, plan, idx, rt, at, tail_rel,
                                                                              tail_abs)
        best, times, (xi, st, nfev) = best_of(run, repeats)
        rel = np.abs(xi / ref_xi - 1)
        j_max = int(np.argmax(nfev))
        methods[cls.__name__] = {
            "scan": scan,
            "chosen": {"rtol": choice["rtol"], "atol": choice["atol"], "max_rel_err": float(rel.max()),
                       "median_rel_err": float(np.median(rel)),
                       "ms_per_traj": best / idx.size * 1e3, "all_s": times, "mean_steps": float(st.mean()),
                       "mean_nfev": float(nfev.mean()), "max_nfev": int(nfev.max()),
                       "us_per_rhs_eval": best / nfev.sum() * 1e6,
                       "costliest_point_flat_index": int(idx[j_max])}}
    return methods


def bench_scipy_at_chosen(scene, plan, idx, ref_xi, methods, repeats):
    """Each method at the tolerance chosen on the strided subsample, re-timed (best of ``repeats``) on the
    points idx (the uniformly random subsample): an unbiased estimate of scipy's mean cost over the grid."""
    tail_rel, tail_abs = scene.rtol, scene.atol["xi_inf"]
    out = {}
    for name, m in methods.items():
        ch = m["chosen"]
        if ch is None:
            out[name] = None
            continue
        cls = {"DOP853": DOP853, "LSODA": LSODA}[name]
        run = lambda cls=cls, rt=ch["rtol"], at=ch["atol"]: scipy_run(cls, plan, idx, rt, at, tail_rel, tail_abs)
        best, times, (xi, st, nfev) = best_of(run, repeats)
        rel = np.abs(xi / ref_xi - 1)
        out[name] = {"rtol": ch["rtol"], "atol": ch["atol"], "max_rel_err": float(rel.max()),
                     "median_rel_err": float(np.median(rel)),
                     "meets_error_target": bool(rel.max() <= ERROR_TARGET),
                     "ms_per_traj": best / idx.size * 1e3, "all_s": times, "mean_steps": float(st.mean()),
                     "mean_nfev": float(nfev.mean()), "max_nfev": int(nfev.max()),
                     "us_per_rhs_eval": best / nfev.sum() * 1e6}
    return out


def bench_engine_subsample(scene, plan, idx, ref_xi, reps):
    """The engine (1 thread) on the points idx: us per trajectory (all runs of each ladder), error vs ref_xi.
    RHS evaluations: evaluations per step x the steps of all runs (RawResult.work); the first derivative of each
    run (2..5 per point: RawResult does not say how many runs) is not counted."""
    numba.set_num_threads(1)
    execute(scene, plan, idx, progress=False)
    best, _, res = best_of(lambda: execute(scene, plan, idx, progress=False), reps)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    rel = np.abs(res.xi_inf / ref_xi - 1)
    evals = point_evals(plan)[idx] * res.work
    return {"threads": 1, "us_per_traj": best / idx.size * 1e6, "mean_steps": float(res.steps.mean()),
            "mean_steps_all_runs": float(res.work.mean()), "mean_rhs_evals": float(evals.mean()),
            "max_rel_err": float(rel.max()), "median_rel_err": float(np.median(rel))}


# ------------------------------------------------------------------------------------------- 3. numpy

def _erfcx(z):
    """The engine's erfcx (exp(z^2) erfc(z) below 25, asymptotic series beyond), vectorised."""
    zs = np.minimum(z, 25.0)
    iz2 = 1.0 / (z * z)
    asym = (1.0 - 0.5 * iz2 * (1.0 - 1.5 * iz2 * (1.0 - 2.5 * iz2))) / (z * SQRT_PI)
    return np.where(z < 25.0, np.exp(zs * zs) * scipy.special.erfc(zs), asym)


def _tail_integral(a, b, u, order):
    kb = order * b
    bs = np.where(b == 0.0, 1.0, b)
    gauss = 0.5 * SQRT_PI / np.sqrt(np.where(kb == 0.0, 1.0, kb)) * _erfcx(np.sqrt(kb) * (u + 0.5 * a / bs))
    return np.where(b == 0.0, 1.0 / (order * a), gauss)


def _tail_slip(k, a, b, u, E):
    T = E * _tail_integral(a, b, u, 1.0) + E * E * _tail_integral(a, b, u, 2.0)
    return np.log1p(k * T) / k


def numpy_lockstep(plan, method, run_point, run_h, rtol, atol):
    """The engine's fixed-step stepper as lockstep numpy over runs (a run = one point at one step h in sigma):
    state (xi, s), ds/dsigma = w = 1/(1/(s + s_c) + r(u)) with r = sqrt(g^2 + |b|/4) + RATE_FLOOR, g = a + 2 b u
    (sweep.integrate.models.stop.make_rate), the explicit tableau of ``method`` (RK4: stage i from stage i-1 only)
    with the end
    derivative
    reused as the next step's first stage, each run frozen (removed from the active set) once its tail test
    passes (or it leaves the finite range), then the closed-form tail. Returns per run (xi_inf, status, steps),
    the seconds, the number of lockstep steps and the cost split by the number of active runs."""
    tab = METHODS[method]
    _, A, bw, _ = tab.arrays()
    stages, fsal = bw.size, tab.fsal
    e_step = evals_per_step(method)
    n = run_point.size
    xi_inf = np.full(n, np.nan)
    status = np.full(n, int(sweep.Status.MAX_STEPS), np.int8)  # unless finished
    steps = np.zeros(n, np.int32)
    finite = plan.finite[run_point]
    status[~finite] = int(sweep.Status.NO_FINITE_LIMIT)
    act = np.flatnonzero(finite)
    k, a, b, s_c = (x[run_point[act]] for x in (plan.k, plan.a, plan.b, plan.s_c))
    h = run_h[act].copy()
    xi = np.zeros(act.size)
    s = np.zeros(act.size)

    def deriv(xi, s):
        u = s - xi
        g = a + 2.0 * b * u
        r = np.sqrt(g * g + 0.25 * np.abs(b)) + RATE_FLOOR
        sc = s + s_c
        w = sc / (1.0 + r * sc)
        expo = -(k * xi + u * (a + b * u))
        expo[expo > EXP_MAX] = np.nan
        E = np.exp(expo)
        return w * E, w, E

    t_step = []
    n_step = 0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        dxi, ds, E = deriv(xi, s)
        t0 = time.perf_counter()
        while act.size and n_step < plan.max_steps:
            Kx, Ks = [dxi], [ds]
            for i in range(1, stages):
                xs, ss = xi, s
                for j in range(i):
                    if A[i, j] != 0.0:
                        xs, ss = xs + A[i, j] * h * Kx[j], ss + A[i, j] * h * Ks[j]
                kx, ks, _ = deriv(xs, ss)
                Kx.append(kx)
                Ks.append(ks)
            sx, ss = bw[0] * Kx[0], bw[0] * Ks[0]
            for j in range(1, stages):
                sx, ss = sx + bw[j] * Kx[j], ss + bw[j] * Ks[j]
            xi, s = xi + h * sx, s + h * ss
            if fsal:
                dxi, ds = Kx[-1], Ks[-1]
                E = dxi / ds
            else:
                dxi, ds, E = deriv(xi, s)
            n_step += 1
            bad = ~(np.isfinite(xi) & np.isfinite(dxi))
            u = s - xi
            g = a + 2.0 * b * u
            tol = rtol * xi + atol
            done = (g > 0.0) & (E <= E_TAIL_MAX) & (E * E * E * (1.0 / (3.0 * g) + k / (2.0 * g * g))
                                                     <= TAIL_SAFETY * tol)
            done &= ~bad
            stop = done | bad
            if stop.any():
                ids = act[done]
                xi_inf[ids] = xi[done] + _tail_slip(k[done], a[done], b[done], u[done], E[done])
                status[ids] = OK
                status[act[bad]] = int(sweep.Status.NONFINITE)
                steps[act[stop]] = n_step
                keep = ~stop
                act, xi, s, dxi, ds, E = act[keep], xi[keep], s[keep], dxi[keep], ds[keep], E[keep]
                k, a, b, s_c, h = k[keep], a[keep], b[keep], s_c[keep], h[keep]
            t_step.append((time.perf_counter(), int(act.size) + int(stop.sum())))
        steps[act] = n_step
        seconds = time.perf_counter() - t0
    # cost split: steps with >= 4096 active runs (numpy's SIMD regime) and the long tail with few runs
    tt = np.array([t for t, _ in t_step])
    na = np.array([m for _, m in t_step], dtype=float)
    dt = np.diff(np.concatenate(([t0], tt)))
    big = na >= 4096
    phases = {}
    for name, m in (("active_ge_4096", big), ("active_lt_4096", ~big)):
        evals = e_step * na[m].sum()
        phases[name] = {"lockstep_steps": int(m.sum()), "seconds": float(dt[m].sum()),
                        "point_stage_evals": float(evals),
                        "ns_per_point_stage_eval": float(dt[m].sum() / evals * 1e9) if evals else None}
    return xi_inf, status, steps, seconds, n_step, phases


LADDER_FIXED = np.array([4.0, 2.0, 1.0])
"""The runs of a fixed ladder (Scene(step=h), sweep/integrate/ladder.py) in units of h; the last one is returned."""


def bench_numpy(scene, plan, repeats, method="rk4"):
    """The engine with a fixed step h (Scene(step=h, method=method): every point's ladder is the fixed 4h, 2h, h,
    the run at h returned) and the same three runs per point as lockstep numpy, on one core each, over the points
    the default plan gives to ``method`` (h: their smallest pilot step in the default plan)."""
    idx = np.flatnonzero(point_methods(plan) == method)
    if idx.size == 0:
        return {"skipped": f"the default scene's plan gives no point to {method}: no numpy replica"}
    h = float(plan.step[idx].min())
    fixed = dataclasses.replace(scene, step=h, method=method)
    fplan = sweep.make_plan(fixed)
    assert fplan.step_source == "override" and fplan.lanes and set(fplan.point_methods) == {method}
    numba.set_num_threads(1)
    execute(fixed, fplan, idx, progress=False)
    t_engine, t_engine_all, eng = best_of(lambda: execute(fixed, fplan, idx, progress=False), repeats + 1)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    n_runs = LADDER_FIXED.size
    run_point = np.repeat(idx, n_runs)
    run_h = h * np.tile(LADDER_FIXED, idx.size)
    best, times, (xi, status, steps, _, n_lock, phases) = best_of(
        lambda: numpy_lockstep(fplan, method, run_point, run_h, fixed.rtol, fixed.atol["xi_inf"]), repeats)
    xi, status, steps = (x.reshape(idx.size, n_runs) for x in (xi, status, steps))
    # the engine's rule (sweep/integrate/ladder.py): the returned run's status, else nonfinite where a coarser run left
    # no value to estimate the error from
    ladder_status = np.where(status[:, -1] != OK, status[:, -1],
                             np.where(np.all(status == OK, axis=1), OK, int(sweep.Status.NONFINITE)))
    e_status = np.where(np.isin(eng.status, OK_LIKE), OK, eng.status)  # numpy makes no error estimate
    ok = (ladder_status == OK) & (e_status == OK)
    rel = np.abs(xi[ok, -1] / eng.xi_inf[ok] - 1)
    work = steps.astype(np.int64).sum(axis=1)
    e_step = evals_per_step(method)
    evals = e_step * int(work.sum())
    engine_evals = e_step * int(eng.work.sum())
    ns_np = best / evals * 1e9
    ns_eng = t_engine / engine_evals * 1e9
    return {"method": method, "step_h_sigma": h, "ladder_steps_over_h": LADDER_FIXED.tolist(),
            "points": int(idx.size), "points_other_methods": int(plan.n_points - idx.size),
            "runs": int(run_point.size), "best_s": best, "all_s": times, "traj_per_s": idx.size / best,
            "lockstep_steps": n_lock, "status_equal": bool(np.array_equal(ladder_status, e_status)),
            "status_counts_engine": {sweep.Status(int(c)).name: int(m) for c, m in zip(*np.unique(
                eng.status, return_counts=True))},
            "returned_run_steps_differ_points": int(np.count_nonzero(steps[:, -1] != eng.steps)),
            "all_runs_steps_differ_points": int(np.count_nonzero(work != eng.work)),
            "compared_points": int(ok.sum()),
            "max_rel_diff_vs_engine": float(rel.max()), "median_rel_diff_vs_engine": float(np.median(rel)),
            "evals_per_step": e_step, "point_stage_evals": evals, "engine_point_stage_evals": engine_evals,
            "engine_s_1_thread_same_points": t_engine, "engine_all_s": t_engine_all,
            "ns_per_point_stage_eval": ns_np, "engine_ns_per_point_stage_eval_1_thread": ns_eng,
            "numpy_over_engine_1_thread_time": best / t_engine,
            "numpy_over_engine_per_eval": ns_np / ns_eng, "phases": phases}


# -------------------------------------------------------------------------------------- 4. cold start

COLD_SNIPPET = r"""
import time
t0 = time.perf_counter()
import json
import numpy as np
import sweep
t1 = time.perf_counter()
sc = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, 10),
                 V=np.logspace(-7, -4, 10))
ds = sweep.run_sweep(sc, progress=False)
x = float(ds["xi_inf"].mean())
t2 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "import_to_result_s": t2 - t0, "mean_xi_inf": x}))
"""


def _process(args):
    t0 = time.perf_counter()
    cp = subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=600)
    wall = time.perf_counter() - t0
    if cp.returncode:
        raise RuntimeError(f"subprocess failed: {cp.stderr[-2000:]}")
    return wall, cp.stdout


def bench_cold(runs):
    warm_wall, _ = _process(["-c", COLD_SNIPPET])  # makes sure the JIT cache is on disk
    walls, inner_import, inner_total, import_walls = [], [], [], []
    for _ in range(runs):
        wall, out = _process(["-c", COLD_SNIPPET])
        d = json.loads(out.strip().splitlines()[-1])
        walls.append(wall)
        inner_import.append(d["import_s"])
        inner_total.append(d["import_to_result_s"])
        import_walls.append(_process(["-c", "import sweep"])[0])
    return {"what": "new process: python -c 'import sweep; run_sweep(10 x 10 sample2 scene)', JIT cache on disk",
            "first_process_wall_s": warm_wall,
            "process_wall_s_median": statistics.median(walls), "process_wall_s_all": walls,
            "in_process_import_s_median": statistics.median(inner_import),
            "in_process_import_to_result_s_median": statistics.median(inner_total),
            "import_only_process_wall_s_median": statistics.median(import_walls),
            "import_only_process_wall_s_all": import_walls,
            "python_startup_process_wall_s": statistics.median(_process(["-c", "pass"])[0] for _ in range(3))}


# ---------------------------------------------------------------------------------------- 5. estimate

def bench_estimate(name, scene, repeats, measured=None, n_est=3):
    """estimate_seconds called n_est times (its pilot lasts milliseconds, so it is sensitive to noise):
    the median is compared with the measured time (best of ``repeats``, all threads)."""
    plan = sweep.make_plan(scene)
    ests, walls = [], []
    for _ in range(n_est):
        t0 = time.perf_counter()
        est, pilot_steps = estimate_seconds(scene, plan)
        walls.append(time.perf_counter() - t0)
        ests.append(est)
    if measured is None:
        execute(scene, plan, progress=False)
        measured, _, res = best_of(lambda: execute(scene, plan, progress=False), repeats)
        mean_steps = float(res.steps.mean())
    else:
        measured, mean_steps = measured
    est = statistics.median(ests)
    ratio = est / measured
    return {"scene": name, "points": plan.n_points, "threads": numba.get_num_threads(),
            "estimate_s_median": est, "estimate_s_all": ests, "estimate_call_wall_s_median": statistics.median(walls),
            "pilot_mean_steps": pilot_steps, "measured_s": measured, "grid_mean_steps": mean_steps,
            "estimate_over_measured": ratio, "estimate_over_measured_all": [e / measured for e in ests],
            "within_2x": bool(1 / TARGET_ESTIMATE <= ratio <= TARGET_ESTIMATE)}


# ---------------------------------------------------------------------------------------------- main

def machine_info():
    return {"cpu_model": common.cpu_model(), "logical_cpus": os.cpu_count(),
            "usable_cpus": common.usable_cpus() or os.cpu_count(),
            "numba_threading_layer": common.threading_layer(),
            "NUMBA_NUM_THREADS": numba.config.NUMBA_NUM_THREADS,
            "NUMBA_NUM_THREADS_env": os.environ.get("NUMBA_NUM_THREADS"),
            "platform": platform.platform()}


def fmt(x, f="{:.3g}"):
    return "-" if x is None else f.format(x)


def verdict(ok):
    return "PASS" if ok else "MISS"


def plot(result, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    h = result["engine"]["steps_histogram"]
    edges = np.array(h["edges"], float)
    edges[0] = min(0.9 * edges[1], max(1.0, 0.9 * result["engine"]["steps_per_point"]["p0"]))
    edges[-1] = max(edges[-2] * 2, result["engine"]["steps_per_point"]["p100"] * 1.05)
    ax1.stairs(h["counts"], edges, fill=True)
    ax1.set_xscale("log")
    ax1.set_yscale("log")
    ax1.set_xlabel(f"{result['engine']['method']} steps per point, returned run (default scene, rtol 1e-6)")
    ax1.set_ylabel("points")
    ax1.set_title("engine: steps per point")
    for name, m in result["scipy"]["methods"].items():
        for af in sorted({r["atol_over_rtol"] for r in m["scan"]}):
            fam = [r for r in m["scan"] if r["atol_over_rtol"] == af]
            ax2.loglog([r["max_rel_err"] for r in fam], [r["ms_per_traj"] * 1e3 for r in fam], "o-", ms=3,
                       label=f"{name}, atol = {af:g} rtol")
    e = result["scipy"]["engine_same_points"]
    ax2.loglog([e["max_rel_err"]], [e["us_per_traj"]], "k*", ms=12, label="engine rtol 1e-6 (1 thread)")
    ax2.axvline(ERROR_TARGET, color="gray", ls=":")
    ax2.set_xlabel("max relative xi_inf error on the subsample")
    ax2.set_ylabel("us per trajectory (1 core)")
    ax2.set_title("scipy tolerance scan vs engine")
    ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="1 repeat, 5 x 5 scipy subsample, every other tolerance, no full-grid error check")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--no-png", action="store_true")
    args = ap.parse_args(argv)
    quick = args.quick
    repeats = 1 if quick else 3
    n_all = numba.config.NUMBA_NUM_THREADS
    warnings.simplefilter("ignore", RuntimeWarning)
    t_start = time.perf_counter()
    load0, digest0 = common.loadavg(), common.sweep_digest()

    scene = sweep.default_scene()
    plan = sweep.make_plan(scene)
    print(f"[1/5] engine: default scene {scene.shape[0]} x {scene.shape[1]}, rtol {scene.rtol:g}", flush=True)
    print(f"      plan: {plan.method}, {plan.describe()['stepper']}", flush=True)
    eng, eng_res = bench_engine(scene, plan, repeats, n_all)
    t_eng_1 = eng["threads_1"]["best_s"]

    print("[2/5] scipy DOP853 / LSODA on a strided subsample", flush=True)
    idx = subsample_indices(scene, 5 if quick else 7)
    tail_checked = common.check_tail_ok()
    ref = reference(scene, idx)
    ref_method = sweep.make_plan(dataclasses.replace(scene, rtol=REF_RTOL)).method
    check = closed_form_check(scene)
    tols = [10.0 ** -e for e in (range(3, 14, 2) if quick else range(3, 14))]
    atol_factors = (1.0, 1e-3)
    methods = bench_scipy(scene, plan, idx, ref.xi_inf, tols, atol_factors, repeats)
    eng_sub = bench_engine_subsample(scene, plan, idx, ref.xi_inf, 5 if quick else 20)
    chosen = {k: v["chosen"] for k, v in methods.items() if v["chosen"]}
    best_name = min(chosen, key=lambda k: chosen[k]["ms_per_traj"]) if chosen else None
    scipy_us = chosen[best_name]["ms_per_traj"] * 1e3 if best_name else math.nan
    per_core_all = eng[f"threads_{n_all}"]["us_per_traj_per_core"]
    # unbiased: the chosen tolerances re-timed on a uniformly random subsample of the grid
    idx_r = random_indices(scene, RANDOM_POINTS)
    ref_r = reference(scene, idx_r)
    rand = bench_scipy_at_chosen(scene, plan, idx_r, ref_r.xi_inf, methods, repeats)
    eng_sub_r = bench_engine_subsample(scene, plan, idx_r, ref_r.xi_inf, 5 if quick else 20)
    chosen_r = {k: v for k, v in rand.items() if v}
    best_r = min(chosen_r, key=lambda k: chosen_r[k]["ms_per_traj"]) if chosen_r else None
    scipy_us_r = chosen_r[best_r]["ms_per_traj"] * 1e3 if best_r else math.nan

    def ratios(scipy_us_per_traj, engine_same_points):
        """scipy cost per trajectory over the engine's: on the same points, and against the grid averages."""
        return {"ratio_same_points_1_core": scipy_us_per_traj / engine_same_points["us_per_traj"],
                "ratio_vs_grid_per_core_all_threads": scipy_us_per_traj / per_core_all,
                "ratio_vs_grid_1_thread": scipy_us_per_traj / (t_eng_1 / plan.n_points * 1e6)}

    scipy_out = {
        "subsample": {"points": int(idx.size), "flat_indices": idx.tolist(),
                      "includes_costliest_grid_point": bool(int(np.argmax(eng_res.steps)) in set(idx.tolist())),
                      "engine_mean_steps_subsample": eng_sub["mean_steps"],
                      "engine_mean_steps_grid": eng["steps_per_point"]["mean"]},
        "formulation": "dxi/ds = exp(-(chi xi + mu1 u + m2 u^2)/A), u = s - xi, xi(0) = 0 (reduced); stepped "
                       "with the scipy OdeSolver class (what solve_ivp drives) until sweep.integrate.models.stop."
                       "tail_is_accurate(k, a, b, u, E, rtol_scene*xi + atol) passes at a step end (a plain-"
                       "Python copy, checked equal on random inputs, to avoid ~1.7 us numba dispatch per step), "
                       "then + tail_slip: the engine's own stopping rule and tail. LSODA gets the analytic "
                       "Jacobian. Timing excludes nothing: Python RHS, stepping, tail test.",
        "tail_test_copy_checked_inputs": tail_checked,
        "error_target": ERROR_TARGET,
        "reference": f"engine at rtol {REF_RTOL:g} on the same points",
        "reference_method": ref_method,
        "reference_closed_form_check_m2_0": check,
        "tolerance_rule": "per atol family (atol = rtol or 1e-3 rtol) the loosest scanned rtol from which every "
                          "tighter scanned rtol also has max rel error <= target; then the faster family",
        "methods": methods,
        "engine_same_points": eng_sub,
        "best_method": best_name,
        "best_us_per_traj": scipy_us,
        **ratios(scipy_us, eng_sub),
        "note_strided_ratios": "ratio_vs_grid_* divide scipy's mean on the strided, corner-heavy subsample "
                              "(biased high) by the engine's grid mean; see random_subsample for the unbiased one",
        "random_subsample": {
            "what": "each method at the tolerance chosen on the strided subsample, re-timed (best of repeats) on "
                    "points drawn uniformly without replacement from the grid: unbiased estimate of scipy's "
                    "mean cost per trajectory over the grid",
            "points": int(idx_r.size), "seed": RANDOM_SEED, "flat_indices": idx_r.tolist(),
            "engine_mean_steps_subsample": eng_sub_r["mean_steps"],
            "engine_mean_steps_grid": eng["steps_per_point"]["mean"],
            "reference": f"engine at rtol {REF_RTOL:g} on the same points",
            "methods": rand,
            "engine_same_points": eng_sub_r,
            "best_method": best_r,
            "best_us_per_traj": scipy_us_r,
            **ratios(scipy_us_r, eng_sub_r),
        },
    }
    if not quick:
        full_ref = reference(scene, np.arange(plan.n_points))
        rel = np.abs(eng_res.xi_inf / full_ref.xi_inf - 1)
        eng["error_vs_rtol_1e-10_full_grid"] = {"max_rel_err": float(rel.max()), "median_rel_err": float(
            np.median(rel)), "p99_rel_err": float(np.percentile(rel, 99))}

    print("[3/5] numpy lockstep RK4 vs the engine at a fixed step (runs 4h, 2h, h per point)", flush=True)
    npy = bench_numpy(scene, plan, 1 if quick else 2)

    print("[4/5] cold start (new processes)", flush=True)
    cold = bench_cold(1 if quick else 3)

    print("[5/5] dry-run estimate vs measured", flush=True)
    numba.set_num_threads(n_all)
    est = [bench_estimate("default (sample2, 200 x 100)", scene, repeats,
                          measured=(eng[f"threads_{n_all}"]["best_s"], eng["steps_per_point"]["mean"]))]
    sc1 = sweep.Scene(protocol="stop", params=sweep.presets["sample1"], K_over_M=np.logspace(3, 6, 100),
                      V=np.logspace(-7, -4, 100))
    est.append(bench_estimate("sample1, 100 x 100", sc1, repeats))

    targets = {
        "scipy_ratio_same_points_1_core": {"value": scipy_out["ratio_same_points_1_core"], "target": ">= 50",
                                           "result": verdict(scipy_out["ratio_same_points_1_core"] >= TARGET_RATIO)},
        "scipy_ratio_grid_strided_corner_subsample_per_core": {
            "value": scipy_out["ratio_vs_grid_per_core_all_threads"], "target": ">= 50",
            "result": verdict(scipy_out["ratio_vs_grid_per_core_all_threads"] >= TARGET_RATIO)},
        "scipy_ratio_grid_random_subsample_per_core": {
            "value": scipy_out["random_subsample"]["ratio_vs_grid_per_core_all_threads"], "target": ">= 50",
            "result": verdict(scipy_out["random_subsample"]["ratio_vs_grid_per_core_all_threads"] >= TARGET_RATIO)},
        "cold_start_s": {"value": cold["process_wall_s_median"], "target": "< 2 s",
                         "result": verdict(cold["process_wall_s_median"] < TARGET_COLD_S)},
    }
    if "skipped" not in npy:
        targets["numpy_over_engine_per_rk4_stage_eval"] = {
            "value": npy["numpy_over_engine_per_eval"], "target": ">= 3",
            "result": verdict(npy["numpy_over_engine_per_eval"] >= TARGET_NUMPY_PER_EVAL)}
    for e in est:
        targets[f"estimate_ratio[{e['scene']}]"] = {"value": e["estimate_over_measured"], "target": "0.5..2",
                                                    "result": verdict(e["within_2x"])}
    result = {
        "benchmark": "benchmarks/throughput.py" + (" --quick" if quick else ""),
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "machine": machine_info(),
        "versions": {**common.versions(), "sweep_git_commit": common.git_commit(),
                     "sweep_tree_dirty": common.sweep_tree_dirty()},
        "sweep_source_digest_start_end": [digest0, common.sweep_digest()],
        "loadavg_start_end": [load0, common.loadavg()],
        "scene": {"name": "sweep.default_scene()", "shape": list(scene.shape), "rtol": scene.rtol,
                  "plan": plan.describe(),
                  "atol_xi_inf": scene.atol["xi_inf"], "plan_step_sigma": {
                      "stable_sliding_k_gt_a": sorted({float(x) for x in plan.step[plan.k > plan.a]}),
                      "unstable_k_le_a": sorted({float(x) for x in plan.step[plan.k <= plan.a]}),
                      "points_stable": int(np.count_nonzero(plan.k > plan.a))},
                  "plan_step_is": ("pilot step h0 of each point's step ladder (runs 2 h0, h0, then finer)"
                                   if plan.lanes else f"step ({plan.step_source})"), "preset": "sample2"},
        "engine": eng,
        "scipy": scipy_out,
        "numpy_rk4": npy,
        "cold_start": cold,
        "estimate": est,
        "targets": targets,
        "benchmark_wall_s": None,
    }
    common.write_result(result, args.out, t_start, None if args.no_png else plot, print_table)


def print_scipy_rows(chosen, engine, rtol, missing):
    """One row per scipy method at its chosen tolerance, then the engine on the same points."""
    print(f"{'':24s}{'rtol':>8s}{'atol':>8s}{'max err':>10s}{'us/traj':>10s}{'nfev':>8s}{'us/eval':>9s}")
    for name, ch in chosen.items():
        if ch is None:
            print(f"{name:24s}  {missing}")
            continue
        print(f"{name:24s}{ch['rtol']:8.0e}{ch['atol']:8.0e}{ch['max_rel_err']:10.1e}{ch['ms_per_traj'] * 1e3:10.0f}"
              f"{ch['mean_nfev']:8.0f}{ch['us_per_rhs_eval']:9.2f}")
    print(f"{'engine (1 thread)':24s}{rtol:8.0e}{'':8s}{engine['max_rel_err']:10.1e}{engine['us_per_traj']:10.1f}"
          f"{engine['mean_rhs_evals']:8.0f}{engine['us_per_traj'] / engine['mean_rhs_evals']:9.3f}")


def print_table(r):
    m, e, s, npy, c = r["machine"], r["engine"], r["scipy"], r["numpy_rk4"], r["cold_start"]
    n_all = m["NUMBA_NUM_THREADS"]
    print(f"\n== sweep throughput  {r['date']}  {m['cpu_model']}, {m['logical_cpus']} cpus, numba "
          f"{r['versions']['numba']} ({m['numba_threading_layer']}, {n_all} threads)")
    sp, lad = e["steps_per_point"], e["ladder"]
    print(f"plan: {r['scene']['plan']['method']}; {r['scene']['plan']['stepper']}")
    print(f"default scene {r['scene']['shape'][0]}x{r['scene']['shape'][1]} rtol {r['scene']['rtol']:g}: steps/point "
          f"mean {sp['mean']:.0f}, median {sp['p50']:.0f}, p95 {sp['p95']:.0f}, max {sp['p100']:.0f}; "
          f"{100 * e['share_of_steps_in_points_over_1000_steps']:.0f}% of all steps in the "
          f"{e['points_over_1000_steps']} points with > 1000 steps (returned run; all runs of the step ladders "
          f"take {lad['all_runs_over_returned']:.3f}x those steps, counted in ns/step below)")
    if len(e["by_method"]) > 1:
        print("points by method: " + ", ".join(f"{m} {v['points']} ({v['all_runs_steps_total']} steps, all runs)"
                                               for m, v in e["by_method"].items()))
    hs = r["scene"]["plan_step_sigma"]
    print(f"plan step in sigma per point ({r['scene']['plan_step_is']}): "
          f"{', '.join(f'{x:.4g}' for x in hs['stable_sliding_k_gt_a'])} on the "
          f"{hs['points_stable']} stable-sliding points (k > a), "
          f"{', '.join(f'{x:.4g}' for x in hs['unstable_k_le_a'])} on the others")
    rows = [("engine 1 thread", e["threads_1"]["best_s"], e["threads_1"]["traj_per_s"],
             e["threads_1"]["traj_per_s_per_core"], e["threads_1"]["ns_per_step_per_core"],
             e["threads_1"]["ns_per_stage_eval_per_core"])]
    if n_all > 1:
        t = e[f"threads_{n_all}"]
        rows.append((f"engine {n_all} threads", t["best_s"], t["traj_per_s"], t["traj_per_s_per_core"],
                     t["ns_per_step_per_core"], t["ns_per_stage_eval_per_core"]))
    if "skipped" not in npy:
        label = f"numpy lockstep {npy['method']}" + (f" ({npy['points']} pts)" if npy["points_other_methods"] else "")
        rows.append((label, npy["best_s"], npy["traj_per_s"], npy["traj_per_s"],
                     npy["evals_per_step"] * npy["ns_per_point_stage_eval"], npy["ns_per_point_stage_eval"]))
    print(f"\n{'':32s}{'seconds':>10s}{'traj/s':>12s}{'traj/s/core':>13s}{'ns/step/core':>14s}{'ns/eval/core':>14s}")
    for name, sec, tps, tpc, ns, nse in rows:
        print(f"{name:32s}{sec:10.3f}{tps:12.0f}{tpc:13.0f}{ns:14.1f}{nse:14.2f}")
    print(f"sweep.run_sweep (plan + kernel + Dataset), {n_all} threads: {e['run_sweep_s_all_threads']:.3f} s")
    if n_all > 1:
        print(f"parallel speedup {e['parallel_speedup']:.2f}x on {n_all} threads (execute)")
    if "error_vs_rtol_1e-10_full_grid" in e:
        print(f"engine rtol 1e-6 vs rtol 1e-10, full grid: max rel err "
              f"{e['error_vs_rtol_1e-10_full_grid']['max_rel_err']:.2e}")
    print(f"\nscipy on {s['subsample']['points']} strided points, corners included (engine mean steps there "
          f"{s['subsample']['engine_mean_steps_subsample']:.0f} vs {s['subsample']['engine_mean_steps_grid']:.0f} "
          f"on the grid); reference check vs m2=0 closed form: max rel err "
          f"{s['reference_closed_form_check_m2_0']['max_rel_err']:.1e}")
    print_scipy_rows({name: mm["chosen"] for name, mm in s["methods"].items()}, s["engine_same_points"],
                     r["scene"]["rtol"], f"no scanned tolerance met {ERROR_TARGET:g}")
    rs = s["random_subsample"]
    print(f"\nscipy at the chosen tolerances on {rs['points']} uniformly random points (seed {rs['seed']}; "
          f"engine mean steps there {rs['engine_mean_steps_subsample']:.0f} vs "
          f"{rs['engine_mean_steps_grid']:.0f} on the grid)")
    print_scipy_rows(rs["methods"], rs["engine_same_points"], r["scene"]["rtol"], "no tolerance chosen")
    per_core = e[f"threads_{n_all}"]["us_per_traj_per_core"]
    print(f"best scipy us/traj: strided {s['best_us_per_traj']:.0f} ({s['best_method']}), random "
          f"{rs['best_us_per_traj']:.0f} ({rs['best_method']}); engine per core over the grid ({n_all} threads) "
          f"{per_core:.2f}; same-points ratio on the random subsample {rs['ratio_same_points_1_core']:.1f}")
    if "skipped" in npy:
        print(f"\nnumpy lockstep: skipped ({npy['skipped']})")
    else:
        ph = npy["phases"]
        print(f"\nnumpy lockstep vs engine, {npy['method']} at the fixed step h = {npy['step_h_sigma']:.4g} "
              f"(runs 4h, 2h, h per point, 1 core each): {npy['returned_run_steps_differ_points']} points with "
              f"different step counts at h ({npy['all_runs_steps_differ_points']} over all runs), rel xi_inf diff max "
              f"{npy['max_rel_diff_vs_engine']:.1e}, median {npy['median_rel_diff_vs_engine']:.1e} "
              f"({npy['compared_points']} points), statuses equal: {npy['status_equal']}; per point-stage evaluation "
              f"{npy['ns_per_point_stage_eval']:.1f} ns vs engine {npy['engine_ns_per_point_stage_eval_1_thread']:.2f} "
              f"ns (x{npy['numpy_over_engine_per_eval']:.1f}); with >= 4096 runs active numpy costs "
              f"{fmt(ph['active_ge_4096']['ns_per_point_stage_eval'], '{:.1f}')} ns, below "
              f"{fmt(ph['active_lt_4096']['ns_per_point_stage_eval'], '{:.1f}')} ns")
    print(f"cold start (10x10 sweep in a new process): median {c['process_wall_s_median']:.2f} s "
          f"(import sweep alone {c['import_only_process_wall_s_median']:.2f} s as a process, "
          f"{c['in_process_import_s_median']:.2f} s in-process; bare python "
          f"{c['python_startup_process_wall_s']:.2f} s)")
    for x in r["estimate"]:
        print(f"estimate {x['scene']}: {x['estimate_s_median']:.3f} s (median of "
              f"{len(x['estimate_s_all'])}; ratios " + ", ".join(f"{v:.2f}" for v in x["estimate_over_measured_all"])
              + f") vs measured {x['measured_s']:.3f} s (x{x['estimate_over_measured']:.2f})")
    print("\ntargets:")
    for name, t in r["targets"].items():
        print(f"  {t['result']}  {name:52s} {t['value']:8.2f}  (target {t['target']})")


if __name__ == "__main__":
    main()
