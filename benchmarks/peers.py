#!/usr/bin/env python
"""The engine side by side with the tools a user would pick instead (issue 17): numbalsoda, diffrax, scipy.

    python benchmarks/peers.py [--quick] [--out benchmarks/results/peers.json] [--no-png]
    python benchmarks/peers.py --driven [--quick] [--models quasistatic,auto] [--out ...]   (the driven scene:
                                                                  benchmarks/_peers_driven.py, issue 35)

Every tool solves the SAME points of the default scene (sweep.default_scene() with model="quasistatic":
sample2, K/M 1e3..1e6 s^-2 (200) x V 0.1..100 um/s (100)) and of its costly corner (chi/A <= 0.1 and mu1 < 0, a
rectangular sub-grid of it), at rtol 1e-3 .. 1e-10, in one process, one after the other:

* engine, run_sweep   sweep.run_sweep (plan + kernels + Dataset: what a user calls), wall time, with
                      numba.set_num_threads(1) and with all threads; the whole grid.
* engine, execute     the kernel path (sweep.make_plan + sweep.protocols.stop.chunk.execute, as
benchmarks/throughput.py uses
                      it), 1 thread and all threads, the whole grid; 1 thread on the subsample as well.
* numbalsoda          LSODA (numbalsoda.lsoda) called from an @njit(parallel=True) prange loop over points, 1
                      thread and all threads; the whole grid and the subsample.
* diffrax             Tsit5 + PIDController under jax.jit(jax.vmap(...)), CPU, float64 (jax_enable_x64), XLA
                      held to one thread (XLA_FLAGS set before jax is imported); the whole grid and the subsample.
* scipy               the OdeSolver classes LSODA (analytic Jacobian) and DOP853, what solve_ivp drives, in a
                      Python loop over points (benchmarks/_common.py's scipy_point); the subsample only.

Every peer gets the engine's own formulation, as benchmarks/throughput.py gives it to scipy: the 1-D ODE
dxi/ds = E = exp(-(chi xi + mu1 u + m2 u^2)/A), u = s - xi, xi(0) = 0, in contact-age time s (reduced:
k = chi/A, a = mu1/A, b = m2/A from the engine's plan), stopped once the engine's tail test
(sweep.integrate.models.stop.tail_is_accurate, tolerance rtol xi + atol_scene) passes, then the engine's closed-form
tail
(sweep.integrate.models.stop.tail_slip) added. So the comparison is of the integrators, not of the formulation. Each
peer runs at atol = ATOL_OVER_RTOL x rtol. Where the tail test is checked: scipy and diffrax at every step end
(diffrax: a diffrax.Event); numbalsoda, whose lsoda returns the solution at given output times only, at
geometric output times (OUT_PER_SEGMENT per segment, segments [s_c, 32], then x32 each; LSODA interpolates to
them without shortening its steps), one lsoda call per segment until the test passes.

Timings exclude JIT compilation for every tool: each (tool, points, rtol) is called once untimed first (numba's
compile or on-disk cache load, jax's trace and XLA compile, the engine's kernels), then best of REPEATS calls
(scipy: one timed call after a 2-point warm-up; it has no JIT), and the whole sweep of tools and tolerances is made
PASSES times over, each (tool, points, rtol) keeping its best pass: a slow spell of the (shared, virtual) machine
then weighs on no tool's block alone (2026-11-27: the engine's 1e-3 run_sweep took 1.05 and 1.40 us a point in two
runs of one hour, its peers' times moved alike). Per core = wall x threads / trajectories.
Errors: max relative xi_inf error against the engine at rtol 1e-10 with REF_CTRL_FACTOR times a run's lane control
tolerance, on the same points, that reference checked against scipy's DOP853 at rtol 1e-13 on a few points (its
max difference is the floor below which errors are not resolved). The peers also run at PEER_EXTRA_TOLS (1e-11,
1e-12: they need ~100x the engine's tolerance for the same max error), so that every error level to 1e-10 has a
peer where one reaches it.

Writes benchmarks/results/peers.json and peers.png (time per trajectory per core vs max error, log-log, one
curve per tool); prints a table. A peer that is not installed is recorded as "not installed" (peers_status, and
tools_missing with the reason) and skipped; --quick runs with whatever is installed.
Install the peers with `pip install -e .[bench]` (numbalsoda builds from source: gfortran and cmake; see
benchmarks/README.md).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as _dt
import importlib.metadata
import math
import os
import sys
import time
import warnings
from pathlib import Path

import _common as common
import numba
import numpy as np
from numba import njit, prange

import sweep
from sweep.integrate.models.stop import EXP_MAX, tail_is_accurate, tail_slip
from sweep.protocols.stop.chunk import execute

HERE = Path(__file__).resolve().parent
DEFAULT_OUT = HERE / "results" / "peers.json"

TOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
TOLS_QUICK = (1e-3, 1e-6, 1e-9)
ERROR_LEVELS = tuple(10.0 ** -e for e in range(3, 11))
REF_RTOL = 1e-10
REF_CTRL_FACTOR = 0.01  # the reference's lane control tolerance, relative to a run's at REF_RTOL
PEER_EXTRA_TOLS = (1e-11, 1e-12)  # the peers only (the engine's rtol stops at 1e-10): their cost at 1e-9..1e-10 error
CHECK_RTOL = 1e-13  # scipy DOP853 cross-check of the reference
CHECK_ATOL = 1e-16
ATOL_OVER_RTOL = 1e-3
SEED = 20261125
N_SUB, N_SUB_QUICK = 256, 12
N_SUB_CORNER, N_SUB_CORNER_QUICK = 128, 8
N_CHECK, N_CHECK_QUICK = 8, 2
REPEATS, REPEATS_QUICK = 3, 1
PASSES = 2
CORNER_K_MAX = 0.1  # chi/A
OUT_PER_SEGMENT = 32
S_FIRST = 32.0
SEGMENT_RATIO = 32.0
MAX_SEGMENTS = 16
LSODA_MXSTEP = 1_000_000
DIFFRAX_MAX_STEPS = 1_000_000
DIFFRAX_PID = (0.0, 1.0, 0.0)  # diffrax.PIDController's own defaults (pcoeff, icoeff, dcoeff)
XLA_ONE_THREAD = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
JIT_NOTE = ("JIT compile time excluded for every tool: each (tool, points, rtol) is called once untimed first "
            "(numba compile or cache load, jax trace + XLA compile, the engine's kernels), then timed")


def version_of(dist):
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return None


# ------------------------------------------------------------------------------------------- point sets

def quasistatic_default():
    return dataclasses.replace(sweep.default_scene(), model="quasistatic")


def quick_scene(scene):
    """A coarse version of the scene (every 10th K/M and V): tiny sizes for --quick."""
    return dataclasses.replace(scene, K_over_M=scene.K_over_M[::10], V=scene.V[::10])


def corner_scene(scene):
    """The costly corner of a scene: the rectangular sub-grid with chi/A <= CORNER_K_MAX and mu1 < 0 (chi/A
    depends on K/M only, mu1 on V only)."""
    plan = sweep.make_plan(scene)
    nk, nv = scene.shape
    k = plan.k.reshape(nk, nv)[:, 0]
    a = plan.a.reshape(nk, nv)[0, :]
    ik, iv = np.flatnonzero(k <= CORNER_K_MAX), np.flatnonzero(a < 0)
    if ik.size == 0 or iv.size == 0:
        return None
    return dataclasses.replace(scene, K_over_M=scene.K_over_M[ik], V=scene.V[iv])


def subsample(n_points, n, seed):
    """Sorted flat indices of n points drawn uniformly without replacement (numpy default_rng(seed))."""
    return np.sort(np.random.default_rng(seed).choice(n_points, size=min(n, n_points), replace=False))


# ---------------------------------------------------------------------------------------------- tools
# A tool: name, label, threads, scopes it runs on ("grid", "sub"), and solve(scene, plan, idx, rtol) ->
# (xi_inf, mean RHS evaluations or None, mean steps or None). idx None = the whole grid.

class Tool:
    def __init__(self, name, label, threads, scopes, solve, family, note=""):
        self.name, self.label, self.threads, self.scopes = name, label, threads, scopes
        self.solve, self.family, self.note = solve, family, note


def with_threads(n, fn):
    def run(*args):
        old = numba.get_num_threads()
        numba.set_num_threads(n)
        try:
            return fn(*args)
        finally:
            numba.set_num_threads(old)
    return run


def engine_tools(n_all):
    def run_sweep(scene, plan, idx, rtol):
        ds = sweep.run_sweep(dataclasses.replace(scene, rtol=rtol), progress=False)
        return ds["xi_inf"].values.ravel(), None, float(ds["steps"].values.mean())

    plans = {}

    def kernel(scene, plan, idx, rtol):
        sc = dataclasses.replace(scene, rtol=rtol)
        key = (id(scene), rtol)
        if key not in plans:  # the plan is made once per scene and rtol, outside the timing (as throughput.py)
            plans.clear()
            plans[key] = sweep.make_plan(sc)
        res = execute(sc, plans[key], idx, progress=False)
        return res.xi_inf, None, float(res.work.mean())

    threads = sorted({1, n_all})
    tools = []
    for nt in threads:
        tools.append(Tool(f"engine_run_sweep_{nt}t", f"engine run_sweep, {nt} thread{'s' * (nt > 1)}", nt,
                          ("grid",), with_threads(nt, run_sweep), "engine"))
    for nt in threads:
        tools.append(Tool(f"engine_execute_{nt}t", f"engine execute (kernel path), {nt} thread{'s' * (nt > 1)}",
                          nt, ("grid", "sub") if nt == 1 else ("grid",), with_threads(nt, kernel), "engine",
                          "mean_steps = all runs of every point's step ladder (RawResult.work)"))
    return tools


def numbalsoda_tools(n_all):
    """numbalsoda's LSODA from an njit prange loop, or a reason why not."""
    try:
        import numbalsoda
        from numba import carray, cfunc
    except Exception as exc:  # ImportError, or a broken build (missing shared library)
        return None, f"not installed ({type(exc).__name__}: {exc})"

    @cfunc(numbalsoda.lsoda_sig)
    def rhs(s, y, dy, p):
        d = carray(p, (4,))  # k, a, b, evaluation counter
        xi = y[0]
        u = s - xi
        dy[0] = math.exp(min(-(d[0] * xi + u * (d[1] + d[2] * u)), EXP_MAX))
        d[3] += 1.0

    ptr = rhs.address
    lsoda = numbalsoda.lsoda

    @njit
    def point(k, a, b, s_c, rtol, atol, tail_rel, tail_abs):
        data = np.array([k, a, b, 0.0])
        y0 = np.zeros(1)
        t = np.empty(OUT_PER_SEGMENT + 1)
        s0, lo, hi = 0.0, math.log(s_c), math.log(S_FIRST)
        for _ in range(MAX_SEGMENTS):
            t[0] = s0
            for j in range(OUT_PER_SEGMENT):
                t[j + 1] = math.exp(lo + (hi - lo) * (j + 1.0) / OUT_PER_SEGMENT)
            y, ok = lsoda(ptr, y0, t, data=data, rtol=rtol, atol=atol, mxstep=LSODA_MXSTEP)
            if not ok:
                return math.nan, data[3]
            for j in range(1, OUT_PER_SEGMENT + 1):
                xi = y[j, 0]
                u = t[j] - xi
                E = math.exp(min(-(k * xi + u * (a + b * u)), EXP_MAX))
                if tail_is_accurate(k, a, b, u, E, tail_rel * xi + tail_abs):
                    return xi + tail_slip(k, a, b, u, E), data[3]
            y0[0] = y[OUT_PER_SEGMENT, 0]
            s0 = t[OUT_PER_SEGMENT]
            lo, hi = hi, hi + math.log(SEGMENT_RATIO)
        return math.nan, data[3]

    @njit(parallel=True)
    def batch(k, a, b, s_c, rtol, atol, tail_rel, tail_abs):
        n = k.size
        xi_inf = np.empty(n)
        nfev = np.empty(n)
        for i in prange(n):
            xi_inf[i], nfev[i] = point(k[i], a[i], b[i], s_c[i], rtol, atol, tail_rel, tail_abs)
        return xi_inf, nfev

    def solve(scene, plan, idx, rtol):
        sel = slice(None) if idx is None else idx
        xi, nfev = batch(plan.k[sel], plan.a[sel], plan.b[sel], plan.s_c[sel], rtol, ATOL_OVER_RTOL * rtol,
                         rtol, scene.atol["xi_inf"])
        return xi, float(nfev.mean()), None

    note = ("LSODA without a Jacobian (numbalsoda's lsoda takes none: finite differences, counted in nfev); tail "
            f"test at {OUT_PER_SEGMENT} geometric output times per segment")
    tools = [Tool(f"numbalsoda_{nt}t", f"numbalsoda LSODA, njit prange, {nt} thread{'s' * (nt > 1)}", nt,
                  ("grid", "sub") if nt == 1 else ("grid",), with_threads(nt, solve), "numbalsoda", note)
             for nt in sorted({1, n_all})]
    return tools, None


