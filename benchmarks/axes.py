"""Throughput of a 4-D sweep against a 2-D sweep of as many points (issue 21, part 1: "a 4-D grid of 1e6 points
runs like a 2-D grid of 1e6 points, same throughput within 10 %").

    python benchmarks/axes.py [--quick] [--out benchmarks/results/axes.json] [--no-png]

Three grids of N = n^2 points over the same (K/M, V) box (sample2, stop protocol, relaxed slip only, the scene's
default rtol and model), each run by ``sweep.run_sweep`` in memory (no file):

* ``2d``: n x n (K/M, V) (1000 x 1000 in the full run);
* ``4d``: (n/10 x n/10) (K/M, V) x 10 A x 10 m1, A and m1 spanning +-20 % around sample2: the physics differs
  from the 2-D grid's (other A and m1 give other transients), so its cost per point may differ for that reason;
* ``4d_same_physics``: the same shape, but the 10 A and 10 m1 values all within 1e-9 (relative) of sample2's:
  every (K/M, V) column holds 100 copies of one problem of a (n/10 x n/10) 2-D grid;
* ``2d_same_problems``: the 2-D grid holding exactly those problems: each of the n/10 K/M and V values repeated
  10 times within 1e-9 (relative; an axis must increase). Against ``4d_same_physics`` only the axis handling
  (broadcasting, per-point parameters, a Dataset of 4 dims) differs: the like-for-like comparison of the target.
  (``2d`` and ``4d_same_physics`` sample the same box at different densities, so their mean steps per point
  differ by a few per cent: ``steps_mean`` shows it.)

Each grid is run once untimed (kernels compiled or loaded), then ``REPEATS`` times, alternating (2d, 4d, ...),
best time kept (the load of
other users only ever adds time); the load average is recorded before and after each run. The throughput ratio
is 4-D points per second over 2-D points per second (target >= 0.9: ``4d_same_physics`` over
``2d_same_problems``). --quick: n = 100, 2 repeats.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import _common as common  # noqa: E402

import sweep  # noqa: E402

DEFAULT_OUT = HERE / "results" / "axes.json"
K_RANGE, V_RANGE = (1e3, 1e6), (1e-7, 1e-4)
"""The (K/M, V) box [s-2], [m s-1] of every grid (the default scene's)."""
N_SIDE, N_SIDE_QUICK = 1000, 100
REPEATS, REPEATS_QUICK = 3, 2
EXTRA = 10
"""Values on each of the extra axes A and m1."""
SPREAD = 0.2
"""The 4-D grid's A and m1 span sample2's value x (1 -+ SPREAD)."""
TARGET_RATIO = 0.9


def scenes(n: int) -> dict[str, sweep.Scene]:
    """The three scenes of the docstring, n^2 points each."""
    p = sweep.presets["sample2"]
    base = dict(protocol="stop", params=p)
    n4 = n // EXTRA
    km4, v4 = np.geomspace(*K_RANGE, n4), np.geomspace(*V_RANGE, n4)
    near = 1.0 + 1e-9 * np.arange(EXTRA)  # strictly increasing (an axis must be), the same physics to 1e-9
    copies = lambda x: (x[:, None] * near).ravel()  # noqa: E731  (each value 10 times, still increasing)
    return {
        "2d": sweep.Scene(**base, K_over_M=np.geomspace(*K_RANGE, n), V=np.geomspace(*V_RANGE, n)),
        "4d": sweep.Scene(**base, K_over_M=km4, V=v4,
                          axes={"A": p.A * np.linspace(1 - SPREAD, 1 + SPREAD, EXTRA),
                                "m1": p.m1 * np.linspace(1 - SPREAD, 1 + SPREAD, EXTRA)}),
        "4d_same_physics": sweep.Scene(**base, K_over_M=km4, V=v4, axes={"A": p.A * near, "m1": p.m1 * near}),
        "2d_same_problems": sweep.Scene(**base, K_over_M=copies(km4), V=copies(v4)),
    }


def run_once(scene: sweep.Scene) -> tuple[float, float, dict]:
    """Wall and CPU seconds of one in-memory run_sweep, and what its Dataset says about the work."""
    c0, t0 = time.process_time(), time.perf_counter()
    ds = sweep.run_sweep(scene, progress=False)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    steps = ds["steps"].values
    return wall, cpu, {"steps_mean": float(steps.mean()), "models": {int(m): int((ds["model"].values == m).sum())
                                                                     for m in np.unique(ds["model"].values)}}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help=f"n = {N_SIDE_QUICK}, {REPEATS_QUICK} repeats")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--no-png", action="store_true", help="accepted for uniformity (this script draws nothing)")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    load0, digest0 = common.loadavg(), common.sweep_digest()
    n, repeats = (N_SIDE_QUICK, REPEATS_QUICK) if args.quick else (N_SIDE, REPEATS)
    grids = scenes(n)
    for sc in grids.values():  # every kernel the grids need compiled or loaded, outside the timings
        sweep.run_sweep(sc, progress=False)
    runs = {name: [] for name in grids}
    work = {}
    for r in range(repeats):
        for name, sc in grids.items():
            before = common.loadavg()
            wall, cpu, work[name] = run_once(sc)
            runs[name].append({"wall_s": wall, "cpu_s": cpu, "loadavg_before": before,
                               "loadavg_after": common.loadavg()})
            print(f"repeat {r}: {name:16s} {sc.n_points} points, wall {wall:.2f} s, cpu {cpu:.2f} s, "
                  f"load {before[0] if before else '?'}", flush=True)
    rows = {}
    for name, sc in grids.items():
        best = min(x["wall_s"] for x in runs[name])
        rows[name] = {"dims": list(sc.dims), "shape": list(sc.shape), "points": sc.n_points, "best_wall_s": best,
                      "best_cpu_s": min(x["cpu_s"] for x in runs[name]), "points_per_s": sc.n_points / best,
                      **work[name], "runs": runs[name]}
    ratio = {"4d_over_2d": rows["4d"]["points_per_s"] / rows["2d"]["points_per_s"],
             "4d_same_physics_over_2d": rows["4d_same_physics"]["points_per_s"] / rows["2d"]["points_per_s"],
             "4d_same_physics_over_2d_same_problems": rows["4d_same_physics"]["points_per_s"]
             / rows["2d_same_problems"]["points_per_s"]}
    result = {
        "benchmark": "benchmarks/axes.py" + (" --quick" if args.quick else ""),
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "quick": args.quick,
        "machine": common.machine_info(),
        "sweep_source_digest_start_end": [digest0, common.sweep_digest()],
        "loadavg_start_end": [load0, common.loadavg()],
        "settings": {"K_over_M_range": K_RANGE, "V_range": V_RANGE, "n_side": n, "extra_values": EXTRA,
                     "spread": SPREAD, "repeats": repeats, "rtol": grids["2d"].rtol, "model": grids["2d"].model,
                     "observables": list(grids["2d"].observables)},
        "grids": rows,
        "throughput_ratios": ratio,
        "target": {"ratio_at_least": TARGET_RATIO,
                   "met": ratio["4d_same_physics_over_2d_same_problems"] >= TARGET_RATIO},
    }

    def table(res):
        for name, row in res["grids"].items():
            print(f"{name:16s} {row['points']:>8d} points  best {row['best_wall_s']:.2f} s  "
                  f"{row['points_per_s']:.3g} points/s  steps/point {row['steps_mean']:.1f}")
        print("throughput ratios: " + ", ".join(f"{k} {v:.3f}" for k, v in res["throughput_ratios"].items()))

    common.write_result(result, args.out, t_start, None, table)


if __name__ == "__main__":
    main()
