#!/usr/bin/env python
"""Work-precision benchmark (in the manner of SciMLBenchmarks): achieved error vs time per trajectory, every
engine configuration and scipy's DOP853 / LSODA / Radau side by side, on one fixed set of stop problems.

    python benchmarks/work_precision.py [--quick | --half] [--out benchmarks/results/work_precision.json]
                                        [--no-png] [--no-threads2] [--replot]

* Problems: six fixed quasi-static stop points from tests/cases.py (reduced form chi, A, mu1, m2), among them
  the costly corner of the default grid, a slow tail and the stiff corner (PROBLEMS below).
* Reference: the closed form xi_inf = A ln(chi/mu1)/(chi - mu1) where m2 = 0; otherwise tests/reference.py's
  solver (paper variables, log time, DOP853) re-run at rtol 1e-13, cross-checked against its rtol 1e-12 value
  and against DOP853 at rtol 1e-13 in the engine's own formulation.
* Engine configurations (one thread, numba.set_num_threads(1); two threads per core as well): RK4 at fixed
  steps h in sigma (a sqrt(2) ladder, 2 .. 0.011: mean steps from ~tens to thousands), RK4 with the plan's
  step rule, DP5 and DOP853 (adaptive) at rtol 1e-2 .. 1e-10, float32 RK4 (steps and rule, rtol >= 1e-5),
  method="auto" with fixed steps (RK4, and the Rosenbrock ros4 at the stiff corner; float64 and float32) and
  method="auto" at rtol 1e-2 .. 1e-10. Each point is solved as the engine always does (a Richardson pair:
  coarse mesh + the same mesh halved, fine result returned with its error estimate).
* scipy: the OdeSolver classes DOP853, LSODA, Radau (what solve_ivp drives) on the engine's formulation at
  rtol 1e-3 .. 1e-11 (atol = ATOL_FACTOR * rtol), stopped by the engine's tail test and completed by its
  closed-form tail (benchmarks/_common.py's scipy_point, shared with benchmarks/throughput.py).
* Error of a configuration = max over the problems of |xi_inf / ref - 1|; time per trajectory = mean over the
  problems of the best-of-repeats CPU time (time.process_time) per trajectory of each problem; the best wall
  time is recorded beside it (the two agree on an idle machine; CPU time stays meaningful on a shared one).

Summary: at each error level 1e-3 .. 1e-10 the cheapest engine configuration whose error is <= the level vs
the cheapest scipy one (speed-up per core; target >= 150x, project goal 1000x), and for each rtol the auto
choice vs the fastest engine configuration that meets that rtol (target within 1.5x).

Writes benchmarks/results/work_precision.json and work_precision.png; prints a table. See benchmarks/README.md.

--half: every other configuration and scipy rtol, one timing pass (~3 min on the 2-core machine; the former
--quick). --quick (a smoke run: does it work, in seconds; its numbers are not results): one or two configurations
of every engine family (QUICK_CONFIGS), scipy at rtol 1e-3, 1e-6, 1e-9, each timed once on a batch sized for
~2 ms, one pass.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numba
import numpy as np
from scipy.integrate import DOP853, LSODA, Radau

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(HERE))

import reference as refmod  # noqa: E402  (tests/reference.py: scipy only, independent of sweep)
from _common import (  # noqa: E402  (benchmarks/_common.py)
    check_tail_ok,
    loadavg,
    machine_info,
    scipy_point,
    sweep_digest,
    timed,
)
from cases import STOP_CASES, case_params  # noqa: E402

import sweep  # noqa: E402
import sweep.plan.plan  # noqa: E402
from sweep.protocols.stop.chunk import execute  # noqa: E402

DEFAULT_OUT = HERE / "results" / "work_precision.json"
PROBLEMS = (
    "s2_KM1e3_V100um_corner",  # costly corner of the default grid (thousands of RK4 steps)
    "g_chiA1_mA0.3_slowtail",  # slow tail tau^-0.3
    "g_chiA1000_mA1_stiff",  # stiff corner, decay rate chi/A = 1000
    "s2_KM2.8e5_V10um",  # paper Fig. 4 transient, mu1 < 0
    "g_chiA0.01_mA1",  # soft spring deep in stick-slip, large slip
    "g_chiA0.1_mA-0.5_m2A0.2",  # mu1 < 0 with m2 > 0
)
LEVELS = [10.0**-e for e in range(3, 11)]  # error levels of the summary
RTOLS_ENGINE = [10.0**-e for e in range(2, 11)]  # Scene accepts 1e-10 <= rtol <= 1e-2 (1e-11 is refused)
RTOLS_F32 = [1e-2, 1e-3, 1e-4, 1e-5]  # float32 needs rtol >= 1e-5
RTOLS_SCIPY = [10.0**-e for e in range(3, 12)]
STEPS_H = [2.0 * 2.0 ** (-j / 2) for j in range(15)]  # 2, 1.41, 1, ..., 0.0156: fixed RK4 steps in sigma
STEPS_H_F32 = STEPS_H[:9]  # float32 rounding floors the error near 1e-6; finer steps only cost
ATOL_FACTOR = 1e-3  # scipy atol = ATOL_FACTOR * rtol (xi starts at 0; the smallest xi_inf here is 0.0069)
TAIL_ATOL = 1e-12  # absolute floor of the tail test for scipy (the engine's default atol for xi_inf)
TARGET_SPEEDUP = 150.0
GOAL_SPEEDUP = 1000.0
TARGET_AUTO = 1.5
REF_RTOL = 1e-13
SCIPY_CAP_S = 4.0  # a scipy trajectory slower than this: no repeats, and no tighter rtol for that method
QUICK_CONFIGS = ("rk4 h=1", "rk4 h=0.25", "rk4 f32 h=0.5", "auto h=0.5", "auto f32 h=0.5", "rk4 rule rtol=0.0001",
                 "rk4 f32 rule rtol=0.0001", "dp5 rtol=1e-06", "dop853 rtol=1e-06", "auto rtol=0.001",
                 "auto rtol=1e-06", "auto rtol=1e-09")
"""The engine configurations of --quick (labels of :func:`engine_configs`): every family at least once."""
RTOLS_SCIPY_QUICK = [1e-3, 1e-6, 1e-9]


# ------------------------------------------------------------------------------------------ problems

def problems():
    byname = {c.name: c for c in STOP_CASES}
    out = []
    for name in PROBLEMS:
        c = byname[name]
        p = case_params(c)
        fp = sweep.FrictionParams(A=p["A"], m1=p["m1"], m2=p["m2"], D0=p["D0"], V0=p["V0"], g=p["g"])
        out.append({"name": name, "why": c.why, "chi": c.chi, "A": c.A, "mu1": c.mu1, "m2": c.m2,
                    "k": c.chi / c.A, "a": c.mu1 / c.A, "b": c.m2 / c.A, "params": fp,
                    "K_over_M": p["K_over_M"], "V": p["V"]})
    return out


def scene_for(pb, **kw) -> sweep.Scene:
    return sweep.Scene(protocol="stop", params=pb["params"], K_over_M=[pb["K_over_M"]], V=[pb["V"]], **kw)


# ----------------------------------------------------------------------------------------- reference

def reference_at(chi, A, mu1, m2, rtol):
    """tests/reference.py's solver with its module tolerance set to ``rtol`` (uncached call)."""
    old = refmod.RTOL
    refmod.RTOL = rtol
    try:
        return refmod.reference_stop.__wrapped__(chi, A, mu1, m2)
    finally:
        refmod.RTOL = old


