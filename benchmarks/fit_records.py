"""Fitting laboratory records (issue 34 targets): one 1,000-sample velocity-step record (a, b, Dc, mu0 free, k fixed,
noise estimated) fitted warm, 100 such records in one call (per record: noise draws on one record's times, and
records of their own times), and scipy's least_squares over solve_ivp
(LSODA) on the same record from the same start at the same rtol, both with 95 % intervals (sweep: profile
likelihoods; scipy: from its Jacobian), both against the Fisher (linearised) half-widths 1.96 sigma sqrt(diag
(J^T J)^-1) from the scipy reference's Jacobian (tests/reference_records.py, Radau rtol 1e-10, central differences,
relative step 1e-4: steps 1e-2..1e-5 agree to 3e-5 of the widths) at the truth.

scipy's Jacobian: forward differences with diff_step = sqrt(rtol) = 1e-3 (its default step, ~1.5e-8, is below the
integrator's noise at rtol 1e-6: its intervals came out 5x too narrow for a and b; 1e-4..1e-2 give intervals within
4 % of Fisher). Ratios: ``speedup_vs_scipy`` = scipy's fit over sweep.fit as users call it (global stage, least
squares, profiles); ``speedup_least_squares_stage`` = scipy's fit over sweep.fit's least-squares stage alone (from
its global stage's best point), and the seconds per forward solve of each side say where the time goes.

The issue's comparison, both sides from START at rtol 1e-6 with 95 % intervals: sweep.fit(search="local") (no global
stage; profiles as always): ``speedup_local_one_record`` = scipy's fit of the record over sweep's of the same
record; ``speedup_local_per_record`` = scipy's mean time per record (SCIPY_SUBSAMPLE of the records of their own
times, each fitted alone, the best of the repeats as for sweep) over sweep's time per record when all of them are
fitted in one call (each its own parameter set, the best of the repeats). A record's steps and slip events are
found once and kept on it (its data do not change), so the repeats fit records whose steps and events are known:
``hundred_records_own_times_local_fresh_s`` is the first call on new Record objects of the same data (the steps
found from the displacement and the events looked for in that call), ``speedup_local_per_record_fresh`` its ratio.
``local_own_times_split_s`` says where such a call's time goes (a separate, untimed run on new Record objects: step
detection from the displacement, the records' slip-event search and the rest of the events check timed by wrapping
their functions).

    python benchmarks/fit_records.py [--repeats 3] [--out benchmarks/results/fit_records.json]

``--quick``: 5 records, one repeat (a smoke run). Targets: one record < 0.5 s warm, 100 records < 10 s, >= 50x scipy.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares
from scipy.stats import t as student

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))
import _common as common  # noqa: E402
from reference_records import record_reference  # noqa: E402

import sweep  # noqa: E402
from sweep.fit.records import Record  # noqa: E402

TRUE = (0.01, 0.015, 1e-5, 0.6)
START = (0.008, 0.012, 2e-5, 0.6)
K, NOISE, V, DUR = 2e3, 2e-4, (1e-6, 1e-5), (20.0, 40.0)
RTOL = 1e-6
DIFF_STEP = 1e-3
"""scipy's relative finite-difference step: sqrt(RTOL) (module docstring)."""
SCIPY_SUBSAMPLE = 10
"""Records of their own times that scipy fits one by one for its time per record (module docstring)."""


def scipy_model(theta, t, V0=1e-6):
    """mu(t) of the record by solve_ivp (LSODA, rtol RTOL) per segment, in (mu, ln theta)."""
    a, b, Dc, mu0 = theta
    vel = lambda mu, lth: V0 * np.exp((mu - mu0 - b * (np.log(V0 / Dc) + lth)) / a)  # noqa: E731

    def rhs(_, y, v_lp):
        v = vel(y[0], y[1])
        return [K * (v_lp - v), (1.0 - v * np.exp(y[1]) / Dc) / np.exp(y[1])]

    y = np.array([mu0 + (a - b) * np.log(V[0] / V0), np.log(Dc / V[0])])
    out, start = np.empty(t.size), 0.0
    for s, (v_lp, T) in enumerate(zip(V, DUR)):
        pick = np.flatnonzero((t >= start) & ((t < start + T) if s < len(V) - 1 else (t <= start + T)))
        sol = solve_ivp(rhs, (0.0, T), y, method="LSODA", rtol=RTOL, atol=[1e-12, 1e-10], args=(v_lp,),
                        t_eval=np.append(t[pick] - start, T))
        out[pick], y, start = sol.y[0, :-1], sol.y[:, -1], start + T
    return out