def diffrax_tools(pid):
    """diffrax Tsit5 + PIDController under jax.vmap (CPU, float64, one XLA thread), or a reason why not."""
    if "jax" not in sys.modules:  # one XLA thread: per-core figures; must precede the first import of jax
        os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + XLA_ONE_THREAD).strip()
    try:
        import jax
        import jax.numpy as jnp
        jax.config.update("jax_enable_x64", True)
        jax.config.update("jax_platforms", "cpu")
        import diffrax
    except Exception as exc:
        return None, f"not installed ({type(exc).__name__}: {exc})"
    from sweep.integrate.models.stop import E_TAIL_MAX, TAIL_SAFETY

    def rhs(s, xi, args):
        k, a, b = args[:3]
        u = s - xi
        return jnp.exp(jnp.minimum(-(k * xi + u * (a + b * u)), EXP_MAX))

    def tail_ok(t, xi, args, **kwargs):  # sweep.integrate.models.stop.tail_is_accurate, elementwise in jax
        k, a, b, tail_rel, tail_abs = args
        u = t - xi
        E = jnp.exp(jnp.minimum(-(k * xi + u * (a + b * u)), EXP_MAX))
        g = a + 2.0 * b * u
        gs = jnp.where(g > 0.0, g, 1.0)
        err = E * E * E * (1.0 / (3.0 * gs) + k / (2.0 * gs * gs))
        return (g > 0.0) & (E <= E_TAIL_MAX) & (err <= TAIL_SAFETY * (tail_rel * xi + tail_abs))

    pcoeff, icoeff, dcoeff = pid

    def one(k, a, b, rtol, atol, tail_rel, tail_abs):
        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rhs), diffrax.Tsit5(), 0.0, 1e12, None, jnp.asarray(0.0),
            args=(k, a, b, tail_rel, tail_abs), saveat=diffrax.SaveAt(t1=True),
            stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol, pcoeff=pcoeff, icoeff=icoeff,
                                                      dcoeff=dcoeff),
            event=diffrax.Event(tail_ok), max_steps=DIFFRAX_MAX_STEPS, throw=False)
        ok = sol.event_mask  # the tail test passed (not: max_steps reached, or a failed step)
        return sol.ts[-1], sol.ys[-1], sol.stats["num_steps"], ok

    solve_all = jax.jit(jax.vmap(one, in_axes=(0, 0, 0, None, None, None, None)))

    @njit
    def add_tail(k, a, b, s, xi, ok):
        out = np.empty(k.size)
        for i in range(k.size):
            u = s[i] - xi[i]
            E = math.exp(min(-(k[i] * xi[i] + u * (a[i] + b[i] * u)), EXP_MAX))
            out[i] = xi[i] + tail_slip(k[i], a[i], b[i], u, E) if ok[i] else math.nan
        return out

    def solve(scene, plan, idx, rtol):
        sel = slice(None) if idx is None else idx
        k, a, b = plan.k[sel], plan.a[sel], plan.b[sel]
        s, xi, steps, ok = (np.asarray(x) for x in jax.block_until_ready(
            solve_all(jnp.asarray(k), jnp.asarray(a), jnp.asarray(b), rtol, ATOL_OVER_RTOL * rtol, rtol,
                      scene.atol["xi_inf"])))
        # Tsit5 is FSAL: 6 new evaluations per step (+1 at the start)
        return add_tail(k, a, b, s, xi, ok), float(6 * steps.mean() + 1), float(steps.mean())

    note = (f"Tsit5 + PIDController(pcoeff={pcoeff:g}, icoeff={icoeff:g}, dcoeff={dcoeff:g}); all points of a call "
            "in one jax.vmap (the costliest lane sets the loop count); tail test as a diffrax.Event at step ends; "
            "closed-form tail added by an njit loop (timed); XLA_FLAGS=" + os.environ.get("XLA_FLAGS", ""))
    return [Tool("diffrax_1t", "diffrax Tsit5 + PID, jax.vmap, CPU f64, 1 thread", 1, ("grid", "sub"), solve,
                 "diffrax", note)], None