def build_reference(pbs):
    out = []
    for pb in pbs:
        chi, A, mu1, m2 = pb["chi"], pb["A"], pb["mu1"], pb["m2"]
        r12 = refmod.reference_stop(chi, A, mu1, m2)
        r13 = reference_at(chi, A, mu1, m2, REF_RTOL)
        # the engine's formulation (contact-age time s), DOP853 at rtol 1e-13: an independent second solution
        x_s, _, nfev_s = scipy_point(DOP853, pb["k"], pb["a"], pb["b"], REF_RTOL, REF_RTOL * 1e-6, REF_RTOL, 1e-16)
        closed = A * math.log(chi / mu1) / (chi - mu1) if m2 == 0.0 else None
        value = closed if closed is not None else r13.xi_inf
        d = {"name": pb["name"], "xi_inf": value,
             "source": "closed form A ln(chi/mu1)/(chi - mu1) (m2 = 0)" if closed is not None
             else f"tests/reference.py at rtol {REF_RTOL:g} ({r13.method}, paper variables in log time)",
             "paper_form_rtol_1e-12": r12.xi_inf, "paper_form_rtol_1e-13": r13.xi_inf,
             "paper_form_method": r13.method, "paper_form_nfev_1e-13": r13.nfev,
             "engine_form_dop853_rtol_1e-13": x_s, "engine_form_nfev": int(nfev_s),
             "rel_diff_1e-12_vs_ref": abs(r12.xi_inf / value - 1),
             "rel_diff_1e-13_vs_ref": abs(r13.xi_inf / value - 1),
             "rel_diff_engine_form_vs_ref": abs(x_s / value - 1)}
        if closed is not None:
            d["closed_form"] = closed
        d["uncertainty_estimate"] = (max(d["rel_diff_1e-13_vs_ref"], d["rel_diff_engine_form_vs_ref"], 1e-15)
                                     if closed is None else 1e-15)
        out.append(d)
    return out


# -------------------------------------------------------------------------------------------- engine

def rtol_for_step(h: float, lo: float, hi: float) -> float:
    """The rtol whose planned RK4 step (sweep.plan.plan's rule, stable side) is h, clipped to [lo, hi]: with a fixed
    step the scene's rtol only sets the tail test (0.001 (rtol xi + atol)) and the status threshold, so it is
    matched to the error that step gives, rather than spending steps on a needlessly tight tail."""
    c = (getattr(sweep.plan.plan, "STEP_SAFETY", 2.0) * getattr(sweep.plan.plan, "ERROR_GAIN", 15.0)
         * getattr(sweep.plan.plan, "C_STABLE", 6e-4))
    return float(min(hi, max(lo, c * h**4)))


