"""Cost of the history protocol (issue 34's targets): a slide-hold-slide series per point, a grid of Delta mu_peak,
and the forward model of record fits.

* shs_point: an SHS series of 8 holds (1..1000 s, log-spaced; slides of 100 um at 10 um/s; lab parameters a = 0.01,
  b = 0.015, Dc = 10 um, k = 1e3/m, quasi-static, aging law, rtol 1e-6) per point, warm: the engine's chunk (two
  dp5 runs per point and the read-off of every observable and beta) on 1 point and on 256 points (per point),
  and run_sweep of one point (the whole path: plan, chunk, Dataset). Target < 5 ms a point.
* grid: a 1e5-point (t_hold, K/M, b/a) sweep of Delta mu_peak: slide 10 um, hold t_hold (1..1e4 s), reslide 50 um
  at 10 um/s; t_hold 50 x K/M 40 (k = 5e2..5e4 /m) x m1 50 (b/a = 1.05..2), run_sweep with numba's threads on the
  machine's cores. Target < 10 s on 2 cores.
* forward: sweep.protocols.history.forward.friction_at for the same SHS series with 1e3 and 1e5 samples, 1 and 16
  parameter sets (the cost of a fit's forward model).

Writes benchmarks/results/history.json. Run: python benchmarks/history.py (~1 min on 2 cores);
--quick: tiny sizes, one call each (checks that the script works; its numbers are not results).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import loadavg, machine_info, timed, write_result  # noqa: E402

import sweep  # noqa: E402
from sweep.protocols.history.engine import history_chunk, history_plan  # noqa: E402
from sweep.protocols.history.forward import LoadHistory, friction_at  # noqa: E402

OUT = Path(__file__).resolve().parent / "results" / "history.json"
LAB = sweep.FrictionParams.from_lab(a=0.01, b=0.015, Dc=1e-5, mu0=0.6)
K_LAB, V = 1e3, 1e-5
HOLDS = np.logspace(0, 3, 8)
SLIDE = 1e-4


def shs_segments(holds=HOLDS) -> list[dict]:
    segs = [{"V_ratio": 1, "displacement": SLIDE}]
    for t_h in holds:
        segs += [{"hold": float(t_h)}, {"V_ratio": 1, "displacement": SLIDE}]
    return segs


def shs_scene(n_points: int) -> sweep.Scene:
    return sweep.Scene(protocol="history", params=LAB, K_over_M=np.linspace(1, 2, n_points) * K_LAB * 9.81, V=[V],
                       rtol=1e-6, model="quasistatic", options={"segments": shs_segments()})


def bench_shs(repeats: int) -> dict:
    out = {}
    for n in (1, 256):
        scene = shs_scene(n)
        plan = history_plan(scene)
        compute = history_chunk(scene, plan)
        points = np.arange(n)
        compute(points)  # warm
        cpu, wall, res = timed(lambda: compute(points), repeats)  # noqa: B023
        out[f"chunk_{n}_points"] = {"points": n, "cpu_s": cpu, "wall_s": wall, "ms_per_point_cpu": 1e3 * cpu / n,
                                    "steps_per_point": float(np.mean(res["steps"])),
                                    "status_ok": int(np.sum(res["status"] == 0)),
                                    "beta_first": float(res["beta"][0])}
    scene = shs_scene(1)
    sweep.run_sweep(scene, progress=False)
    cpu, wall, _ = timed(lambda: sweep.run_sweep(scene, progress=False), repeats)
    out["run_sweep_1_point"] = {"cpu_s": cpu, "wall_s": wall}
    return out


def grid_scene(n_h: int, n_k: int, n_b: int) -> sweep.Scene:
    """Slide 10 um, hold t_hold, reslide 50 um at 10 um/s over t_hold 1..1e4 s x k 5e2..5e4 /m x b/a 1.05..2."""
    b_over_a = np.linspace(1.05, 2.0, n_b)
    return sweep.Scene(protocol="history", params=LAB, K_over_M=np.logspace(np.log10(5e2), np.log10(5e4), n_k) * 9.81,
                       V=[V], axes={"t_hold": np.logspace(0, 4, n_h), "m1": (b_over_a - 1) * LAB.A}, rtol=1e-6,
                       model="quasistatic", observables=("mu_end", "delta_mu_peak"),
                       options={"segments": [{"V_ratio": 1, "displacement": 1e-5}, {"hold": "t_hold"},
                                             {"V_ratio": 1, "displacement": 5e-5}]})


def bench_grid(quick: bool) -> dict:
    scene = grid_scene(*((4, 4, 4) if quick else (50, 40, 50)))
    sweep.run_sweep(grid_scene(2, 2, 2), progress=False)  # warm
    c0, t0 = time.process_time(), time.perf_counter()
    ds = sweep.run_sweep(scene, progress=False)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    peak = ds["delta_mu_peak"].isel(segment=2)
    return {"points": int(np.prod(scene.shape)), "shape": dict(zip(scene.dims, map(int, scene.shape))),
            "wall_s": wall, "cpu_s": cpu, "us_per_point_wall": 1e6 * wall / np.prod(scene.shape),
            "status_counts": {int(k): int(v) for k, v in zip(*np.unique(ds["status"].values, return_counts=True))},
            "steps_mean": float(ds["steps"].mean()), "delta_mu_peak_range": [float(peak.min()), float(peak.max())],
            "load_after": loadavg()}


def bench_forward(repeats: int, quick: bool) -> dict:
    segs = shs_segments()
    velocities = np.array([V * s.get("V_ratio", 0.0) for s in segs])
    durations = np.array([s.get("hold", s.get("displacement", 0.0) / V) for s in segs])
    load = LoadHistory(velocities, durations)
    base = {"A": LAB.A, "m1": LAB.m1, "m2": 0.0, "D0": LAB.D0, "m0": LAB.m0, "V0": LAB.V0, "K_over_M": K_LAB * 9.81}
    out = {}
    for n_t in (1000,) if quick else (1000, 100_000):
        t = np.sort(np.random.default_rng(0).uniform(0, load.total, n_t))
        for n_sets in (1, 16):
            params = {**base, "D0": LAB.D0 * np.linspace(1, 1.1, n_sets)}
            friction_at(params, load, t)
            cpu, wall, res = timed(lambda: friction_at(params, load, t), repeats)  # noqa: B023
            out[f"{n_t}_samples_{n_sets}_sets"] = {"cpu_s": cpu, "wall_s": wall, "ms_per_set_cpu": 1e3 * cpu / n_sets,
                                                   "steps_per_set": float(np.mean(res.steps))}
    out["history_s"] = load.total
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    t_start = time.perf_counter()
    repeats = 1 if args.quick else 5
    result = {"benchmark": "history", "quick": args.quick, "machine": {**machine_info(), "load_before": loadavg()}}
    result["shs_point"] = bench_shs(repeats)
    result["forward"] = bench_forward(repeats, args.quick)
    result["grid"] = bench_grid(args.quick)
    per_point = result["shs_point"]["chunk_1_points"]["ms_per_point_cpu"]
    result["targets"] = {"shs_point_ms": {"target": 5.0, "measured_cpu_ms": per_point, "met": per_point < 5.0},
                         "grid_1e5_s": {"target": 10.0, "measured_wall_s": result["grid"]["wall_s"],
                                        "met": result["grid"]["wall_s"] < 10.0, "points": result["grid"]["points"]}}
    write_result(result, args.out, t_start, print_table=lambda r: print(
        f"SHS point (8 holds): {per_point:.2f} ms cpu (1 point), "
        f"{r['shs_point']['chunk_256_points']['ms_per_point_cpu']:.2f} ms/point (256)\n"
        f"grid {r['grid']['points']} points: {r['grid']['wall_s']:.2f} s wall, {r['grid']['cpu_s']:.2f} s cpu\n"
        "forward: " + ", ".join(f"{k} {v['cpu_s'] * 1e3:.2f} ms" for k, v in r["forward"].items()
                                if k != "history_s")))


if __name__ == "__main__":
    main()