def scipy_tools():
    try:
        from scipy.integrate import DOP853, LSODA
    except Exception as exc:
        return None, f"not installed ({type(exc).__name__}: {exc})"

    def make(cls):
        def solve(scene, plan, idx, rtol):
            out = [common.scipy_point(cls, plan.k[i], plan.a[i], plan.b[i], rtol, ATOL_OVER_RTOL * rtol, rtol,
                                      scene.atol["xi_inf"]) for i in idx]
            return (np.array([o[0] for o in out]), float(np.mean([o[2] for o in out])),
                    float(np.mean([o[1] for o in out])))
        return solve

    return [Tool(f"scipy_{c.__name__}", f"scipy {c.__name__} (OdeSolver loop), 1 thread", 1, ("sub",), make(c),
                 "scipy", "LSODA with the analytic Jacobian" if c is LSODA else "")
            for c in (LSODA, DOP853)], None


# --------------------------------------------------------------------------------------------- timing

def rel_err(xi, ref):
    rel = np.abs(xi / ref - 1.0)
    bad = ~np.isfinite(rel)
    return rel, int(bad.sum())


def time_tool(tool, scene, plan, idx, rtol, repeats, ref, sub_pos):
    """One (tool, points, rtol): untimed warm-up call (JIT excluded), then best of ``repeats`` (scipy: 1 timed
    call after a 2-point warm-up). ``sub_pos``: positions of the subsample within the points (grid scope)."""
    n = plan.n_points if idx is None else idx.size
    if tool.family == "scipy":
        tool.solve(scene, plan, idx[:2], rtol)
        repeats = 1
    else:
        tool.solve(scene, plan, idx, rtol)
    load0 = common.loadavg()
    cpu, wall, (xi, nfev, steps) = common.timings(lambda: tool.solve(scene, plan, idx, rtol), repeats)
    load1 = common.loadavg()
    best = min(wall)
    rel, failed = rel_err(np.asarray(xi, float), ref)
    row = {"rtol": rtol, "atol": ATOL_OVER_RTOL * rtol if tool.family != "engine" else scene.atol["xi_inf"],
           "points": int(n), "best_wall_s": best, "all_wall_s": wall, "best_cpu_s": min(cpu),
           "us_per_traj": best / n * 1e6, "us_per_traj_per_core": best * tool.threads / n * 1e6,
           "traj_per_s_per_core": n / (best * tool.threads),
           "max_rel_err": float(np.nanmax(rel)) if failed < n else None,
           "median_rel_err": float(np.nanmedian(rel)) if failed < n else None,
           "failed_points": failed, "mean_rhs_evals": nfev, "mean_steps": steps,
           "loadavg_before": load0, "loadavg_after": load1}
    if sub_pos is not None:
        r = rel[sub_pos]
        row["max_rel_err_on_subsample"] = float(np.nanmax(r)) if np.isfinite(r).any() else None
    return row