def time_engine(scene, plan, target_s, repeats, n_min=64, n_max=400_000, probes=3):
    """Best-of-``repeats`` seconds per trajectory (CPU, wall) of the problem repeated N times through
    sweep.protocols.stop.chunk.execute (the kernel path run_sweep takes, without building the Dataset); N is chosen so
    that
    one call lasts about ``target_s``, from probes at growing N (a call has a fixed cost of ~0.4 ms, so a probe
    at 64 points overstates the cost per point several times at loose rtol and would leave batches of a few
    hundred points, timed mostly on that fixed cost). Returns (CPU s per trajectory, wall s per trajectory, N,
    batch xi_inf)."""
    n = n_min
    execute(scene, plan, np.zeros(n, np.int64), progress=False)  # compile / load from numba's cache
    for _ in range(probes):
        per, _, _ = timed(lambda n=n: execute(scene, plan, np.zeros(n, np.int64), progress=False), min(3, repeats))
        n_next = int(min(n_max, max(n_min, target_s / max(per / n, 1e-9))))
        if n_next <= n:
            break
        n = n_next
    idx = np.zeros(n, np.int64)
    cpu, wall, res = timed(lambda: execute(scene, plan, idx, progress=False), repeats)
    return cpu / n, wall / n, n, res.xi_inf


def run_engine_config(pbs, refs, label, family, kw_for, threads2, target_s, repeats, probes=3):
    """One engine configuration over all problems: error (public run_sweep on the 1-point scene), timing.
    Returns the summary and, per problem, (scene, plan) for later timing passes (:func:`time_row`)."""
    rows, handles = [], []
    for pb, ref in zip(pbs, refs):
        kw = kw_for(pb)
        scene = scene_for(pb, **kw)
        plan = sweep.plan.plan.make_plan(scene)
        ds = sweep.run_sweep(scene, progress=False)
        x = float(ds["xi_inf"].values.item())
        est = float(ds["xi_inf_error"].values.item())
        status = int(ds["status"].values.item())
        steps = int(ds["steps"].values.item())
        # "step": the plan's step (lanes on auto: the pilot step h0 of the ladder, sweep/integrate/ladder.py)
        row = {"problem": pb["name"], "scene_rtol": scene.rtol, "method": plan.method,
               "step": float(plan.step[0]) if not plan.adaptive else None, "xi_inf": x,
               "rel_err": abs(x / ref["xi_inf"] - 1), "rel_err_estimate": est / abs(x) if x else math.nan,
               "status": sweep.Status(status).name.lower(), "steps_fine": steps,
               "work": int(execute(scene, plan, np.zeros(1, np.int64), progress=False).work[0])}
        row["estimate_over_true"] = row["rel_err_estimate"] / max(row["rel_err"], 1e-300)
        time_row(row, scene, plan, threads2, target_s, repeats, probes)
        rows.append(row)
        handles.append((scene, plan))
    return summarise(label, family, rows, refs), handles


def time_row(row, scene, plan, threads2, target_s, repeats, probes=3):
    """Time one (configuration, problem) and keep the best over the passes so far (1 thread, and 2 threads)."""
    numba.set_num_threads(1)
    t1, w1, n1, xb = time_engine(scene, plan, target_s, repeats, probes=probes)
    row.setdefault("us_per_traj_1thread_passes", []).append(t1 * 1e6)
    row["us_per_traj_1thread"] = min(row["us_per_traj_1thread_passes"])
    row["us_per_traj_1thread_wall"] = min(row.get("us_per_traj_1thread_wall", math.inf), w1 * 1e6)
    row["batch"] = n1
    x = row["xi_inf"]
    same = bool(np.all(xb == x) or np.allclose(xb, x, rtol=1e-15, atol=0))
    row["batch_matches_single"] = row.get("batch_matches_single", True) and same
    tab = plan.tableau
    evals = row["work"] * (len(tab.b) - (1 if tab.fsal else 0))  # all runs of the point (RawResult.work)
    row["ns_per_stage_eval_approx"] = row["us_per_traj_1thread"] * 1e3 / evals if evals else None
    if threads2:
        numba.set_num_threads(2)
        c2, w2, _, _ = time_engine(scene, plan, target_s, repeats, probes=probes)
        row["us_per_traj_per_core_2threads"] = min(row.get("us_per_traj_per_core_2threads", math.inf), 2 * w2 * 1e6)
        row["us_cpu_per_traj_2threads"] = min(row.get("us_cpu_per_traj_2threads", math.inf), c2 * 1e6)
        numba.set_num_threads(1)


def summarise(label, family, rows, refs):
    errs = np.array([r["rel_err"] for r in rows])
    rtol = rows[0].get("scene_rtol", rows[0].get("rtol"))
    unc = np.array([ref["uncertainty_estimate"] for ref in refs])
    t = np.array([r.get("us_per_traj_1thread", r.get("us_per_traj")) for r in rows])
    wall = [r.get("us_per_traj_1thread_wall", r.get("us_per_traj_wall")) for r in rows]
    out = {"label": label, "family": family, "max_rel_err": float(errs.max()),
           "worst_problem": rows[int(errs.argmax())]["problem"], "us_per_traj": float(t.mean()),
           "us_per_traj_wall": float(np.mean(wall)),
           "us_per_traj_max_problem": float(t.max()),
           "max_err_over_rtol": float(errs.max() / rtol) if rtol else None,
           "error_at_reference_floor": bool(np.all(errs <= 10 * unc)), "per_problem": rows}
    if "steps_fine" in rows[0]:
        st = np.array([r["steps_fine"] for r in rows])
        ratio = np.array([r["estimate_over_true"] for r in rows])
        resolved = errs > 10 * unc  # true error measurable above the reference's own uncertainty
        out.update({"mean_steps_fine": float(st.mean()), "median_steps_fine": float(np.median(st)),
                    "all_status_ok": all(r["status"] == "ok" for r in rows),
                    "statuses": sorted({r["status"] for r in rows}),
                    "estimate_over_true_min": float(ratio[resolved].min()) if resolved.any() else None,
                    "estimate_over_true_max": float(ratio[resolved].max()) if resolved.any() else None,
                    "batch_matches_single": all(r["batch_matches_single"] for r in rows),
                    "ns_per_stage_eval_approx": float(np.median([r["ns_per_stage_eval_approx"] for r in rows]))})
        if "us_per_traj_per_core_2threads" in rows[0]:
            out["us_per_traj_per_core_2threads"] = float(np.mean([r["us_per_traj_per_core_2threads"] for r in rows]))
    return out