def scipy_fit(t, mu):
    scale = np.array(START)
    res = least_squares(lambda z: scipy_model(z * scale, t) - mu, np.ones(4), method="trf", x_scale=1.0,
                        diff_step=DIFF_STEP)
    dof = t.size - 4
    s2 = 2 * res.cost / dof
    cov = np.linalg.inv(res.jac.T @ res.jac) * s2
    half = student.ppf(0.975, dof) * np.sqrt(np.diag(cov))
    return res.x * scale, half * scale, res.nfev, res.njev


def sweep_solve_seconds(rec: Record) -> dict[str, float]:
    """Seconds of one friction_at call at TRUE as the least squares run it (without estimates: rtol 10 RTOL, its
    tighter run at RTOL/10), for 1 set and per set for 5 (a forward-difference round of 4 parameters)."""
    from sweep.fit.segments import load_history
    from sweep.protocols.history.forward import friction_at

    load, out = load_history(rec), {}
    for n in (1, 5):
        lab = {"A": np.full(n, TRUE[0]), "m1": np.full(n, TRUE[1] - TRUE[0]), "m2": np.zeros(n),
               "D0": np.full(n, TRUE[2]), "m0": np.full(n, TRUE[3]), "V0": np.full(n, 1e-6), "K_over_M": K * 9.81}
        friction_at(lab, load, rec.t - rec.t[0], rtol=10 * RTOL)
        t0 = time.perf_counter()
        for _ in range(20):
            friction_at(lab, load, rec.t - rec.t[0], rtol=10 * RTOL)
        out[f"sets_{n}_per_set_s"] = (time.perf_counter() - t0) / 20 / n
    return out


def fisher_half_widths(t):
    """1.96 NOISE sqrt(diag (J^T J)^-1) at TRUE, J from the reference by central differences (relative step 1e-4)."""
    theta = np.array(TRUE)
    jac = np.empty((t.size, theta.size))
    for j in range(theta.size):
        h = 1e-4 * abs(theta[j])
        up, down = theta.copy(), theta.copy()
        up[j], down[j] = theta[j] + h, theta[j] - h
        jac[:, j] = (record_reference(*up, K, list(V), list(DUR), t)[0]
                     - record_reference(*down, K, list(V), list(DUR), t)[0]) / (2 * h)
    return 1.96 * NOISE * np.sqrt(np.diag(np.linalg.inv(jac.T @ jac)))


def coverage(ds, n_rec: int, free) -> float:
    """Fraction of (record, parameter) pairs whose 95 % interval holds the truth."""
    return float(np.mean([[float(ds[f"{n}_lower"][q]) <= v <= float(ds[f"{n}_upper"][q]) for n, v in zip(free, TRUE)]
                          for q in range(n_rec)]))


