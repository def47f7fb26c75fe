"""Cost of the Hopf line and of the driven scene, with the map of both lines.

* the inertial line (sample2 with m2 = 0, gamma/A = 1e-3 .. 10 over 10 velocities) against mu1 (1 + gamma/A),
  and its bifurcation type at each velocity;
* the inertial driven scene deep in stick-slip (the same parameters, chi = 0.3..1.5 chi_c, gamma/A 1e-3..1): stiff
  stick phases, RODAS3 steps there; points per second and regimes (none should be undecided);
* locating the line over 50 velocities (sample2, V 0.1..6 um/s where mu1 > 0, and 10..100 um/s where it is not):
  sweep.locate_hopf by simulation (with and without the bifurcation type) vs the analytic line (eq. 3), side by
  side, and the largest relative distance between the two lines;
* the same 50 velocities A/B against the code before (key "line_ab"; --base, default /tmp/hopf_base, a ``git
  worktree add`` of an older commit): each tree in fresh subprocesses of this script, alternating, best of 3, one
  thread (and this tree on two): times with and without the type, the speed-up (target 10x with the type), types,
  located lines and amplitudes compared;
* throughput of the driven scene: run_sweep on a 40 x 20 (K/M, V) grid of sample2, quasi-static, points per
  second, per regime (mean steps and cycles), 1 thread and 2 threads; and with model="auto", where the
  quasi-static breakdowns (regime runaway) are run again with inertia (gamma/A 2e-5..2e-3 there: stiff);
* the regime map with the analytic and the simulated Hopf lines (sweep.plot.files.plot_regimes, PNG);
* the type of the line from the normal form (sweep/analysis/lyapunov.py, docs/hopf-type.md; key "lyapunov"): l1
  with its error along 1,000 velocities (targets < 1 s), the Bautin point of the inertial m2 = 0 line to 1e-3 in
  gamma/A (< 2 s) and its convergence, the bistable band's width by simulation at 5 velocities on the inverted
  side (< 30 s on 2 cores) with width / l1^2, the square-root law's coefficient against simulation at 2 distances,
  and the Bautin point as a function of mu1/A (m2 = 0) and of m2/A (where the inverted window closes).

Writes benchmarks/results/hopf.json and hopf.png. Run: python benchmarks/hopf.py (~1 min on 2 cores).

    python benchmarks/hopf.py [--quick] [--out benchmarks/results/hopf.json] [--no-png] [--only-lyapunov] [--base DIR]

--only-lyapunov: the "lyapunov" part alone (~30 s), written to --out (default benchmarks/results/lyapunov.json).

--quick: every part on tiny sets (4 velocities on the line, 2 on the inertial line, a 4 x 2 deep grid, an 8 x 4
driven grid), one timed call each: checks that the script works; its numbers are not results. The driven
kernel's inertial variant is compiled in every process (sweep/integrate/driven.py: INERTIAL_NOT_CACHED), for
locate_hopf and again for run_sweep's driven batch, so a quick run still spends ~20 s compiling.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import loadavg, machine_info, sweep_digest  # noqa: E402

import sweep  # noqa: E402
from sweep import physics  # noqa: E402
from sweep.analysis.bistable import bistable_band  # noqa: E402
from sweep.analysis.lyapunov import bautin_points, lyapunov_line, reduced_l1  # noqa: E402
from sweep.integrate.driven import DrivenParams, DrivenSettings, Regime, simulate_point  # noqa: E402
from sweep.plot.files import plot_regimes  # noqa: E402

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


def _v_of(params, ratio):
    """Velocities [m s-1] at the given gamma/A."""
    return np.sqrt(np.asarray(ratio) * params.g * params.D0 * params.A)


def _bautin_g(a: float, b: float, g_grid: np.ndarray) -> list[float]:
    """gamma/A of the sign changes of l1 at fixed a = mu1/A, b = m2/A (chord root on the grid; the parameter map)."""
    l1, err, _ = reduced_l1(a, b, g_grid)
    sign = np.where(l1 > err, 1, np.where(l1 < -err, -1, 0))
    out = []
    for i in np.flatnonzero((sign[:-1] * sign[1:]) < 0):
        x0, x1 = np.log(g_grid[i]), np.log(g_grid[i + 1])
        out.append(float(np.exp(x0 + (x1 - x0) * l1[i] / (l1[i] - l1[i + 1]))))
    return out


def _window_closes(a: float, g_grid: np.ndarray, halvings: int) -> dict:
    """The b = m2/A above which l1 <= 0 at every gamma/A of the grid (the inverted window closed), at a = mu1/A:
    bisection on the largest l1 - l1_error over the grid, from [0, 2]."""
    def opens(b):
        l1, err, _ = reduced_l1(a, b, g_grid)
        return bool(np.any(l1 > err))

    lo, hi = 0.0, 2.0
    for _ in range(halvings):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if opens(mid) else (lo, mid)
    return {"mu1_over_A": a, "m2_over_A": 0.5 * (lo + hi), "bracket": [lo, hi],
            "gamma_over_A_grid": [float(g_grid[0]), float(g_grid[-1]), int(g_grid.size)]}


def lyapunov_part(quick: bool) -> dict:
    """The "lyapunov" part of the JSON (module docstring)."""
    params = PARAMS.replace(m2=0.0)
    a = params.m1 / params.A
    repeats = 1 if quick else 5
    v_1000 = np.logspace(-7, -4, 100 if quick else 1000)
    lyapunov_line(PARAMS, v_1000[:4])  # numpy's first calls
    t_line, line = best_of(lambda: lyapunov_line(PARAMS, v_1000), repeats)
    v_inertial = _v_of(params, np.logspace(-3, 1, v_1000.size))
    t_line_in, line_in = best_of(lambda: lyapunov_line(params, v_inertial, model="inertial"), repeats)
    v_range = (float(v_inertial[0]), float(v_inertial[-1]))
    t_bautin, points = best_of(lambda: bautin_points(params, v_range, rtol=1e-3), repeats)
    finer = bautin_points(params, v_range, rtol=5e-4)
    reference = bautin_points(params, v_range, rtol=1e-9)
    g_b = [b.gamma_over_A for b in points]
    bautin = {"params": "sample2 with m2 = 0, inertial line gamma/A 1e-3 .. 10", "seconds": t_bautin, "rtol": 1e-3,
              "gamma_over_A": g_b, "V_um_s": [b.V * 1e6 for b in points],
              "K_over_M": [b.K_over_M for b in points], "direct_above": [b.direct_above for b in points],
              "moved_by_halving_rtol_rel_V": [abs(f.V / b.V - 1) for f, b in zip(finer, points)],
              "error_vs_rtol_1e-9_rel_gamma_over_A": [abs(b.gamma_over_A / r.gamma_over_A - 1)
                                                      for b, r in zip(points, reference)]}
    # the bistable band (simulation) at 5 velocities on the inverted side, towards the Bautin point
    band_ratios = [0.05, 0.115] if quick else [0.02, 0.05, 0.08, 0.1, 0.115]
    bistable_band(a, 0.0, 0.1, rtol=0.5)  # compile the inertial driven kernel outside the timing
    t0 = time.perf_counter()
    bands = [bistable_band(a, 0.0, g, rtol=0.1 if quick else 1e-2) for g in band_ratios]
    t_band = time.perf_counter() - t0
    l1_band = reduced_l1(a, 0.0, np.array(band_ratios))[0]
    band = {"gamma_over_A": band_ratios, "seconds_total": t_band, "rtol": 0.1 if quick else 1e-2,
            "width_rel": [b.d_hi for b in bands], "width_lower_bracket": [b.d_lo for b in bands],
            "bistable_checked": [b.bistable for b in bands], "simulations": [b.simulations for b in bands],
            "undecided": [b.undecided for b in bands], "l1": l1_band.tolist(),
            "width_over_l1_squared": [b.d_hi / x**2 for b, x in zip(bands, l1_band)]}
    # the square-root law below a direct line: simulated amplitude / normal form's sqrt(c d)
    sqrt_law = []
    for g in ([1.0] if quick else [0.3, 1.0]):
        l1, _, nf = reduced_l1(a, 0.0, g)
        c = nf.dlambda[0].real * a * (1 + g) / (nf.omega[0] * l1[0])
        for d in (1e-3, 4e-3):
            r = simulate_point(DrivenParams(a * (1 + g) * (1 - d), a, 0.0, g), DrivenSettings(1e-4, 1e-10, 10_000,
                                                                                             20_000_000))
            sqrt_law.append({"gamma_over_A": g, "d": d, "simulated": r.amplitude, "normal_form": float(np.sqrt(c * d)),
                             "ratio": r.amplitude / float(np.sqrt(c * d))})
    # the Bautin point over the parameters (reduced: a = mu1/A, b = m2/A), l1 on a gamma/A grid at each
    g_grid = np.logspace(-3, 1.5, 200 if quick else 2000)
    by_a = {f"{x:.3g}": _bautin_g(x, 0.0, g_grid) for x in ([0.5, 1.786, 5.0] if quick else
                                                              [0.2, 0.5, 1.0, 1.786, 3.0, 5.0, 10.0])}
    b_values = [0.0, 0.1, 0.3] if quick else [0.0, 0.02, 0.05, 0.1, 0.2, 0.3, 0.35, 0.4, 0.5]
    by_b = {f"{x:.3g}": _bautin_g(a, x, g_grid) for x in b_values}
    closes = _window_closes(a, g_grid, 20 if quick else 40)
    return {"line_1000_velocities": {"velocities": int(v_1000.size), "seconds_sample2_auto": t_line,
                                     "seconds_inertial_m2_zero": t_line_in,
                                     "l1_error_max_over_abs_l1_median": float(np.nanmax(line_in.l1_error) /
                                                                               np.nanmedian(np.abs(line_in.l1))),
                                     "types_sample2_auto": np.bincount(line.kind, minlength=4).tolist()},
            "bautin": bautin, "bistable_band": band, "sqrt_law": sqrt_law,
            "bautin_gamma_over_A_by_mu1_over_A_at_m2_zero": by_a,
            "bautin_gamma_over_A_by_m2_over_A_at_mu1_over_A_1.786": by_b,
            "inverted_window_closes_at_m2_over_A": closes,
            "targets": {"line_1000_under_1_s": max(t_line, t_line_in) < 1.0, "bautin_under_2_s": t_bautin < 2.0,
                        "band_5_velocities_under_30_s": t_band < 30.0}}


def line_worker(tree: str, threads: int, quick: bool) -> None:
    """One tree's measurement of the 50-velocity line (--worker; PYTHONPATH = the tree): JSON on stdout."""
    assert Path(sweep.__file__).resolve().is_relative_to(Path(tree).resolve()), sweep.__file__
    v_line = V_LINE_QUICK if quick else V_LINE
    sweep.locate_hopf(PARAMS, v_line[:2])  # kernels loaded (or compiled) and warm
    numba.set_num_threads(threads)
    t0 = time.perf_counter()
    typed = sweep.locate_hopf(PARAMS, v_line)
    t_typed = time.perf_counter() - t0
    t0 = time.perf_counter()
    sweep.locate_hopf(PARAMS, v_line, bifurcation=False)
    t_untyped = time.perf_counter() - t0
    print(json.dumps({"with_type_s": t_typed, "without_type_s": t_untyped, "threads": threads, "sweep": sweep.__file__,
                      "K_over_M_c": typed["K_over_M_c"].values.tolist(),
                      "K_over_M_c_linear": typed["K_over_M_c_linear"].values.tolist(),
                      "bifurcation": typed["bifurcation"].values.tolist(),
                      "limit_cycle_amplitude": typed["limit_cycle_amplitude"].values.tolist(),
                      "simulations": typed["simulations"].values.tolist()}))