def engine_configs(half=False, quick=False):
    """(label, family, kw_for(problem)) of every engine configuration (half: every other step h; quick: only
    QUICK_CONFIGS)."""
    if quick:
        cfgs = [c for c in engine_configs(half=True) if c[0] in QUICK_CONFIGS]
        missing = set(QUICK_CONFIGS) - {c[0] for c in cfgs}
        assert not missing, f"QUICK_CONFIGS names no configuration {sorted(missing)}"
        return cfgs
    cfgs = []
    hs = STEPS_H[::2] if half else STEPS_H
    hs32 = STEPS_H_F32[::2] if half else STEPS_H_F32
    # fixed steps: rk4 alone, and method auto (RK4, and ros4 at the stiff points: sweep.plan.plan.stiff_points)
    for method, name, family in (("rk4", "rk4", "engine rk4"), ("auto", "auto", "engine auto (rk4 + ros4)")):
        for precision, tag, steps, rtol_min in (("float64", "", hs, 1e-10), ("float32", " f32", hs32, 1e-5)):
            for h in steps:
                cfgs.append((f"{name}{tag} h={h:.4g}", f"{family}{' float32' if tag else ''} fixed h",
                             lambda pb, h=h, m=method, p=precision, lo=rtol_min: dict(
                                 method=m, step=h, precision=p, rtol=rtol_for_step(h, lo, 1e-2))))
    for rt in RTOLS_ENGINE:
        cfgs.append((f"rk4 rule rtol={rt:g}", "engine rk4 plan rule", lambda pb, rt=rt: dict(method="rk4", rtol=rt)))
    for rt in RTOLS_F32:
        cfgs.append((f"rk4 f32 rule rtol={rt:g}", "engine rk4 float32 plan rule",
                     lambda pb, rt=rt: dict(method="rk4", rtol=rt, precision="float32")))
    for m in ("dp5", "dop853"):
        for rt in RTOLS_ENGINE:
            cfgs.append((f"{m} rtol={rt:g}", f"engine {m}", lambda pb, rt=rt, m=m: dict(method=m, rtol=rt)))
    for rt in RTOLS_ENGINE:
        cfgs.append((f"auto rtol={rt:g}", "engine auto", lambda pb, rt=rt: dict(method="auto", rtol=rt)))
    return cfgs


# --------------------------------------------------------------------------------------------- scipy

def scipy_solve(method, pb, rtol):
    atol = ATOL_FACTOR * rtol
    cls = {"DOP853": DOP853, "LSODA": LSODA, "Radau": Radau}[method]
    return scipy_point(cls, pb["k"], pb["a"], pb["b"], rtol, atol, rtol, TAIL_ATOL)


def run_scipy(pbs, refs, repeats, passes, rtols):
    configs, skipped = [], []
    for method in ("DOP853", "LSODA", "Radau"):
        scipy_solve(method, pbs[1], 1e-6)  # warm-up (imports, first-call paths)
        capped = False
        for rt in rtols:
            if capped:
                skipped.append({"method": method, "rtol": rt, "why": f"a looser rtol already took > {SCIPY_CAP_S} s "
                                "per trajectory on some problem"})
                continue
            rows = []
            for pb, ref in zip(pbs, refs):
                solve = lambda method=method, pb=pb, rt=rt: scipy_solve(method, pb, rt)
                first, first_wall, (x, steps, nfev) = timed(solve, 1)
                n_rep = repeats if first < 0.05 else (3 if first < 1.0 else 1)
                cpu, wall = first, first_wall
                if n_rep > 1 and first < SCIPY_CAP_S:
                    cpu, wall, _ = timed(solve, n_rep - 1)
                capped |= first > SCIPY_CAP_S
                rows.append({"problem": pb["name"], "rtol": rt, "xi_inf": x, "rel_err": abs(x / ref["xi_inf"] - 1),
                             "us_per_traj": min(cpu, first) * 1e6, "us_per_traj_wall": min(wall, first_wall) * 1e6,
                             "repeats": n_rep, "steps": int(steps), "nfev": int(nfev)})
            s = summarise(f"scipy {method} rtol={rt:g}", f"scipy {method}", rows, refs)
            s.update({"rtol": rt, "atol": ATOL_FACTOR * rt, "mean_steps": float(np.mean([r["steps"] for r in rows])),
                      "mean_nfev": float(np.mean([r["nfev"] for r in rows]))})
            configs.append(s)
            print(f"  {s['label']:<28} err {s['max_rel_err']:9.2e}  {s['us_per_traj'] / 1e3:9.3f} ms/traj", flush=True)
    for k in range(1, passes):  # later passes (best of 3 more each), keeping the best
        print(f"  scipy timing pass {k + 1} of {passes}", flush=True)
        for i, c in enumerate(configs):
            method = c["family"].split()[1]
            for row, pb in zip(c["per_problem"], pbs):
                if row["us_per_traj"] > 1e6 * SCIPY_CAP_S / 4:
                    continue
                cpu, wall, _ = timed(lambda method=method, pb=pb, rt=c["rtol"]: scipy_solve(method, pb, rt), 3)
                row["us_per_traj"] = min(row["us_per_traj"], cpu * 1e6)
                row["us_per_traj_wall"] = min(row["us_per_traj_wall"], wall * 1e6)
                row["repeats"] += 3
            extra = {k2: c[k2] for k2 in ("rtol", "atol", "mean_steps", "mean_nfev")}
            configs[i] = summarise(c["label"], c["family"], c["per_problem"], refs) | extra
    return configs, skipped


