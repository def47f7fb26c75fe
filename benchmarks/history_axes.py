"""What sweeping a history's own numbers costs (issue 34): a history scene whose segments name grid axes against one
of as many points whose segments are numbers.

    python benchmarks/history_axes.py [--quick] [--out benchmarks/results/history_axes.json]

Grids of N points (10,000; --quick 1,600), laboratory parameters a = 0.007, b = 0.0195, Dc = 0.7 um, quasi-static,
rtol 1e-6, observables mu_end and delta_mu_peak, run by ``sweep.run_sweep`` in memory (no file):

* ``hold_axis``: a slide-hold-slide (slides of 20 um at 1 um/s) with ``hold = "t_hold"``, over k (1/m, 5e4..1e6) x
  b (0.0195..0.03) x t_hold (1..1e4 s): the issue's (t_h, k, b) sweep;
* ``hold_fixed``: the same history with the hold a number (100 s), over k x V (V 0.5..2 um/s), as many points;
* ``ratio_axis``: a step V -> r V with ``V_ratio = "r"`` (r 0.1..10) over k x r: the kernel takes one ratio per
  segment for all its points, so a chunk runs one kernel call per distinct r (its cost is the grouping);
* ``ratio_axis_same_physics``: the same over k x r with the r all within 1e-9 (relative) of 3: the problems of
  ``ratio_fixed``, one kernel call per r and chunk;
* ``ratio_fixed``: the step V -> 3 V over k x V, the V all within 1e-9 of 1 um/s: one kernel call per chunk. Against
  ``ratio_axis_same_physics`` only the grouping differs (the ratio printed).

Each is run once untimed (kernels loaded), then REPEATS times alternating, the best CPU and wall times kept; the
load average is recorded around each run (this machine is shared).
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

DEFAULT_OUT = HERE / "results" / "history_axes.json"
REPEATS, REPEATS_QUICK = 3, 2
SLIDE = {"V_ratio": 1, "displacement": 2e-5}


def scenes(n: int) -> dict[str, sweep.Scene]:
    """The four scenes of about ``n`` points each (module docstring)."""
    lab = sweep.FrictionParams.from_lab(a=0.007, b=0.0195, Dc=0.7e-6)
    side = int(round(n ** 0.5))
    k = np.geomspace(5e4, 1e6, side)
    common_kw = dict(protocol="history", params=lab, K_over_M=None, model="quasistatic", rtol=1e-6,
                     observables=["mu_end", "delta_mu_peak"])
    n_b = 10
    return {
        "hold_axis": sweep.Scene(V=[1e-6], axes={"k": np.geomspace(5e4, 1e6, n // (n_b * 20)),
                                                  "b": np.linspace(0.0195, 0.03, n_b),
                                                  "t_hold": np.geomspace(1, 1e4, 20)},
                                 options={"segments": [SLIDE, {"hold": "t_hold"}, SLIDE]}, **common_kw),
        "hold_fixed": sweep.Scene(V=np.geomspace(5e-7, 2e-6, side), axes={"k": k},
                                  options={"segments": [SLIDE, {"hold": 100.0}, SLIDE]}, **common_kw),
        "ratio_axis": sweep.Scene(V=[1e-6], axes={"k": k, "r": np.geomspace(0.1, 10, side)},
                                  options={"segments": [SLIDE, {"V_ratio": "r", "displacement": 2e-5}]}, **common_kw),
        "ratio_axis_same_physics": sweep.Scene(V=[1e-6], axes={"k": k, "r": 3.0 * (1 + 1e-9 * np.arange(side))},
                                               options={"segments": [SLIDE, {"V_ratio": "r", "displacement": 2e-5}]},
                                               **common_kw),
        "ratio_fixed": sweep.Scene(V=1e-6 * (1 + 1e-9 * np.arange(side)), axes={"k": k},
                                   options={"segments": [SLIDE, {"V_ratio": 3, "displacement": 2e-5}]}, **common_kw),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    t_start = time.perf_counter()
    n, repeats = (1600, REPEATS_QUICK) if args.quick else (10_000, REPEATS)
    grids = scenes(n)
    runs = {name: (lambda sc=sc: sweep.run_sweep(sc, progress=False)) for name, sc in grids.items()}
    for run in runs.values():
        run()  # kernels compiled or loaded
    cpu = {name: [] for name in runs}
    wall = {name: [] for name in runs}
    load = []
    for _ in range(repeats):
        for name, run in runs.items():
            load.append(common.loadavg())
            c, w, ds = common.timings(run, 1)
            cpu[name] += c
            wall[name] += w
            assert int((ds.status == 0).sum()) == grids[name].n_points, name
    load.append(common.loadavg())
    result = {"benchmark": "history_axes", "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
              "machine": common.machine_info(), "quick": args.quick, "repeats": repeats, "loadavg": load,
              "grids": {name: {"dims": dict(zip(sc.dims, sc.shape)), "n_points": sc.n_points,
                               "cpu_s_best": min(cpu[name]), "wall_s_best": min(wall[name]),
                               "points_per_s_wall": sc.n_points / min(wall[name])} for name, sc in grids.items()}}
    g = result["grids"]
    result["ratio_hold_axis_over_fixed_wall_per_point"] = ((g["hold_axis"]["wall_s_best"] / g["hold_axis"]["n_points"])
                                                           / (g["hold_fixed"]["wall_s_best"]
                                                              / g["hold_fixed"]["n_points"]))
    result["ratio_ratio_axis_over_fixed_wall_per_point"] = ((g["ratio_axis_same_physics"]["wall_s_best"]
                                                             / g["ratio_axis_same_physics"]["n_points"])
                                                            / (g["ratio_fixed"]["wall_s_best"]
                                                               / g["ratio_fixed"]["n_points"]))

    def table(r: dict) -> None:
        for name, x in r["grids"].items():
            print(f"{name:>12}: {x['n_points']:>6} points {x['dims']}  wall {x['wall_s_best']:.3f} s  "
                  f"cpu {x['cpu_s_best']:.3f} s  {x['points_per_s_wall']:,.0f} points/s")
        print(f"per point, hold axis / fixed hold: {r['ratio_hold_axis_over_fixed_wall_per_point']:.2f}; "
              f"ratio axis / fixed ratio (same problems): {r['ratio_ratio_axis_over_fixed_wall_per_point']:.2f}")

    common.write_result(result, args.out, t_start, print_table=table)


if __name__ == "__main__":
    main()
