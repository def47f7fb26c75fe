"""Cost of the Hopf line and of the driven scene, with the map of both lines.

* the inertial line (sample2 with m2 = 0, gamma/A = 1e-3 .. 10 over 10 velocities) against mu1 (1 + gamma/A),
  and its bifurcation type at each velocity;
* the inertial driven scene deep in stick-slip (the same parameters, chi = 0.3..1.5 chi_c, gamma/A 1e-3..1): stiff
  stick phases, RODAS3 steps there; points per second and regimes (none should be undecided);
* locating the line over 50 velocities (sample2, V 0.1..6 um/s where mu1 > 0, and 10..100 um/s where it is not):
  sweep.locate_hopf by simulation (with and without the bifurcation type) vs the analytic line (eq. 3), side by
  side, and the largest relative distance between the two lines;
* throughput of the driven scene: run_sweep on a 40 x 20 (K/M, V) grid of sample2, quasi-static, points per
  second, per regime (mean steps and cycles), 1 thread and 2 threads; and with model="auto", where the
  quasi-static breakdowns (regime runaway) are run again with inertia (gamma/A 2e-5..2e-3 there: stiff);
* the regime map with the analytic and the simulated Hopf lines (sweep.plot.files.plot_regimes, PNG).

Writes benchmarks/results/hopf.json and hopf.png. Run: python benchmarks/hopf.py (~1 min on 2 cores).

    python benchmarks/hopf.py [--quick] [--out benchmarks/results/hopf.json] [--no-png]

--quick: every part on tiny sets (4 velocities on the line, 2 on the inertial line, a 4 x 2 deep grid, an 8 x 4
driven grid), one timed call each: checks that the script works; its numbers are not results. The driven
kernel's inertial variant is compiled in every process (sweep/integrate/driven.py: INERTIAL_NOT_CACHED), for
locate_hopf and again for run_sweep's driven batch, so a quick run still spends ~20 s compiling.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import loadavg, machine_info, sweep_digest  # noqa: E402
from sweep.plot.files import plot_regimes  # noqa: E402

import sweep  # noqa: E402
from sweep import physics  # noqa: E402
from sweep.integrate.driven import Regime  # noqa: E402

OUT = Path(__file__).resolve().parent / "results"
PARAMS = sweep.presets["sample2"]
V_LINE = np.concatenate([np.logspace(-7, np.log10(6e-6), 45), np.logspace(-5, -4, 5)])
V_LINE_QUICK = np.concatenate([np.logspace(-7, np.log10(6e-6), 3), np.logspace(-4, -4, 1)])
GRID = dict(K_over_M=np.logspace(3, 6, 40), V=np.logspace(-7, -5, 20))
GRID_QUICK = dict(K_over_M=np.logspace(3, 6, 8), V=np.logspace(-7, -5, 4))


def best_of(fn, repeats=3):
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny sets, one timed call each (a smoke run)")
    ap.add_argument("--out", type=Path, default=OUT / "hopf.json", help="the JSON (the PNG beside it, .png)")
    ap.add_argument("--no-png", action="store_true")
    args = ap.parse_args(argv)
    quick = args.quick
    v_line = V_LINE_QUICK if quick else V_LINE
    grid = GRID_QUICK if quick else GRID
    repeats = 1 if quick else 3
    # the inertial line over gamma/A = 10^lo .. 10^hi (quick: 0.1 and 10; 1e-3 costs seconds to type), the deep grid
    (lo, hi, n_fast), deep_shape = ((-1, 1, 2), (4, 2)) if quick else ((-3, 1, 10), (13, 7))
    t_start = time.perf_counter()
    digest0, load0 = sweep_digest(), loadavg()
    sweep.locate_hopf(PARAMS, v_line[:2])  # compile / load the kernels
    numba.set_num_threads(1)
    t_typed, line = best_of(lambda: sweep.locate_hopf(PARAMS, v_line), 1)
    t_sim, line_only = best_of(lambda: sweep.locate_hopf(PARAMS, v_line, bifurcation=False), repeats)
    t_lin, lin = best_of(lambda: physics.hopf_K_over_M(v_line, PARAMS.A, PARAMS.m1, PARAMS.m2, PARAMS.D0,
                                                       PARAMS.V0, PARAMS.g), 20)
    inertial_params = PARAMS.replace(m2=0.0)  # mu1 = m1 at every V: the inertial line up to gamma/A = 10
    v_fast = np.sqrt(np.logspace(lo, hi, n_fast) * PARAMS.g * PARAMS.D0 * PARAMS.A)
    t_inertial, inertial = best_of(lambda: sweep.locate_hopf(inertial_params, v_fast, model="inertial",
                                                             bifurcation=False), 1)
    t_inertial_typed, inertial_typed = best_of(lambda: sweep.locate_hopf(inertial_params, v_fast, model="inertial"), 1)
    inertial_kinds = [inertial_typed["bifurcation"].attrs["flag_meanings"].split()[c]
                      for c in inertial_typed["bifurcation"].values]
    deep = sweep.Scene(protocol="driven", params=inertial_params, model="inertial",
                       K_over_M=np.linspace(0.3, 1.5, deep_shape[0]) * PARAMS.m1 * PARAMS.g / PARAMS.D0,
                       V=np.sqrt(np.logspace(-3, 0, deep_shape[1]) * PARAMS.g * PARAMS.D0 * PARAMS.A))
    t_deep, deep_ds = best_of(lambda: sweep.run_sweep(deep, progress=False), 1)
    deep_regimes = {r.name.lower(): int(np.count_nonzero(deep_ds["regime"].values == r)) for r in Regime}
    has_line = np.isfinite(lin)
    rel = np.abs(line["K_over_M_c"].values[has_line] / lin[has_line] - 1)
    names = line["bifurcation"].attrs["flag_meanings"].split()
    kinds = {names[c]: int(n) for c, n in zip(*np.unique(line["bifurcation"].values, return_counts=True))}

    def regimes_of(ds):
        out = {}
        for r in Regime:
            sel = ds["regime"].values == r
            if sel.any():
                out[r.name.lower()] = {"points": int(sel.sum()), "mean_steps": float(ds["steps"].values[sel].mean()),
                                       "mean_cycles": float(ds["cycles"].values[sel].mean())}
        return out

    scene = sweep.Scene(protocol="driven", params=PARAMS, model="quasistatic", simulated_hopf_line=True, **grid)
    sweep.run_sweep(scene, progress=False)
    driven = {}
    for threads in (1, 2):
        numba.set_num_threads(threads)
        t, ds = best_of(lambda: sweep.run_sweep(scene, progress=False), repeats)
        driven[f"threads_{threads}"] = {"seconds": t, "points_per_s": scene.n_points / t}
    regimes = regimes_of(ds)
    agree = (ds["regime"].values == Regime.STEADY) == (ds["stable"].values == 1)
    # model="auto" (the default): the quasi-static breakdowns (runaway) of the same grid run again with inertia
    auto_scene = sweep.Scene(protocol="driven", params=PARAMS, **grid)
    t_auto, ds_auto = best_of(lambda: sweep.run_sweep(auto_scene, progress=False), 1)
    statuses = ds_auto["status"].attrs["flag_meanings"].split()
    driven_auto = {"threads": numba.get_num_threads(), "seconds": t_auto, "points_per_s": scene.n_points / t_auto,
                   "points_run_with_inertia": int(ds_auto["model"].values.sum()), "regimes": regimes_of(ds_auto),
                   "status": {statuses[c]: int(n) for c, n in zip(*np.unique(ds_auto["status"].values,
                                                                             return_counts=True))}}
    result = {
        "benchmark": "hopf" + (" --quick (tiny sets: a check of the script, not a result)" if quick else ""),
        "quick": quick, "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "machine": machine_info(),
        "sweep_source_digest_start_end": [digest0, sweep_digest()], "loadavg_start_end": [load0, loadavg()],
        "line": {"velocities": int(v_line.size), "with_line": int(has_line.sum()),
                 "seconds_simulation_with_type_1thread": t_typed, "seconds_simulation_1thread": t_sim,
                 "seconds_analytic": t_lin, "simulation_over_analytic": t_sim / t_lin,
                 "simulations_per_velocity_mean": float(line_only["simulations"].values[has_line].mean()),
                 "max_rel_distance_to_linear": float(rel.max()), "bifurcation_counts": kinds},
        "inertial_line": {"params": "sample2 with m2 = 0", "gamma_over_A": [10.0**lo, 10.0**hi], "velocities": n_fast,
                          "seconds_1thread": t_inertial, "seconds_with_type_1thread": t_inertial_typed,
                          "bifurcation_by_gamma_over_A": dict(zip((inertial_typed["gamma"].values / PARAMS.A).round(
                              4).astype(str).tolist(), inertial_kinds)),
                          "max_rel_distance_to_linear": float(np.max(np.abs(
                              inertial["K_over_M_c"].values / inertial["K_over_M_c_linear"].values - 1)))},
        "inertial_driven_deep_stick_slip": {"shape": list(deep.shape), "chi_over_chi_c": [0.3, 1.5],
                                            "gamma_over_A": [1e-3, 1.0], "seconds_1thread": t_deep,
                                            "points_per_s": deep.n_points / t_deep, "regimes": deep_regimes,
                                            "mean_steps": float(deep_ds["steps"].values.mean())},
        "driven_grid": {"shape": list(scene.shape), "model": "quasistatic", **driven, "regimes": regimes,
                        "steady_iff_linearly_stable_fraction": float(agree.mean())},
        "driven_grid_auto": driven_auto,
        "benchmark_wall_s": time.perf_counter() - t_start,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1))
    if not args.no_png:  # the run_sweep file carries the simulated line (K_over_M_c_simulated)
        plot_regimes(ds, args.out.with_suffix(".png"))
    print(json.dumps(result, indent=1))
    print(f"wrote {args.out}" + ("" if args.no_png else f" and {args.out.with_suffix('.png')}"))


if __name__ == "__main__":
    main()