# ------------------------------------------------------------------------------------------- summary

CORNER = "s2_KM1e3_V100um_corner"


def subset(cfg, names):
    """The configuration's error and mean time recomputed over the problems ``names`` only."""
    rows = [r for r in cfg["per_problem"] if r["problem"] in names]
    t = [r.get("us_per_traj_1thread", r.get("us_per_traj")) for r in rows]
    out = {"label": cfg["label"], "family": cfg["family"], "max_rel_err": max(r["rel_err"] for r in rows),
           "us_per_traj": float(np.mean(t)), "all_status_ok": all(r.get("status", "ok") == "ok" for r in rows),
           "per_problem": rows}
    if "us_per_traj_per_core_2threads" in cfg:
        out["us_per_traj_per_core_2threads"] = float(np.mean([r["us_per_traj_per_core_2threads"] for r in rows]))
    return out


def diagnostics(engine, scipy_cfgs, table):
    """What the speed-up is made of: cost per stage evaluation per engine family, scipy's cost per RHS evaluation,
    and the costly corner's share of the best engine configuration's time at each error level."""
    fam = {}
    for c in engine:
        fam.setdefault(c["family"], []).append(c["ns_per_stage_eval_approx"])
    sc = {}
    for c in scipy_cfgs:
        per = [r["us_per_traj"] / r["nfev"] for r in c["per_problem"]]
        sc.setdefault(c["family"], []).extend(per)
    by_label = {c["label"]: c for c in engine + scipy_cfgs}
    share = []
    for r in table:
        row = {"level": r["level"]}
        for side, key in (("engine", "engine_best"), ("scipy", "scipy_best")):
            c = by_label.get(r[key])
            if c:
                t = [p.get("us_per_traj_1thread", p.get("us_per_traj")) for p in c["per_problem"]]
                corner = next(x for p, x in zip(c["per_problem"], t) if p["problem"] == CORNER)
                row[f"{side}_corner_share"] = corner / sum(t)
        share.append(row)
    return {"engine_ns_per_stage_eval_median_by_family": {k: float(np.median(v)) for k, v in fam.items()},
            "scipy_us_per_rhs_eval_median_by_method": {k: float(np.median(v)) for k, v in sc.items()},
            "corner_share_of_time_of_best_configs": share}


def cheapest(configs, level):
    ok = [c for c in configs if c["max_rel_err"] <= level]
    return min(ok, key=lambda c: c["us_per_traj"]) if ok else None


def frontier_time(configs, level):
    """Log-log interpolated time at error ``level`` on the Pareto frontier (time vs error) of ``configs``:
    between the cheapest config with error <= level and the next cheaper one with error > level."""
    pts = sorted(((c["max_rel_err"], c["us_per_traj"]) for c in configs), key=lambda p: p[1])
    front, best = [], math.inf
    for e, t in pts:  # increasing time, keep strictly decreasing error
        if e < best:
            front.append((e, t))
            best = e
    for (e0, t0), (e1, t1) in zip(front, front[1:]):
        if e1 <= level < e0:
            w = (math.log(level) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0)))
    if front and front[0][0] <= level:
        return front[0][1]
    return None