def line_ab(base: Path, quick: bool) -> dict:
    """locate_hopf over the 50 velocities (with and without the type) in ``base`` (a git worktree of the code
    before, default /tmp/hopf_base) and in this tree, each in fresh subprocesses of this script (``--worker``,
    PYTHONPATH = the tree, the numba cache of the tree), alternating base, new, base, new, ...; best wall time of
    each; 1 thread, and this tree on 2 threads. Where the base tree is missing, this tree against itself."""
    root = Path(__file__).resolve().parents[1]
    base = base if (base / "sweep" / "__init__.py").is_file() else root
    trees = {"base": base, "new": root}

    def worker(tree: Path, threads: int) -> dict:
        cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", str(tree), "--threads", str(threads)]
        proc = subprocess.run(cmd + ["--quick"] * quick, env={**os.environ, "PYTHONPATH": str(tree)},
                              capture_output=True, text=True, cwd=tempfile.gettempdir())
        if proc.returncode:
            raise RuntimeError(f"worker failed ({' '.join(cmd)}):\n{proc.stderr[-4000:]}")
        return {**json.loads(proc.stdout.strip().splitlines()[-1]), "loadavg": loadavg()}

    rows = {name: [] for name in trees}
    for _ in range(1 if quick else 3):
        for name, tree in trees.items():
            rows[name].append(worker(tree, 1))
    two = worker(root, 2)
    best = {key: {name: min(r[key] for r in rows[name]) for name in trees} for key in ("with_type_s", "without_type_s")}
    b, n = rows["base"][0], rows["new"][0]
    kb, kn, lin = np.array(b["K_over_M_c"]), np.array(n["K_over_M_c"]), np.array(n["K_over_M_c_linear"])
    has = np.isfinite(lin)
    amp_b, amp_n = np.array(b["limit_cycle_amplitude"]), np.array(n["limit_cycle_amplitude"])
    both = np.isfinite(amp_b) & np.isfinite(amp_n)
    rtol = 1e-3  # locate_hopf's default
    return {"base_tree": str(base), "base_commit": subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=base,
                                                                   capture_output=True, text=True).stdout.strip(),
            "velocities": len(lin), "with_line": int(has.sum()),
            "seconds_with_type_1thread": best["with_type_s"], "seconds_without_type_1thread": best["without_type_s"],
            "speedup_with_type_1thread": best["with_type_s"]["base"] / best["with_type_s"]["new"],
            "speedup_without_type_1thread": best["without_type_s"]["base"] / best["without_type_s"]["new"],
            "new_seconds_with_type_2threads": two["with_type_s"],
            "types_equal": b["bifurcation"] == n["bifurcation"],
            "same_velocities_without_line": bool(np.array_equal(np.isnan(kb), np.isnan(kn))),
            "max_rel_diff_K_over_M_c_new_vs_base": float(np.max(np.abs(kn[has] / kb[has] - 1))),
            "within_rtol_of_base": bool(np.all(np.abs(kn[has] / kb[has] - 1) <= rtol)),
            "max_rel_distance_to_linear": {"base": float(np.max(np.abs(kb[has] / lin[has] - 1))),
                                           "new": float(np.max(np.abs(kn[has] / lin[has] - 1)))},
            "limit_cycle_amplitude_max_rel_diff": float(np.max(np.abs(amp_n[both] / amp_b[both] - 1)))
            if both.any() else None,
            "simulations_per_velocity_mean": {name: float(np.mean(np.array(r[0]["simulations"])[has]))
                                              for name, r in rows.items()},
            "rows": {name: [{k: v for k, v in r.items() if k.endswith("_s") or k == "loadavg"} for r in runs]
                     for name, runs in rows.items()},
            "new_2threads": {k: v for k, v in two.items() if k.endswith("_s") or k == "loadavg"},
            "target": {"speedup_with_type_1thread": 10.0,
                       "met": best["with_type_s"]["base"] / best["with_type_s"]["new"] >= 10.0}}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="tiny sets, one timed call each (a smoke run)")
    ap.add_argument("--out", type=Path, default=OUT / "hopf.json", help="the JSON (the PNG beside it, .png)")
    ap.add_argument("--no-png", action="store_true")
    ap.add_argument("--only-lyapunov", action="store_true", help="the type of the line from l1 alone")
    ap.add_argument("--base", type=Path, default=Path("/tmp/hopf_base"), help="the tree before (line A/B)")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--threads", type=int, default=1, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    quick = args.quick
    if args.worker:
        return line_worker(args.worker, args.threads, quick)
    if args.only_lyapunov:
        out = args.out if args.out != OUT / "hopf.json" else OUT / "lyapunov.json"
        t_start = time.perf_counter()
        result = {"benchmark": "hopf --only-lyapunov" + (" --quick" if quick else ""), "quick": quick,
                  "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "machine": machine_info(),
                  "loadavg_start": loadavg(), "lyapunov": lyapunov_part(quick)}
        result["loadavg_end"], result["benchmark_wall_s"] = loadavg(), time.perf_counter() - t_start
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(result, indent=1))
        print(json.dumps(result, indent=1))
        print(f"wrote {out}")
        return
    v_line = V_LINE_QUICK if quick else V_LINE
    grid = GRID_QUICK if quick else GRID
    repeats = 1 if quick else 3
    # the inertial line over gamma/A = 10^lo .. 10^hi (quick: 0.1 and 10; 1e-3 costs seconds to type), the deep grid
    (lo, hi, n_fast), deep_shape = ((-1, 1, 2), (4, 2)) if quick else ((-3, 1, 10), (13, 7))
    t_start = time.perf_counter()
    digest0, load0 = sweep_digest(), loadavg()
    ab = line_ab(args.base, quick)
    sweep.locate_hopf(PARAMS, v_line[:2])  # compile / load the kernels
    numba.set_num_threads(1)
    t_typed, line = best_of(lambda: sweep.locate_hopf(PARAMS, v_line), 1)
    t_sim, line_only = best_of(lambda: sweep.locate_hopf(PARAMS, v_line, bifurcation=False), repeats)
    t_lin, lin = best_of(lambda: physics.hopf_K_over_M(v_line, PARAMS.A, PARAMS.m1, PARAMS.m2, PARAMS.D0,
                                                       PARAMS.V0, PARAMS.g), 20)
    inertial_params = PARAMS.replace(m2=0.0)  # mu1 = m1 at every V: the inertial line up to gamma/A = 10
    v_fast = np.sqrt(np.logspace(lo, hi, n_fast) * PARAMS.g * PARAMS.D0 * PARAMS.A)
    # the inertial driven kernels outside the timings: the one-point driver, compiled in every process
    # (INERTIAL_NOT_CACHED), for the growth-rate runs, and the inertial lanes for the type's fuller rounds
    # (sweep/analysis/hopf_batch.py: INERTIAL_LANES_FROM)
    sweep.locate_hopf(inertial_params, v_fast[-1:], model="inertial", bifurcation=False, lyapunov=False)
    sweep.locate_hopf(inertial_params, v_fast, model="inertial", lyapunov=False)
    t_inertial, inertial = best_of(lambda: sweep.locate_hopf(inertial_params, v_fast, model="inertial",
                                                             bifurcation=False), 1)
    t_inertial_typed, inertial_typed = best_of(lambda: sweep.locate_hopf(inertial_params, v_fast, model="inertial"), 1)
    inertial_kinds = [inertial_typed["bifurcation"].attrs["flag_meanings"].split()[c]
                      for c in inertial_typed["bifurcation"].values]
    deep = sweep.Scene(protocol="driven", params=inertial_params, model="inertial",
                       K_over_M=np.linspace(0.3, 1.5, deep_shape[0]) * PARAMS.m1 * PARAMS.g / PARAMS.D0,
                       V=np.sqrt(np.logspace(-3, 0, deep_shape[1]) * PARAMS.g * PARAMS.D0 * PARAMS.A))
    warm = sweep.Scene(protocol="driven", params=inertial_params, model="inertial", K_over_M=deep.K_over_M[:1],
                       V=deep.V[:1])
    sweep.run_sweep(warm, progress=False)  # its inertial batch kernel, compiled in every process, outside the timing
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
    sweep.run_sweep(auto_scene, progress=False)  # its inertial kernels compiled (or loaded) outside the timing
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
        "line_ab": ab,
        "lyapunov": lyapunov_part(quick),
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