def local_split(own, free, params) -> dict[str, float]:
    """Seconds of one local fit of ``own`` (one call, on records new to it) by part: the stages the fit reports, the
    load histories (segments.load_history, called by the RecordStack: the steps found from the displacement), the
    records' slip-event search (events._record_finest, once per record, in the event stage or the verdicts) and the
    rest of the events check of the verdicts (events.record_events), each timed by wrapping it (its own time, less
    the wrapped calls inside it); the rest (noise, covariance, engine-error check, verdicts, Dataset) is the
    difference."""
    from sweep.fit import events, record_forward

    spent = {"step_detection": 0.0, "slip_event_search": 0.0, "events_check": 0.0}
    originals = {"step_detection": (record_forward, "load_history"), "slip_event_search": (events, "_record_finest"),
                 "events_check": (events, "record_events")}
    inside: list[float] = []  # per wrapped call in progress: the time of the wrapped calls inside it

    def wrap(key, fn):
        def timed(*a, **k):
            t0 = time.perf_counter()
            inside.append(0.0)
            try:
                return fn(*a, **k)
            finally:
                took = time.perf_counter() - t0
                spent[key] += took - inside.pop()
                if inside:
                    inside[-1] += took
        return timed

    saved = {key: getattr(mod, name) for key, (mod, name) in originals.items()}
    for key, (mod, name) in originals.items():
        setattr(mod, name, wrap(key, saved[key]))
    try:
        t0 = time.perf_counter()
        ds = sweep.fit(own, free=free, params=params, rtol=RTOL, per_data_set=True, search="local")
        total = time.perf_counter() - t0
    finally:
        for key, (mod, name) in originals.items():
            setattr(mod, name, saved[key])
    stages = json.loads(ds.attrs["fit_seconds"])
    out = {"total": total, **spent, **stages}
    out["rest"] = total - sum(v for k, v in out.items() if k != "total")
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="smoke run: 5 records instead of 100, one repeat")
    ap.add_argument("--out", default=str(HERE / "results" / "fit_records.json"))
    args = ap.parse_args(argv)
    n_rec, repeats = (5, 1) if args.quick else (100, args.repeats)
    load0, t_start = common.loadavg(), time.perf_counter()
    rng = np.random.default_rng(0)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 999))))
    mu, disp = record_reference(*TRUE, K, list(V), list(DUR), t)
    records = [Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=K, name=f"r{i}")
               for i in range(n_rec)]  # one history and times: one layout, the global grid solved once
    # records of their own times: the reference on a 1 ms grid (10 ms quick), interpolated
    dense = np.linspace(0.0, 60.0, 6001 if args.quick else 60001)
    mu_d, disp_d = record_reference(*TRUE, K, list(V), list(DUR), dense)  # (error ~ 1e-8, noise 2e-4)
    own = []
    for i in range(n_rec):
        ti = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 999))))
        own.append(Record(ti, np.interp(ti, dense, mu_d) + NOISE * rng.standard_normal(ti.size),
                          displacement=np.interp(ti, dense, disp_d), k=K, name=f"own{i}"))
    params = sweep.FrictionParams.from_lab(*START)
    free = ("a", "b", "Dc", "mu0")
    sweep.fit(records[0], free=free, params=params, rtol=RTOL)  # warm: compiled kernels loaded
    one, many, many_own, ref = [], [], [], []
    one_local, many_local = [], []
    sweep.fit(records[0], free=free, params=params, rtol=RTOL, search="local")
    fresh = []
    for _ in range(repeats):
        copies = [Record(r.t, r.mu, displacement=r.displacement, k=r.k, name=r.name) for r in own]
        t0 = time.perf_counter()
        sweep.fit(copies, free=free, params=params, rtol=RTOL, per_data_set=True, search="local")
        fresh.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        ds1_local = sweep.fit(records[0], free=free, params=params, rtol=RTOL, search="local")
        one_local.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        ds_own_local = sweep.fit(own, free=free, params=params, rtol=RTOL, per_data_set=True, search="local")
        many_local.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        ds1 = sweep.fit(records[0], free=free, params=params, rtol=RTOL)
        one.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        ds100 = sweep.fit(records, free=free, params=params, rtol=RTOL, per_data_set=True)
        many.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        ds_own = sweep.fit(own, free=free, params=params, rtol=RTOL, per_data_set=True)
        many_own.append(time.perf_counter() - t0)
    for _ in range(repeats):  # the best of as many repeats as sweep's
        t0 = time.perf_counter()
        best_sp, half_sp, nfev, njev = scipy_fit(t, records[0].mu)
        ref.append(time.perf_counter() - t0)
    fisher = fisher_half_widths(t)
    sub = own[:min(SCIPY_SUBSAMPLE, n_rec)]
    scipy_each = []
    for rec in sub:  # scipy per record, each of its own times fitted alone from START, the best of the repeats
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            scipy_fit(rec.t, rec.mu)
            times.append(time.perf_counter() - t0)
        scipy_each.append(min(times))
    split = local_split([Record(r.t, r.mu, displacement=r.displacement, k=r.k, name=r.name) for r in own], free,
                        params)
    ls_stage = json.loads(ds1.attrs["fit_seconds"])["least_squares"]
    ls_rounds = json.loads(ds1.attrs["fit_rounds"])["least_squares"] if "fit_rounds" in ds1.attrs else None
    t0 = time.perf_counter()
    scipy_model(np.array(TRUE), t)
    scipy_solve = time.perf_counter() - t0
    sweep_solve = sweep_solve_seconds(records[0])
    ok100 = int(np.sum(ds100["fit_status"].values == 0))
    cover = coverage(ds100, n_rec, free)
    per_record_local = min(many_local) / n_rec
    result = {
        "benchmark": "fit_records", "quick": bool(args.quick), "records": n_rec,
        "machine": common.machine_info(), "versions": common.versions(),
        "git_commit": common.git_commit(), "sweep_tree_dirty": common.sweep_tree_dirty(),
        "loadavg_start_end": [load0, common.loadavg()], "rtol": RTOL, "samples_per_record": int(t.size),
        "one_record_warm_s": min(one), "one_record_warm_s_all": one,
        "hundred_records_s": min(many), "hundred_records_s_all": many, "hundred_records_ok": ok100,
        "hundred_records_coverage_95": float(cover),
        "hundred_records_own_times_s": min(many_own), "hundred_records_own_times_s_all": many_own,
        "hundred_records_own_times_ok": int(np.sum(ds_own["fit_status"].values == 0)),
        "hundred_records_own_times_stage_s": json.loads(ds_own.attrs["fit_seconds"]),
        "scipy_least_squares_s": min(ref), "scipy_least_squares_s_all": ref, "scipy_nfev": int(nfev),
        "scipy_njev": int(njev),
        "scipy_diff_step": DIFF_STEP, "scipy_forward_solves": int(nfev + 4 * njev), "scipy_solve_s": scipy_solve,
        "speedup_vs_scipy": min(ref) / min(one),
        "sweep_solve_s": sweep_solve, "sweep_least_squares_stage_s": ls_stage, "sweep_least_squares_rounds": ls_rounds,
        "speedup_least_squares_stage": min(ref) / ls_stage,
        "sweep_best": {n: float(ds1[n][0]) for n in free},
        "sweep_half_width_95": {n: float(ds1[f"{n}_upper"][0] - ds1[f"{n}_lower"][0]) / 2 for n in free},
        "scipy_best": dict(zip(free, map(float, best_sp))), "scipy_half_width_95": dict(zip(free, map(float, half_sp))),
        "fisher_half_width_95_at_truth": dict(zip(free, map(float, fisher))),
        "sweep_over_fisher": {n: float(ds1[f"{n}_upper"][0] - ds1[f"{n}_lower"][0]) / 2 / f
                              for n, f in zip(free, fisher)},
        "scipy_over_fisher": {n: float(h / f) for n, h, f in zip(free, half_sp, fisher)},
        "one_record_local_s": min(one_local), "one_record_local_s_all": one_local,
        "one_record_local_rounds": json.loads(ds1_local.attrs["fit_rounds"]),
        "speedup_local_one_record": min(ref) / min(one_local),
        "hundred_records_own_times_local_s": min(many_local), "hundred_records_own_times_local_s_all": many_local,
        "per_record_local_s": per_record_local,
        "hundred_records_own_times_local_ok": int(np.sum(ds_own_local["fit_status"].values == 0)),
        "hundred_records_own_times_local_coverage_95": coverage(ds_own_local, n_rec, free),
        "hundred_records_own_times_local_function_evaluations_mean":
            float(np.mean(ds_own_local["function_evaluations"].values)),
        "local_own_times_split_s": split,
        "scipy_per_record_s": float(np.mean(scipy_each)), "scipy_per_record_s_all": scipy_each,
        "scipy_per_record_records": len(sub),
        "speedup_local_per_record": float(np.mean(scipy_each)) / per_record_local,
        "hundred_records_own_times_local_fresh_s": min(fresh), "hundred_records_own_times_local_fresh_s_all": fresh,
        "speedup_local_per_record_fresh": float(np.mean(scipy_each)) / (min(fresh) / n_rec),
        "sweep_local_best": {n: float(ds1_local[n][0]) for n in free},
        "sweep_local_half_width_95": {n: float(ds1_local[f"{n}_upper"][0] - ds1_local[f"{n}_lower"][0]) / 2
                                      for n in free},
        "sweep_local_over_fisher": {n: float(ds1_local[f"{n}_upper"][0] - ds1_local[f"{n}_lower"][0]) / 2 / f
                                    for n, f in zip(free, fisher)},
        "targets": {"one_record_s": 0.5, "hundred_records_s": 10.0, "speedup": 50.0},
    }
    common.write_result(result, Path(args.out), t_start, print_table=lambda r: print(json.dumps(
        {k: v for k, v in r.items() if k not in ("machine", "versions")}, indent=1)))


if __name__ == "__main__":
    main()