def summary(engine, scipy_cfgs):
    rows = []
    for L in LEVELS:
        e, s = cheapest(engine, L), cheapest(scipy_cfgs, L)
        row = {"level": L, "engine_best": e and e["label"], "engine_us": e and e["us_per_traj"],
               "engine_err": e and e["max_rel_err"], "scipy_best": s and s["label"], "scipy_us": s and s["us_per_traj"],
               "scipy_err": s and s["max_rel_err"]}
        row["speedup"] = s["us_per_traj"] / e["us_per_traj"] if e and s else None
        row["speedup_wall_same_configs"] = (s["us_per_traj_wall"] / e["us_per_traj_wall"]
                                            if e and s and "us_per_traj_wall" in e else None)
        e2 = [c for c in engine if "us_per_traj_per_core_2threads" in c and c["max_rel_err"] <= L]
        if e2 and s:
            b2 = min(e2, key=lambda c: c["us_per_traj_per_core_2threads"])
            row["engine_best_2threads"] = b2["label"]
            row["speedup_per_core_2threads"] = s["us_per_traj"] / b2["us_per_traj_per_core_2threads"]
        fe, fs = frontier_time(engine, L), frontier_time(scipy_cfgs, L)
        row["speedup_interpolated"] = fs / fe if fe and fs else None
        row["meets_target"] = row["speedup"] is not None and row["speedup"] >= TARGET_SPEEDUP
        row["meets_goal"] = row["speedup"] is not None and row["speedup"] >= GOAL_SPEEDUP
        rows.append(row)
    auto = []
    for rt in RTOLS_ENGINE:
        a = next((c for c in engine if c["label"] == f"auto rtol={rt:g}"), None)
        others = [c for c in engine if c["family"] != "engine auto"]
        f64 = [c for c in others if "float32" not in c["family"]]
        best = cheapest(f64, rt)  # auto runs float64 unless precision="float32" is asked for
        best32 = cheapest(others, rt)
        best_ok = cheapest([c for c in f64 if c["all_status_ok"] and c["per_problem"][0]["scene_rtol"] <= rt], rt)
        r = {"rtol": rt, "auto": a and a["label"], "auto_method": a and a["per_problem"][0]["method"],
             "auto_us": a and a["us_per_traj"], "auto_err": a and a["max_rel_err"],
             "auto_meets_rtol": bool(a and a["max_rel_err"] <= rt), "auto_status_ok": a and a["all_status_ok"],
             "fastest_meeting_rtol": best and best["label"], "fastest_us": best and best["us_per_traj"],
             "fastest_err": best and best["max_rel_err"],
             "fastest_incl_float32": best32 and best32["label"],
             "fastest_incl_float32_us": best32 and best32["us_per_traj"],
             "fastest_status_ok_scene_rtol_le_rtol": best_ok and best_ok["label"],
             "fastest_status_ok_us": best_ok and best_ok["us_per_traj"]}
        r["auto_over_fastest"] = a["us_per_traj"] / best["us_per_traj"] if a and best else None
        r["auto_over_fastest_incl_float32"] = a["us_per_traj"] / best32["us_per_traj"] if a and best32 else None
        r["auto_over_fastest_status_ok"] = a["us_per_traj"] / best_ok["us_per_traj"] if a and best_ok else None
        r["within_target"] = r["auto_over_fastest"] is not None and r["auto_over_fastest"] <= TARGET_AUTO
        auto.append(r)
    return rows, auto


# -------------------------------------------------------------------------------------------- output

FAMILY_STYLE = {
    "engine rk4 fixed h": ("C0", "o", "-"), "engine rk4 plan rule": ("C0", "s", ":"),
    "engine rk4 float32 fixed h": ("C9", "o", "-"), "engine rk4 float32 plan rule": ("C9", "s", ":"),
    "engine dp5": ("C1", "^", "-"), "engine dop853": ("C2", "v", "-"), "engine auto": ("k", "*", "--"),
    "scipy DOP853": ("C3", "v", "-"), "scipy LSODA": ("C4", "D", "-"), "scipy Radau": ("C5", "P", "-"),
}