def reference(scene, plan, sub, n_check):
    """The engine at rtol 1e-10 with its lanes' control tolerance REF_CTRL_FACTOR times that of a run at 1e-10, on
    the whole grid (all threads), checked against scipy's DOP853 at rtol 1e-13 on n_check points of the subsample
    (the costliest one for the engine among them). Tighter than any timed run, so that the engine's own 1e-10 row
    has a measured error too."""
    from scipy.integrate import DOP853
    sc = dataclasses.replace(scene, rtol=REF_RTOL)
    ref_plan = sweep.make_plan(sc)
    ref_plan = dataclasses.replace(ref_plan, ctrl_tol=ref_plan.ctrl_tol * REF_CTRL_FACTOR)
    t0 = time.perf_counter()
    res = execute(sc, ref_plan, progress=False)
    ref_s = time.perf_counter() - t0
    costly = sub[int(np.argmax(res.work[sub]))]
    others = np.random.default_rng(SEED + 1).choice(sub[sub != costly], size=min(n_check - 1, sub.size - 1),
                                                    replace=False)
    chk = np.sort(np.concatenate(([costly], others)))
    t0 = time.perf_counter()
    dop = np.array([common.scipy_point(DOP853, plan.k[i], plan.a[i], plan.b[i], CHECK_RTOL, CHECK_ATOL,
                                       CHECK_RTOL, CHECK_ATOL)[0] for i in chk])
    rel = np.abs(res.xi_inf[chk] / dop - 1)
    return res.xi_inf, {
        "what": f"engine at rtol {REF_RTOL:g}, lane control tolerance {ref_plan.ctrl_tol:.1e} ({REF_CTRL_FACTOR:g} x "
                f"a run's at that rtol), on every point (execute, all threads); checked against scipy DOP853 "
                f"at rtol {CHECK_RTOL:g}, atol {CHECK_ATOL:g}, tail tolerance {CHECK_RTOL:g} xi + {CHECK_ATOL:g}",
        "status_counts": {sweep.Status(int(c)).name: int(m) for c, m in zip(*np.unique(res.status,
                                                                                      return_counts=True))},
        "engine_s": ref_s, "check_flat_indices": chk.tolist(), "check_xi_engine": res.xi_inf[chk].tolist(),
        "check_xi_dop853": dop.tolist(), "check_rel_diff": rel.tolist(), "check_max_rel_diff": float(rel.max()),
        "check_s": time.perf_counter() - t0,
        "max_estimate_rel": float(np.nanmax(res.xi_inf_err / np.abs(res.xi_inf))),
        "error_floor": float(max(rel.max(), 1e-15)),
        "note": "errors below error_floor are not resolved by the reference"}


