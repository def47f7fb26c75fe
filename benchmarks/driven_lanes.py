#!/usr/bin/env python
"""The driven scene in lanes against a base tree (issue 35): speed, regimes and observables, A/B in one run.

    python benchmarks/driven_lanes.py [--base DIR] [--quick] [--repeats N] [--out benchmarks/results/driven_lanes.json]

The grid is the issue's: preset sample2; V 20 values log-spaced over 0.1..5 um/s; K/M 40 values log-spaced from
0.3 x the smallest to 3 x the largest quasi-static (K/M)_c over those V (--quick: every 4th K/M and V). Models
"quasistatic" and "auto", 1 thread and (quasi-static) all threads. The deep inertial stick-slip grid (model
"inertial", 1 thread): V 10 values log-spaced over 0.1..5 um/s, K/M 10 values log-spaced over 0.05..0.5 x the
smallest (K/M)_c over those V (0.0034..0.5 x each V's own; gamma/A 2e-7..5e-4), every point stick-slip (--quick:
every 2nd K/M and V).

Each tree (``--base``, default /tmp/driven_base, a ``git worktree add`` of the commit before the lanes; and the tree
this script is in) is measured in fresh subprocesses of this script (``--worker``) with PYTHONPATH = the tree (the
worker checks that ``import sweep`` resolved there) and a numba cache of its own that persists between runs, so the
warm-up call loads kernels rather than compiling them. A worker builds the plan, calls the driven chunk once
untimed, then times ``--timed-calls`` calls (best kept), and saves its per-point outputs. Base and new alternate
(base, new, base, new, ...) ``--repeats`` times; each figure is the best wall time over them; the load average is
recorded with each. Where the base tree is missing, the tree is compared with itself (the smoke run).

Numbers: regimes per class and the points whose regime moved (steady, stick_slip and runaway must keep theirs;
undecided and neutral may move), growth rates where both closed >= 2 cycles (|dg| x period), stick-slip amplitudes
(relative), and steps. Both trees' quasi-static outputs are also compared with a reference: the new tree with the
driven stepper at 1e-12 (scene rtol REFERENCE_RTOL). Writes JSON (no PNG) and prints a summary.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DEFAULT_OUT = HERE / "results" / "driven_lanes.json"
DEFAULT_BASE = Path("/tmp/driven_base")
FIELDS = ("regime", "status", "growth_rate", "period", "amplitude", "cycles", "steps")
REGIMES = ("steady", "stick_slip", "neutral", "runaway", "undecided")
TARGETS = {"quasistatic_1t": 10.0, "auto_1t": 20.0, "deep_inertial_1t": 20.0}


def issue_grid(n_v: int = 20, n_k: int = 40, deep: bool = False):
    """(preset sample2, K/M [s-2], V [m/s]) of the issue's driven grid: V n_v values log-spaced over 0.1..5 um/s,
    K/M n_k values log-spaced from 0.3 x the smallest to 3 x the largest quasi-static (K/M)_c over those V; ``deep``:
    from 0.05 to 0.5 x the smallest (all stick-slip)."""
    import sweep
    from sweep import physics

    p = sweep.presets["sample2"]
    V = np.logspace(-7, np.log10(5e-6), n_v)
    kc = physics.hopf_K_over_M(V, p.A, p.m1, p.m2, p.D0, p.V0)
    lo, hi = (0.05 * np.nanmin(kc), 0.5 * np.nanmin(kc)) if deep else (0.3 * np.nanmin(kc), 3.0 * np.nanmax(kc))
    return p, np.logspace(np.log10(lo), np.log10(hi), n_k), V


def add_worker_arguments(ap: argparse.ArgumentParser, default_out: Path) -> None:
    """The options a driven benchmark and its ``--worker`` subprocesses share."""
    ap.add_argument("--out", type=Path, default=default_out)
    ap.add_argument("--no-png", action="store_true", help="accepted for uniformity (this script draws nothing)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--model", default="quasistatic", help=argparse.SUPPRESS)
    ap.add_argument("--threads", type=int, default=1, help=argparse.SUPPRESS)
    ap.add_argument("--save", help=argparse.SUPPRESS)


def worker(args) -> None:
    """One measurement in this process (PYTHONPATH = the tree): JSON on stdout, outputs into args.save."""
    import numba

    import sweep
    from sweep.protocols.driven.chunk import driven_chunk

    assert Path(sweep.__file__).resolve().is_relative_to(Path(args.tree).resolve()), sweep.__file__
    deep = args.grid == "deep"
    p, KM, V = issue_grid(10, 10, deep=True) if deep else issue_grid()
    if args.quick:
        KM, V = (KM[::2], V[::2]) if deep else (KM[::4], V[::4])
    rtol = {} if args.rtol is None else {"rtol": args.rtol}
    scene = sweep.Scene(protocol="driven", params=p, K_over_M=KM, V=V, model=args.model, **rtol)
    numba.set_num_threads(args.threads)
    plan = sweep.make_plan(scene)
    compute = driven_chunk(scene, plan)
    points = np.arange(plan.n_points)
    compute(points)  # kernels loaded (or compiled) and warm
    walls = []
    out = None
    for _ in range(args.timed_calls):
        t0 = time.perf_counter()
        out = compute(points)
        walls.append(time.perf_counter() - t0)
    np.savez(args.save, **{f: np.asarray(out[f]) for f in FIELDS})
    print(json.dumps({"walls": walls, "points": int(plan.n_points), "threads": args.threads,
                      "numba_threads": numba.config.NUMBA_NUM_THREADS, "sweep": sweep.__file__}))


def run_worker(tree: Path, model: str, threads: int, grid: str, quick: bool, timed: int, save: Path,
               cache: Path, rtol: float | None = None) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree), "NUMBA_CACHE_DIR": str(cache)}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", "--tree", str(tree), "--model", model,
           "--threads", str(threads), "--grid", grid, "--timed-calls", str(timed), "--save", str(save)]
    cmd += ["--quick"] * quick + ([] if rtol is None else ["--rtol", repr(rtol)])
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tempfile.gettempdir())
    if proc.returncode:
        raise RuntimeError(f"worker failed ({' '.join(cmd)}):\n{proc.stderr[-4000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def compare(base: dict, new: dict) -> dict:
    """Regimes, moved points and observables of ``new`` against ``base`` (per-point arrays)."""
    rb, rn = base["regime"], new["regime"]
    moved = rb != rn
    firm = np.isin(rb, [0, 1, 3])  # steady, stick_slip, runaway must keep their regime
    both = (base["cycles"] >= 2) & (new["cycles"] >= 2) & np.isfinite(base["growth_rate"]) & ~moved
    g = np.abs(new["growth_rate"][both] - base["growth_rate"][both]) * base["period"][both]
    slip = (rb == 1) & ~moved
    amp = np.abs(new["amplitude"][slip] / base["amplitude"][slip] - 1.0)
    count = lambda r: {name: int((r == i).sum()) for i, name in enumerate(REGIMES)}  # noqa: E731
    return {"regimes_base": count(rb), "regimes_new": count(rn), "moved": int(moved.sum()),
            "moved_firm": int((moved & firm).sum()),
            "moved_pairs": [[REGIMES[a], REGIMES[b]] for a, b in zip(rb[moved], rn[moved])],
            "growth_compared": int(both.sum()),
            "max_growth_diff_per_cycle": float(g.max()) if g.size else None,
            "max_amplitude_rel_diff": float(amp.max()) if amp.size else None,
            "steps_base": int(base["steps"].sum()), "steps_new": int(new["steps"].sum())}


REFERENCE_RTOL = 1e-10
"""Scene rtol of the reference run (the driven stepper at 1e-12: sweep.accuracy.driven_stepper_rtol)."""


def against_reference(out: dict, ref: dict) -> dict:
    """Errors of one tree's quasi-static outputs against the reference run's (the new tree at REFERENCE_RTOL):
    stick-slip amplitudes and periods (relative), growth rates where both closed the same number of cycles."""
    slip = (out["regime"] == 1) & (ref["regime"] == 1)
    amp = np.abs(out["amplitude"][slip] / ref["amplitude"][slip] - 1.0)
    per = np.abs(out["period"][slip] / ref["period"][slip] - 1.0)
    same = (out["cycles"] == ref["cycles"]) & (out["cycles"] >= 2) & np.isfinite(ref["growth_rate"])
    g = np.abs(out["growth_rate"][same] - ref["growth_rate"][same]) * ref["period"][same]
    return {"regimes_differ": int((out["regime"] != ref["regime"]).sum()), "stick_slip_compared": int(slip.sum()),
            "amplitude_rel_err_max": float(amp.max()), "amplitude_rel_err_median": float(np.median(amp)),
            "period_rel_err_max": float(per.max()), "growth_compared": int(same.sum()),
            "growth_err_per_cycle_max": float(g.max())}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--base", type=Path, default=DEFAULT_BASE)
    ap.add_argument("--quick", action="store_true", help="every 4th K/M and V, 1 repeat, 1 timed call")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--timed-calls", type=int, default=3)
    add_worker_arguments(ap, DEFAULT_OUT)
    ap.add_argument("--tree", help=argparse.SUPPRESS)
    ap.add_argument("--grid", default="issue", choices=("issue", "deep"), help=argparse.SUPPRESS)
    ap.add_argument("--rtol", type=float, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return worker(args)
    sys.path.insert(0, str(HERE))
    import _common as common

    t_start = time.perf_counter()
    base = args.base if (args.base / "sweep" / "__init__.py").is_file() else ROOT
    trees = {"base": base, "new": ROOT}
    repeats, timed = (1, 1) if args.quick else (args.repeats, args.timed_calls)
    n_all = os.cpu_count() or 1
    configs = [("quasistatic", 1, "issue"), ("quasistatic", n_all, "issue"), ("auto", 1, "issue"),
               ("inertial", 1, "deep")]
    work = Path(tempfile.mkdtemp(prefix="driven_lanes_"))
    caches = {name: Path(tempfile.gettempdir()) / f"driven_lanes_cache_{name}_{abs(hash(str(t))) % 10**8}"
              for name, t in trees.items()}
    figures = {}
    numbers = {}
    for model, threads, grid in configs:
        key = f"{model}_{threads}t" if grid == "issue" else f"{grid}_{model}_{threads}t"
        rows = {name: [] for name in trees}
        for _ in range(repeats):
            for name, tree in trees.items():
                save = work / f"{key}_{name}.npz"
                load0 = common.loadavg()
                r = run_worker(tree, model, threads, grid, args.quick, timed, save, caches[name])
                rows[name].append({**r, "loadavg": [load0, common.loadavg()]})
        best = {name: min(min(r["walls"]) for r in rows[name]) for name in trees}
        n = rows["new"][0]["points"]
        figures[key] = {"points": n, "threads": threads, "model": model, "grid": grid, "rows": rows,
                        **{f"{name}_points_per_s_per_core": n / (best[name] * threads) for name in trees},
                        "speedup_new_over_base": best["base"] / best["new"]}
        outs = {name: dict(np.load(work / f"{key}_{name}.npz")) for name in trees}
        numbers[key] = compare(outs["base"], outs["new"])
        print(f"{key:16s} base {best['base']:.3f} s  new {best['new']:.3f} s  x{best['base'] / best['new']:.2f}  "
              f"moved {numbers[key]['moved']} (firm {numbers[key]['moved_firm']})  growth diff "
              f"{numbers[key]['max_growth_diff_per_cycle']}", flush=True)
        if key == "quasistatic_1t":  # both trees' accuracy: against the new tree at a tolerance 100x tighter
            save = work / "reference.npz"
            run_worker(ROOT, model, 1, grid, args.quick, 1, save, caches["new"], rtol=REFERENCE_RTOL)
            ref = dict(np.load(save))
            numbers[key]["against_reference"] = {name: against_reference(outs[name], ref) for name in trees}
            print("  against the reference: " + "; ".join(
                f"{name} amplitude {r['amplitude_rel_err_max']:.1e} max, {r['amplitude_rel_err_median']:.1e} median"
                for name, r in numbers[key]["against_reference"].items()), flush=True)
    result = {
        "benchmark": "benchmarks/driven_lanes.py" + (" --quick" if args.quick else ""),
        "quick": args.quick,
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "machine": common.machine_info(), "versions": common.versions(),
        "trees": {name: str(t) for name, t in trees.items()},
        "base_commit": subprocess.run(["git", "rev-parse", "HEAD"], cwd=base, capture_output=True,
                                      text=True).stdout.strip(),
        "new_commit": common.git_commit(), "new_tree_dirty": common.sweep_tree_dirty(),
        "settings": {"repeats": repeats, "timed_calls": timed, "grid": "sample2, V 20 x K/M 40 (issue 35)"
                     + (", every 4th" if args.quick else ""),
                     "deep_grid": "sample2, V 10 x K/M 10 (0.05..0.5 x the smallest (K/M)_c), model inertial"
                     + (", every 2nd" if args.quick else "")},
        "figures": figures, "numbers": numbers,
        "targets": {k: {"target": v, "speedup": figures[k]["speedup_new_over_base"],
                        "met": figures[k]["speedup_new_over_base"] >= v} for k, v in TARGETS.items()},
    }
    common.write_result(result, args.out, t_start)


if __name__ == "__main__":
    main()