def plot(engine, scipy_cfgs, table, table_nc, refs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 5.6), gridspec_kw={"width_ratios": [1.6, 1]})
    fams = {}
    for c in engine + scipy_cfgs:
        fams.setdefault(c["family"], []).append(c)
    for fam, cs in fams.items():
        col, mk, ls = FAMILY_STYLE.get(fam, ("gray", ".", "-"))
        # in configuration order (step h large to small, rtol loose to tight)
        ax.loglog([c["max_rel_err"] for c in cs], [c["us_per_traj"] for c in cs], ls, color=col, marker=mk, ms=5,
                  lw=1.3, label=fam, alpha=0.9)
    ax.axvspan(1e-10, 1e-3, color="0.93", zorder=0)
    floor = max(r["uncertainty_estimate"] for r in refs)
    ax.axvspan(floor, 1e-16, color="0.75", alpha=0.4, zorder=0, lw=0)
    ax.text(floor * 0.6, ax.get_ylim()[0] * 1.5, "reference\nuncertainty", fontsize=7, color="0.35")
    ax.set_xlabel("achieved error: max over the 6 problems of |xi_inf/ref - 1|")
    ax.set_ylabel("time per trajectory [us] (mean over problems, 1 core)")
    ax.set_title("work-precision, quasi-static stop (xi_inf)")
    ax.set_xlim(max(c["max_rel_err"] for c in engine + scipy_cfgs) * 3, 1e-15)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7.5, loc="upper left")
    lv = [r["level"] for r in table if r["speedup"]]
    ax2.semilogx(lv, [r["speedup"] for r in table if r["speedup"]], "ko-", label="cheapest config with error <= level")
    li = [(r["level"], r["speedup_interpolated"]) for r in table if r["speedup_interpolated"]]
    if li:
        ax2.semilogx(*zip(*li), "k--", alpha=0.6, label="log-log interpolated frontiers")
    ln = [(r["level"], r["speedup"]) for r in table_nc if r["speedup"]]
    if ln:
        ax2.semilogx(*zip(*ln), "o:", color="0.5", ms=4, label="same, costly corner left out (5 problems)")
    ax2.axhline(TARGET_SPEEDUP, color="C3", lw=1, label=f"target {TARGET_SPEEDUP:g}x")
    ax2.axhline(GOAL_SPEEDUP, color="C2", lw=1, label=f"goal {GOAL_SPEEDUP:g}x")
    ax2.set_yscale("log")
    ax2.invert_xaxis()
    ax2.set_xlabel("error level")
    ax2.set_ylabel("best scipy / best engine, time per trajectory per core")
    ax2.set_title("speed-up")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.set_ylim(top=max(6 * GOAL_SPEEDUP, ax2.get_ylim()[1]))
    ax2.legend(fontsize=7.5, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def fmt(x, f="{:.3g}"):
    return "-" if x is None else f.format(x)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--quick", action="store_true", help="a dozen configurations, one timing each (a smoke run)")
    mode.add_argument("--half", action="store_true", help="every other configuration, one pass (~3 min)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--no-png", action="store_true")
    ap.add_argument("--no-threads2", action="store_true", help="skip the 2-thread engine timings")
    ap.add_argument("--replot", action="store_true", help="only redraw the PNG from the JSON at --out")
    args = ap.parse_args(argv)
    if args.replot:
        d = json.loads(args.out.read_text())
        sm = d["summary"]
        plot(d["engine"], d["scipy"], sm["speedup_by_error_level"], sm["speedup_by_error_level_without_corner"],
             d["reference"], args.out.with_suffix(".png"))
        return
    warnings.simplefilter("ignore", RuntimeWarning)
    t_start = time.perf_counter()
    # short calls, several of them: the best one escapes other processes' load
    repeats = 1 if args.quick else 3 if args.half else 7
    # batches of thousands of points at loose rtol, as in a sweep (run_sweep's chunks are 4096)
    target_s = 0.002 if args.quick else 0.02
    probes = 1 if args.quick else 3
    passes = 1 if args.quick or args.half else 2
    threads2 = not args.no_threads2 and numba.config.NUMBA_NUM_THREADS >= 2

    load0 = loadavg()
    digest0 = sweep_digest()
    pbs = problems()
    print(f"[1/4] reference (rtol {REF_RTOL:g}, closed form where m2 = 0)", flush=True)
    tail_checked = check_tail_ok()
    refs = build_reference(pbs)
    for r in refs:
        print(f"  {r['name']:<26} xi_inf {r['xi_inf']:.15g}  1e-12 vs ref {r['rel_diff_1e-12_vs_ref']:.1e}  "
              f"engine-form vs ref {r['rel_diff_engine_form_vs_ref']:.1e}", flush=True)

    print("[2/4] engine configurations (1 thread" + (", then 2 threads" if threads2 else "") + ")", flush=True)
    engine, handles = [], []
    for label, fam, kw_for in engine_configs(args.half, args.quick):
        c, h = run_engine_config(pbs, refs, label, fam, kw_for, threads2, target_s, repeats, probes)
        engine.append(c)
        handles.append(h)
        print(f"  {label:<24} err {c['max_rel_err']:9.2e}  {c['us_per_traj']:9.2f} us/traj  steps mean "
              f"{c['mean_steps_fine']:7.0f}  est/true {fmt(c['estimate_over_true_min'])}.."
              f"{fmt(c['estimate_over_true_max'])}  {','.join(c['statuses'])}", flush=True)
    for k in range(1, passes):  # later passes, minutes apart: the best of them escapes bursts of load
        print(f"  engine timing pass {k + 1} of {passes}", flush=True)
        for i, (c, h) in enumerate(zip(engine, handles)):
            for row, (scene, plan) in zip(c["per_problem"], h):
                time_row(row, scene, plan, threads2, target_s, repeats)
            engine[i] = summarise(c["label"], c["family"], c["per_problem"], refs)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)

    print(f"[3/4] scipy DOP853 / LSODA / Radau, rtol {RTOLS_SCIPY[0]:g}..{RTOLS_SCIPY[-1]:g}", flush=True)
    scipy_cfgs, skipped = run_scipy(pbs, refs, 1 if args.quick else 2 if args.half else 7, passes,
                                    RTOLS_SCIPY_QUICK if args.quick else RTOLS_SCIPY[::2] if args.half
                                    else RTOLS_SCIPY)

    print("[4/4] summary", flush=True)
    table, auto = summary(engine, scipy_cfgs)
    rest = [pb["name"] for pb in pbs if pb["name"] != CORNER]
    table_nc, _ = summary([subset(c, rest) for c in engine], [subset(c, rest) for c in scipy_cfgs])
    table_64, _ = summary([c for c in engine if "float32" not in c["family"]], scipy_cfgs)
    result = {
        "what": "work-precision: achieved xi_inf error vs time per trajectory, engine configurations and scipy",
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "machine": machine_info(),
        "quick": args.quick, "half": args.half,
        "problems": [{k: v for k, v in pb.items() if k != "params"} | {"params": pb["params"].as_dict()}
                     for pb in pbs],
        "reference": refs,
        "method": {
            "error": "max over problems of |xi_inf/ref - 1|; per problem in per_problem",
            "time": "mean over problems of the per-problem CPU time per trajectory (time.process_time; the "
                    "best wall time is kept beside it as *_wall); engine: best of "
                    f"{repeats} calls of sweep.protocols.stop.chunk.execute on the problem repeated N times "
                    f"(N so that a call "
                    f"lasts ~{target_s:g} s) in each of {passes} passes over all configurations, best of all; 1 thread;"
                    " scipy: best of 7 single trajectories (3 if one takes > 50 ms, 1 if > 1 s), plus 3 more per later "
                    "pass; 2 threads: us_per_traj_per_core_2threads = 2 x best wall / N",
            "sweep_source_digest_start_end": [digest0, sweep_digest()],
            "engine_work": "each point solved twice (Richardson pair: coarse mesh, then the same mesh halved); "
                           "steps_fine = steps of the returned fine run; xi_inf_error = the engine's estimate",
            "rk4_fixed_h_rtol": "scene rtol matched to h (rtol_for_step: the plan's rule inverted, clipped to "
                                "[1e-10, 1e-2], [1e-5, 1e-2] for float32); it only sets the tail test and status",
            "engine_rtol_range": "Scene accepts 1e-10 <= rtol <= 1e-2: rtol 1e-11 is refused, so engine "
                                 "adaptive/auto configurations stop at 1e-10",
            "scipy_formulation": "the engine's: dxi/ds = exp(-(chi xi + mu1 u + m2 u^2)/A), u = s - xi, xi(0) = 0 "
                                 "in contact-age time s; scipy OdeSolver classes stepped until the engine's tail "
                                 "test (plain-Python copy tail_ok, verified) passes at a step end with tolerance "
                                 f"rtol xi + {TAIL_ATOL:g}, then + the engine's closed-form tail_slip "
                                 "(benchmarks/_common.py scipy_point, for DOP853, LSODA and Radau); "
                                 f"atol = {ATOL_FACTOR:g} rtol; LSODA and Radau get the analytic Jacobian",
            "tail_test_copy_checked_inputs": tail_checked,
            "reference": f"closed form where m2 = 0; else tests/reference.py at rtol {REF_RTOL:g}; "
                         "uncertainty_estimate per problem = disagreement with the independent engine-form "
                         "DOP853 solution at rtol 1e-13 (or 1e-15 for the closed form)",
        },
        "engine": engine,
        "scipy": scipy_cfgs,
        "scipy_skipped": skipped,
        "diagnostics": diagnostics(engine, scipy_cfgs, table),
        "summary": {"speedup_by_error_level": table, "auto_vs_fastest": auto,
                    "speedup_by_error_level_without_corner": table_nc,
                    "speedup_by_error_level_float64_only": table_64,
                    "targets": {"speedup_per_core": TARGET_SPEEDUP, "goal_speedup": GOAL_SPEEDUP,
                                "auto_within": TARGET_AUTO},
                    "speedup_target_met_all_levels": all(r["meets_target"] for r in table),
                    "speedup_goal_met_all_levels": all(r["meets_goal"] for r in table),
                    "auto_target_met_all_rtols": all(r["within_target"] for r in auto if r["rtol"] <= 1e-3)},
        "elapsed_s": None,
        "loadavg_start_end": [load0, loadavg()],
    }
    result["elapsed_s"] = time.perf_counter() - t_start
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1, default=float) + "\n")
    if not args.no_png:
        try:
            plot(engine, scipy_cfgs, table, table_nc, refs, args.out.with_suffix(".png"))
        except ImportError:
            print("matplotlib not installed: no PNG")

    print(f"\n{'level':>7} {'engine best (1 thread)':>24} {'us':>8} {'scipy best':>24} {'us':>7} {'speedup':>8} "
          f"{'interp':>7} {'2thr/core':>9} {'no corner':>9} {'float64':>8}")
    for r, rn, r64 in zip(table, table_nc, table_64):
        print(f"{r['level']:7.0e} {fmt(r['engine_best'], '{}'):>24} {fmt(r['engine_us'], '{:.2f}'):>8} "
              f"{fmt(r['scipy_best'], '{}'):>24} {fmt(r['scipy_us'], '{:.0f}'):>7} {fmt(r['speedup'], '{:.0f}x'):>8} "
              f"{fmt(r['speedup_interpolated'], '{:.0f}x'):>7} {fmt(r.get('speedup_per_core_2threads'), '{:.0f}x'):>9} "
              f"{fmt(rn['speedup'], '{:.0f}x'):>9} {fmt(r64['speedup'], '{:.0f}x'):>8}"
              f"{'' if r['meets_target'] else '  MISS'}")
    print(f"\n{'rtol':>7} {'auto':>6} {'us':>8} {'err':>8} {'fastest float64 meeting rtol':>28} {'us':>8} {'ratio':>6} "
          f"{'incl. float32':>24} {'ratio':>6} {'certified':>9}")
    for r in auto:
        print(f"{r['rtol']:7.0e} {fmt(r['auto_method'], '{}'):>6} {fmt(r['auto_us'], '{:.2f}'):>8} "
              f"{fmt(r['auto_err'], '{:.1e}'):>8} {fmt(r['fastest_meeting_rtol'], '{}'):>28} "
              f"{fmt(r['fastest_us'], '{:.2f}'):>8} {fmt(r['auto_over_fastest'], '{:.2f}'):>6} "
              f"{fmt(r['fastest_incl_float32'], '{}'):>24} {fmt(r['auto_over_fastest_incl_float32'], '{:.2f}'):>6} "
              f"{fmt(r['auto_over_fastest_status_ok'], '{:.2f}'):>9}"
              f"{'' if r['within_target'] else '  MISS'}")
    s = result["summary"]
    print(f"\nspeed-up >= {TARGET_SPEEDUP:g}x at every level 1e-3..1e-10: {s['speedup_target_met_all_levels']}; "
          f"auto within {TARGET_AUTO}x at every rtol <= 1e-3: {s['auto_target_met_all_rtols']}")
    print(f"wrote {args.out} ({result['elapsed_s']:.0f} s)")


if __name__ == "__main__":
    main()