def matched(rows, level, key="max_rel_err"):
    """The cheapest scanned setting whose max error is <= level, or None."""
    ok = [r for r in rows if r.get(key) is not None and r[key] <= level and not r["failed_points"]]
    return min(ok, key=lambda r: r["us_per_traj_per_core"]) if ok else None


def ratios(tools_out, tols, scope):
    """Peer / engine per core, in one run: at the same rtol, and at matched accuracy (each tool's cheapest
    scanned rtol whose max error on the scope's points is <= the level)."""
    engines = [t for t, v in tools_out.items() if v.get("family") == "engine" and scope in v.get("scopes", {})]
    peers = [t for t, v in tools_out.items() if v.get("family") not in (None, "engine")
             and scope in v.get("scopes", {})]
    same_rtol = {}
    for e in engines:
        for p in peers:
            er = {r["rtol"]: r for r in tools_out[e]["scopes"][scope]}
            pr = {r["rtol"]: r for r in tools_out[p]["scopes"][scope]}
            same_rtol[f"{p}/{e}"] = {f"{rt:g}": pr[rt]["us_per_traj_per_core"] / er[rt]["us_per_traj_per_core"]
                                     for rt in tols if rt in er and rt in pr}
    at_level = {}
    for level in ERROR_LEVELS:
        ent = {}
        for t in engines + peers:
            m = matched(tools_out[t]["scopes"][scope], level)
            ent[t] = None if m is None else {"rtol": m["rtol"], "us_per_traj_per_core": m["us_per_traj_per_core"],
                                             "max_rel_err": m["max_rel_err"]}
        have = [p for p in peers if ent[p]]
        best = min(have, key=lambda p: ent[p]["us_per_traj_per_core"]) if have else None
        ent["best_peer"] = best
        ent["engine_speedup_vs_best_peer"] = {  # best peer's time per trajectory per core / the engine's
            e: ent[best]["us_per_traj_per_core"] / ent[e]["us_per_traj_per_core"]
            for e in engines if ent[e] and best}
        at_level[f"{level:g}"] = ent
    return {"same_rtol_peer_over_engine": same_rtol, "matched_accuracy": at_level}


