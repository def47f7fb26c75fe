"""What model="auto" costs over model="quasistatic", and what a second thread gains, at 2e4 and 1e6 points.

    python benchmarks/auto_cost.py [--quick] [--out PATH]

Issue 17's targets: ``model="auto"`` at most 1.2x ``model="quasistatic"`` on the default scene and at 1e6 points;
2 threads at least 1.8x 1 thread on both. Each grid is the default scene's (sample2, K/M 1e3..1e6 x V 1e-7..1e-4,
rtol 1e-6; 1e6 points: 1000 x 1000 over the same ranges), run through ``sweep.run_sweep`` with no output file, after
one untimed warm-up call per model; best of ``--repeats`` calls per (model, threads), models alternated, in one
process (numba.set_num_threads). ``--quick``: 2e4 and 4e4 points, one repeat (a smoke run). Writes JSON with machine
info and the load average under benchmarks/results/.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numba
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _common import loadavg, machine_info, write_result  # noqa: E402

import sweep  # noqa: E402

DEFAULT_OUT = HERE / "results" / "auto_cost.json"
MODELS = ("quasistatic", "auto")


def scene(side: int | None, model: str) -> sweep.Scene:
    """The default scene (side None) or its ranges on a side x side grid, with ``model``."""
    base = dataclasses.replace(sweep.default_scene(), model=model)
    if side is None:
        return base
    return dataclasses.replace(base, K_over_M=np.logspace(3, 6, side), V=np.logspace(-7, -4, side))


def measure(side: int | None, threads: int, repeats: int) -> dict:
    """Best wall time per model at ``threads`` threads, the auto/quasistatic ratio and auto's inertial points."""
    numba.set_num_threads(threads)
    best, inertial = dict.fromkeys(MODELS, float("inf")), 0
    for model in MODELS:
        sweep.run_sweep(scene(side, model), progress=False)  # warm-up: kernels loaded, caches filled
    for _ in range(repeats):
        for model in MODELS:
            t = time.perf_counter()
            ds = sweep.run_sweep(scene(side, model), progress=False)
            best[model] = min(best[model], time.perf_counter() - t)
            if model == "auto":
                inertial = int(ds["model"].sum())
    return {"points": scene(side, "auto").n_points, "threads": threads, "wall_s": best,
            "auto_over_quasistatic": best["auto"] / best["quasistatic"], "auto_inertial_points": inertial,
            "loadavg": loadavg()}


def print_table(result: dict) -> None:
    print(f"\n{'points':>9s}{'threads':>8s}{'quasistatic s':>15s}{'auto s':>9s}{'auto/qs':>9s}")
    for r in result["rows"]:
        print(f"{r['points']:9d}{r['threads']:8d}{r['wall_s']['quasistatic']:15.3f}{r['wall_s']['auto']:9.3f}"
              f"{r['auto_over_quasistatic']:9.3f}")
    for points, gain in result["two_threads_over_one"].items():
        print(f"2 threads / 1 thread at {points} points: {gain:.2f}x (quasistatic)")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="2e4 and 4e4 points, one repeat")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    sides, repeats = ((None, 200), 1) if args.quick else ((None, 1000), args.repeats)
    rows = [measure(side, threads, repeats) for side in sides for threads in (1, 2)]
    gains = {str(a["points"]): a["wall_s"]["quasistatic"] / b["wall_s"]["quasistatic"]
             for a, b in zip(rows[::2], rows[1::2])}
    result = {"benchmark": "benchmarks/auto_cost.py", "command": " ".join(sys.argv), "quick": args.quick,
              "machine": machine_info(), "rows": rows, "two_threads_over_one": gains,
              "targets": {"auto_over_quasistatic_max": 1.2, "two_threads_over_one_min": 1.8}}
    write_result(result, args.out, t_start, None, print_table)


if __name__ == "__main__":
    main()
