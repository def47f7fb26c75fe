#!/usr/bin/env python
"""The driven scene on a 1e5-point grid: all threads against one (issue 35 target: >= 1.8x on 2 threads).

    python benchmarks/driven_scaling.py [--models quasistatic,auto] [--repeats 3] [--quick]
                                        [--out benchmarks/results/driven_scaling.json]

The grid spans the issue's ranges (preset sample2; V log-spaced over 0.1..5 um/s; K/M log-spaced from 0.3 x the
smallest to 3 x the largest quasi-static (K/M)_c over those V) at 400 V x 250 K/M = 1e5 points (--quick: 40 x 25).
Each measurement runs in a fresh subprocess of this script (``--worker``): it builds the plan, calls the driven chunk
(:func:`sweep.protocols.driven.chunk.driven_chunk`, the code a run's chunks call) once on a 1 % subsample untimed
(kernels loaded or compiled), then times one call on every point. One thread and all threads alternate ``--repeats``
times; each figure is the best wall time; the load average is recorded with each. The regimes of the two thread
counts must agree point for point (a point's numbers do not depend on its lane or thread). Beside them, in every
repeat, the machine's own gain from a second thread (auto_cost.machine_ceiling: a loop that shares nothing, alone and
twice at once), the ceiling of any 2-thread gain in that run. Writes JSON.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from driven_lanes import add_worker_arguments

HERE = Path(__file__).resolve().parent
DEFAULT_OUT = HERE / "results" / "driven_scaling.json"
TARGET = 1.8
SHAPE = (250, 400)  # K/M x V


def grid(quick: bool):
    """(preset, K/M, V) of the 1e5-point grid (driven_lanes.issue_grid at SHAPE; --quick 25 x 40)."""
    from driven_lanes import issue_grid

    n_k, n_v = (25, 40) if quick else SHAPE
    return issue_grid(n_v, n_k)


def worker(args) -> None:
    import numba

    import sweep
    from sweep.protocols.driven.chunk import driven_chunk

    p, KM, V = grid(args.quick)
    numba.set_num_threads(args.threads)
    scene = sweep.Scene(protocol="driven", params=p, K_over_M=KM, V=V, model=args.model)
    plan = sweep.make_plan(scene)
    compute = driven_chunk(scene, plan)
    points = np.arange(plan.n_points)
    compute(points[::100])  # kernels loaded (or compiled) and warm
    t0 = time.perf_counter()
    out = compute(points)
    wall = time.perf_counter() - t0
    np.save(args.save, np.asarray(out["regime"]))
    print(json.dumps({"wall": wall, "points": int(plan.n_points), "threads": args.threads,
                      "steps": int(np.asarray(out["steps"]).sum())}))


def run_worker(model: str, threads: int, quick: bool, save: Path) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", "--model", model, "--threads", str(threads),
           "--save", str(save)] + (["--quick"] * quick)
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=tempfile.gettempdir())
    if proc.returncode:
        raise RuntimeError(f"worker failed ({' '.join(cmd)}):\n{proc.stderr[-4000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", default="quasistatic")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="a 1,000-point grid, one repeat")
    add_worker_arguments(ap, DEFAULT_OUT)
    args = ap.parse_args(argv)
    if args.worker:
        return worker(args)
    sys.path.insert(0, str(HERE))
    import _common as common

    t_start = time.perf_counter()
    n_all = common.usable_cpus()
    repeats = 1 if args.quick else args.repeats
    work = Path(tempfile.mkdtemp(prefix="driven_scaling_"))
    from auto_cost import machine_ceiling

    figures, ceilings = {}, []
    for model in args.models.split(","):
        rows = {1: [], n_all: []}
        for _ in range(repeats):
            ceilings.append(machine_ceiling())
            for threads in rows:
                load0 = common.loadavg()
                r = run_worker(model, threads, args.quick, work / f"{model}_{threads}.npy")
                rows[threads].append({**r, "loadavg": [load0, common.loadavg()]})
        best = {th: min(r["wall"] for r in rows[th]) for th in rows}
        same = bool(np.array_equal(np.load(work / f"{model}_1.npy"), np.load(work / f"{model}_{n_all}.npy")))
        n = rows[1][0]["points"]
        figures[model] = {"points": n, "threads": n_all, "rows": {str(k): v for k, v in rows.items()},
                          "best_wall_s": {str(k): v for k, v in best.items()},
                          "points_per_s": {str(k): n / v for k, v in best.items()},
                          "speedup_all_threads": best[1] / best[n_all], "regimes_equal": same,
                          "target": TARGET, "met": best[1] / best[n_all] >= TARGET}
        print(f"{model:12s} {n} points: 1 thread {best[1]:.2f} s, {n_all} threads {best[n_all]:.2f} s, "
              f"x{best[1] / best[n_all]:.2f}, regimes equal {same}", flush=True)
    result = {"benchmark": "benchmarks/driven_scaling.py" + (" --quick" if args.quick else ""), "quick": args.quick,
              "machine": common.machine_info(), "versions": common.versions(), "git_commit": common.git_commit(),
              "sweep_tree_dirty": common.sweep_tree_dirty(),
              "settings": {"repeats": repeats, "grid": f"sample2, K/M {SHAPE[0]} x V {SHAPE[1]} over the issue's "
                           "ranges" + (" (quick: 25 x 40)" if args.quick else "")},
              "figures": figures, "machine_ceiling_rows": ceilings,
              "machine_two_threads_over_one": 2 * min(c["alone_s"] for c in ceilings)
              / min(c["together_s"] for c in ceilings)}
    common.write_result(result, args.out, t_start)


if __name__ == "__main__":
    main()