def tool_tols(tool, tols):
    """The rtols a tool scans: ``tols``, and for the peers also PEER_EXTRA_TOLS below them (a full run's
    tolerances reach 1e-10; the peers need ~100x tighter than the engine for the same max error)."""
    if tool.family == "engine" or min(tols) > REF_RTOL:
        return tols
    return tuple(tols) + tuple(t for t in PEER_EXTRA_TOLS if t < min(tols))


def best_pass(rows, new):
    """``rows`` (one per rtol, of the passes so far) with each replaced by ``new``'s row of the same rtol where that
    one was faster; every pass's wall times are kept in ``all_wall_s``."""
    if rows is None:
        return new
    merged = []
    for old, row in zip(rows, new):
        best = row if row["best_wall_s"] < old["best_wall_s"] else old
        merged.append({**best, "all_wall_s": old["all_wall_s"] + row["all_wall_s"]})
    return merged


def time_scope(tool, scope, scene, plan, tols, repeats, ref, sub):
    """One pass of ``tool`` over its tolerances on ``scope`` ("grid": every point, "sub": the subsample ``sub``):
    (its rows, None), or (the rows before the failure, why) where an installed peer fails (the others go on)."""
    idx = None if scope == "grid" else sub
    rows = []
    for rt in tool_tols(tool, tols):
        t0 = time.perf_counter()
        try:
            row = time_tool(tool, scene, plan, idx, rt, repeats, ref if idx is None else ref[idx],
                            sub if idx is None else None)
        except Exception as exc:
            if tool.family == "engine":
                raise
            why = f"{type(exc).__name__}: {exc}"[:500]
            print(f"    {tool.name:22s} {scope:4s} rtol {rt:7.0e}: failed ({why})", flush=True)
            return rows, why
        rows.append(row)
        err = "-" if row["max_rel_err"] is None else f"{row['max_rel_err']:.1e}"
        print(f"    {tool.name:22s} {scope:4s} rtol {rt:7.0e}: {row['us_per_traj_per_core']:10.2f} us/traj/core"
              f"  max err {err:>9s}  ({time.perf_counter() - t0:.1f} s)", flush=True)
    return rows, None


def bench_scene(name, scene, tools, tols, repeats, n_sub, n_check, passes=1):
    plan = sweep.make_plan(scene)
    sub = subsample(plan.n_points, n_sub, SEED)
    print(f"[{name}] {scene.shape[0]} x {scene.shape[1]} = {plan.n_points} points, subsample {sub.size} "
          f"(seed {SEED}); reference (engine rtol {REF_RTOL:g} + DOP853 {CHECK_RTOL:g} check)", flush=True)
    ref, ref_info = reference(scene, plan, sub, n_check)
    print(f"    reference check: max rel diff {ref_info['check_max_rel_diff']:.1e} on "
          f"{len(ref_info['check_flat_indices'])} points", flush=True)
    out = {}
    for n_pass in range(passes):
        if passes > 1:
            print(f"  pass {n_pass + 1} of {passes}", flush=True)
        for tool in tools:
            entry = out.setdefault(tool.name, {"label": tool.label, "family": tool.family, "threads": tool.threads,
                                               "note": tool.note, "scopes": {}})
            if "failed" in entry:
                continue
            for scope in tool.scopes:
                rows, why = time_scope(tool, scope, scene, plan, tols, repeats, ref, sub)
                if rows and not (why and scope in entry["scopes"]):  # a failed later pass keeps the earlier rows
                    entry["scopes"][scope] = best_pass(entry["scopes"].get(scope), rows)
                if why:
                    entry["failed"] = why
                    break
    return {"shape": list(scene.shape), "points": plan.n_points,
            "K_over_M_range": [float(scene.K_over_M.min()), float(scene.K_over_M.max())],
            "V_range": [float(scene.V.min()), float(scene.V.max())],
            "chi_over_A_range": [float(plan.k.min()), float(plan.k.max())],
            "mu1_over_A_range": [float(plan.a.min()), float(plan.a.max())],
            "plan": {"method": plan.describe()["method"], "stepper": plan.describe()["stepper"]},
            "subsample": {"points": int(sub.size), "seed": SEED, "flat_indices": sub.tolist()},
            "reference": ref_info, "tools": out,
            "ratios": {scope: ratios(out, tols, scope) for scope in ("grid", "sub")}}


# ------------------------------------------------------------------------------------------- output

def plot(result, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    scenes = [s for s in ("default", "corner") if s in result["scenes"]]
    fig, axes = plt.subplots(1, len(scenes), figsize=(6.2 * len(scenes), 6.4), squeeze=False)
    styles = {"engine": "-", "numbalsoda": "--", "diffrax": "-.", "scipy": ":"}
    for ax, sname in zip(axes[0], scenes):
        sc = result["scenes"][sname]
        for t in sc["tools"].values():
            if not t["scopes"]:
                continue
            scope = "grid" if "grid" in t["scopes"] else "sub"
            rows = [r for r in t["scopes"][scope] if r.get("max_rel_err")]
            if not rows:
                continue
            ax.loglog([r["max_rel_err"] for r in rows], [r["us_per_traj_per_core"] for r in rows],
                      styles.get(t["family"], "-"), marker="o", ms=3, lw=2.2 if t["family"] == "engine" else 1.2,
                      label=f"{t['label']} [{scope}: {rows[0]['points']} pts]")
        ax.axvspan(1e-17, sc["reference"]["error_floor"], color="0.9", zorder=0)
        ax.set_xlim(left=max(1e-13, 0.3 * sc["reference"]["error_floor"]))
        ax.set_xlabel(f"max relative xi_inf error (vs engine rtol {REF_RTOL:g}, control x{REF_CTRL_FACTOR:g})")
        ax.set_ylabel("us per trajectory per core")
        ax.set_title(f"{sname}: {sc['shape'][0]} x {sc['shape'][1]}, rtol {result['settings']['tols'][0]:g}.."
                     f"{result['settings']['tols'][-1]:g}", fontsize=9)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
    fig.suptitle(f"sweep vs peers, {result['machine']['cpu']} ({result['date']}); JIT compile excluded",
                 fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def print_table(result):
    tols = result["settings"]["tols"]
    print(f"\n== sweep vs peers  {result['date']}  {result['machine']['cpu']}, {result['machine']['usable_cpus']} "
          f"usable cpus; us per trajectory per core (max rel error); JIT excluded")
    for name, st in result["peers_status"].items():
        if st != "ok":
            print(f"   {name}: {st}")
    for sname, sc in result["scenes"].items():
        print(f"\n[{sname}] {sc['shape'][0]} x {sc['shape'][1]} ({sc['points']} points; subsample "
              f"{sc['subsample']['points']}); reference floor {sc['reference']['error_floor']:.1e}")
        columns = sorted({r["rtol"] for t in sc["tools"].values() for rows in t["scopes"].values() for r in rows}
                         | set(tols), reverse=True)
        print(f"{'tool':24s}{'pts':>7s}" + "".join(f"{t:>18.0e}" for t in columns))
        for name, t in sc["tools"].items():
            if "failed" in t:
                print(f"{name:24s} failed: {t['failed']}")
            for rows in t["scopes"].values():
                by_rtol = {r["rtol"]: r for r in rows}
                cells = []
                for rt in columns:
                    r = by_rtol.get(rt)
                    e = "" if r is None else ("-" if r["max_rel_err"] is None else f"{r['max_rel_err']:.0e}")
                    cells.append("" if r is None else f"{r['us_per_traj_per_core']:9.2f} ({e:>5s})")
                print(f"{name:24s}{rows[0]['points']:7d}" + "".join(f"{c:>18s}" for c in cells))
        for scope in ("grid", "sub"):
            ml = sc["ratios"][scope]["matched_accuracy"]
            print(f"  matched accuracy ({scope}): engine speed-up per core vs the best peer (its time / the engine's)")
            for lvl, ent in ml.items():
                bp = ent["best_peer"]
                us = f"{ent[bp]['us_per_traj_per_core']:9.2f} us" if bp else ""
                parts = [f"{e.replace('engine_', '')} x{v:.2f}" for e, v in ent["engine_speedup_vs_best_peer"].items()]
                print(f"    err <= {lvl:>6s}: best peer {bp or '-':15s}{us:>13s}   " + "  ".join(parts))


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if "--driven" in argv:  # the driven scene's peers (issue 35): benchmarks/_peers_driven.py
        import _peers_driven
        return _peers_driven.main([a for a in argv if a != "--driven"])
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny grids (every 10th K/M and V), 12-point subsample, "
                                                         "3 tolerances, 1 repeat: checks that the script works")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--no-png", action="store_true")
    ap.add_argument("--passes", type=int, default=PASSES, help=f"sweeps over every tool and tolerance, each keeping "
                                                                f"its best (default {PASSES}; --quick: 1)")
    ap.add_argument("--no-corner", action="store_true", help="the default scene only")
    ap.add_argument("--tols", type=lambda x: tuple(sorted((float(v) for v in x.split(",")), reverse=True)),
                    help="comma-separated rtols instead of 1e-3..1e-10 (--quick: 1e-3,1e-6,1e-9)")
    args = ap.parse_args(argv)
    quick = args.quick
    warnings.simplefilter("ignore", RuntimeWarning)
    t_start = time.perf_counter()
    load0, digest0 = common.loadavg(), common.sweep_digest()
    n_all = numba.config.NUMBA_NUM_THREADS
    tols = args.tols or (TOLS_QUICK if quick else TOLS)
    repeats = REPEATS_QUICK if quick else REPEATS

    tools = engine_tools(n_all)
    status = {}
    for name, make in (("numbalsoda", lambda: numbalsoda_tools(n_all)), ("diffrax", lambda: diffrax_tools(DIFFRAX_PID)),
                       ("scipy", scipy_tools)):
        got, why = make()
        status[name] = "ok" if got else why
        tools += got or []
        print(f"peer {name}: {status[name]}", flush=True)

    base = quasistatic_default()
    if quick:
        base = quick_scene(base)
    scenes = {"default": (base, N_SUB_QUICK if quick else N_SUB)}
    corner = None if args.no_corner else corner_scene(base)
    if corner is not None:
        scenes["corner"] = (corner, N_SUB_CORNER_QUICK if quick else N_SUB_CORNER)
    n_check = N_CHECK_QUICK if quick else N_CHECK
    passes = 1 if quick else args.passes
    out_scenes = {name: bench_scene(name, sc, tools, tols, repeats, n, n_check, passes)
                  for name, (sc, n) in scenes.items()}

    import scipy
    result = {
        "benchmark": "benchmarks/peers.py" + (" --quick" if quick else ""),
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "machine": common.machine_info(),
        "versions": {**common.versions(), "scipy": scipy.__version__, "jax": version_of("jax"),
                     "jaxlib": version_of("jaxlib"), "diffrax": version_of("diffrax"),
                     "equinox": version_of("equinox"), "numbalsoda": version_of("numbalsoda")},
        "sweep_source_digest_start_end": [digest0, common.sweep_digest()],
        "loadavg_start_end": [load0, common.loadavg()],
        "peers_status": status,
        "tools_missing": {name: why for name, why in status.items() if why != "ok"},  # left out of this run
        "settings": {
            "tols": list(tols), "peer_extra_tols": [t for t in PEER_EXTRA_TOLS if t < min(tols) <= REF_RTOL],
            "reference_ctrl_factor": REF_CTRL_FACTOR, "repeats": repeats, "passes": passes, "scipy_repeats": 1,
            "seed": SEED,
            "atol_peers": f"{ATOL_OVER_RTOL:g} x rtol", "atol_engine": "the scene's atol (xi_inf 1e-12)",
            "tail_test_tolerance": "rtol x xi + the scene's atol (xi_inf), the engine's own at that rtol",
            "scene": "sweep.default_scene() with model='quasistatic'" + (", every 10th K/M and V" if quick else ""),
            "corner": f"the sub-grid with chi/A <= {CORNER_K_MAX:g} and mu1 < 0",
            "jit": JIT_NOTE,
            "per_core": "wall x threads / trajectories (diffrax and scipy: 1 thread)",
            "scopes": "grid: every point of the scene (engine, numbalsoda, diffrax); sub: the fixed-seed random "
                      "subsample, the same points for every tool (scipy runs there only)",
            "numbalsoda_output_times": {"per_segment": OUT_PER_SEGMENT, "first_segment": f"[s_c, {S_FIRST:g}]",
                                        "segment_ratio": SEGMENT_RATIO},
            "diffrax_pid": dict(zip(("pcoeff", "icoeff", "dcoeff"), DIFFRAX_PID)),
            "numba_threads_all": n_all,
        },
        "formulation": "dxi/ds = exp(-(k xi + a u + b u^2)), u = s - xi, xi(0) = 0 (k = chi/A, a = mu1/A, b = m2/A "
                       "from the engine's plan); stop once sweep.integrate.models.stop.tail_is_accurate passes "
                       "(tolerance "
                       "rtol xi + atol_scene), then + sweep.integrate.models.stop.tail_slip",
        "scenes": out_scenes,
        "benchmark_wall_s": None,
    }
    common.write_result(result, args.out, t_start, None if args.no_png else plot, print_table)


if __name__ == "__main__":
    main()
