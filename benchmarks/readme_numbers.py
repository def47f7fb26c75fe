"""Render docs/benchmarks.md and the measured numbers of the README and docs/ from benchmarks/results/*.json.

Measured figures are never typed by hand into user documentation. Two things come from the JSON files that the
benchmark scripts write into benchmarks/results/:

- docs/benchmarks.md, written whole by :func:`render_benchmarks`: every figure once, each section with the
  machine, date, commit and versions that its JSON records (the only page of the docs that names them);
- marked spans ``<!-- n:KEY -->27<!-- /n -->`` (invisible in the rendered markdown) in README.md and in the docs
  pages of :data:`PAGES`: the text of each span is the value of KEY in :data:`NUMBERS`.

Run it after a benchmark run:

    python benchmarks/readme_numbers.py          # rewrite docs/benchmarks.md and the marked spans
    python benchmarks/readme_numbers.py --check  # exit 1 if any of them is out of date; write nothing
    python benchmarks/readme_numbers.py --out /tmp/n.json   # write nothing but the numbers as JSON

With --out the script only reads: it writes every key's value, the README's spans and whether README.md is up to
date to that JSON. --quick changes nothing (the script reads a few small files); it is accepted so that every
script in benchmarks/ takes the same smoke-run flags (tests/test_benchmarks.py). The script imports nothing from
sweep.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
README = ROOT / "README.md"
BENCHMARKS_MD = ROOT / "docs" / "benchmarks.md"
PAGES = [README, *(ROOT / "docs" / name for name in ("index.md", "user-guide.md", "cli.md", "physics.md", "fit.md"))]
"""The pages whose marked spans are filled (docs/benchmarks.md is rendered whole)."""
SPAN = re.compile(r"<!-- n:(?P<key>[\w.]+) -->(?P<text>.*?)<!-- /n -->")


def _json(name: str) -> dict:
    return json.loads((RESULTS / f"{name}.json").read_text())


def _sci(x: float) -> str:
    """4.7e-4, 1e-6 (at most two digits, no zero-padded exponent)."""
    mantissa, exponent = f"{x:.1e}".split("e")
    return f"{mantissa.removesuffix('.0')}e{int(exponent)}"


def _level(x: float | str) -> str:
    """1e-3 for 0.001 (an error level or a tolerance)."""
    return f"1e{int(round(math.log10(float(x))))}"


def _x(x: float, digits: int = 1) -> str:
    return f"{x:.{digits}f}x"


def _pct(x: float) -> str:
    return f"{100 * x:.1f} %"


def _int(x: float) -> str:
    return f"{round(x):,}"


# --- the figures -------------------------------------------------------------------------------------------------

def _peer_rows(scene: str) -> list[tuple[str, str, float | None, float | None]]:
    """(error level, best peer, run_sweep 1 thread speed-up, kernel path 1 thread speed-up) of one scene."""
    rows = []
    for level, entry in _json("peers")["scenes"][scene]["ratios"]["grid"]["matched_accuracy"].items():
        speedup = entry.get("engine_speedup_vs_best_peer") or {}
        rows.append((_level(level), entry.get("best_peer") or "", speedup.get("engine_run_sweep_1t"),
                     speedup.get("engine_execute_1t")))
    return rows


def _peer_speedups(scene: str) -> list[float]:
    return [r[2] for r in _peer_rows(scene) if r[2] is not None]


def _peer_levels(scene: str) -> list[str]:
    return [r[0] for r in _peer_rows(scene) if r[2] is not None]


def _auto() -> dict:
    return _json("models")["cost"]["default_scene"]


NUMBERS: dict[str, Callable[[], str]] = {
    "peers_points": lambda: f"{_json('peers')['scenes']['default']['points']:,}",
    "peers_min": lambda: f"{min(_peer_speedups('default')):.1f}",
    "peers_max": lambda: f"{max(_peer_speedups('default')):.1f}",
    "peers_loosest": lambda: _peer_levels("default")[0],
    "peers_tightest": lambda: _peer_levels("default")[-1],
    "auto_inertial_points": lambda: f"{_auto()['auto']['inertial_points']:,}",
    "auto_points": lambda: f"{_auto()['points']:,}",
    "auto_largest_quasistatic_error": lambda: _sci(
        _auto()["model_error_vs_inertial_rtol_1e-6"]["auto"]["max_true_error_on_quasistatic_points"]),
    "cold_process_s": lambda: f"{_json('throughput')['cold_start']['process_wall_s_median']:.1f}",
    "fit_record_one_s": lambda: f"{_json('fit_records')['one_record_warm_s']:.2f}",
    "fit_record_local_s": lambda: f"{_json('fit_records')['one_record_local_s']:.3f}",
    "fit_records_shared_s": lambda: f"{_json('fit_records')['hundred_records_s']:.1f}",
    "fit_records_own_s": lambda: f"{_json('fit_records')['hundred_records_own_times_s']:.1f}",
    "fit_records_own_local_s": lambda: f"{_json('fit_records')['hundred_records_own_times_local_s']:.1f}",
    "fit_records_scipy_s": lambda: f"{_json('fit_records')['scipy_least_squares_s']:.2f}",
    "fit_records_local_one_x": lambda: _x(_json('fit_records')['speedup_local_one_record']),
    "fit_records_local_per_record_x": lambda: f"{_json('fit_records')['speedup_local_per_record']:.0f}x",
    "fit_records_local_fresh_x": lambda: f"{_json('fit_records')['speedup_local_per_record_fresh']:.0f}x",
    "cold_import_s": lambda: f"{_json('throughput')['cold_start']['import_only_process_wall_s_median']:.1f}",
}
"""Key of a marked span -> its text, from the measurement."""


# --- docs/benchmarks.md ------------------------------------------------------------------------------------------

def _record(name: str) -> str:
    """What benchmarks/results/NAME.json records about where and when it was measured, as one paragraph."""
    d = _json(name)
    machine = d.get("machine") or {}
    versions = {**(machine.get("versions") or {}), **(d.get("versions") or {})}
    for key in ("python", "numpy", "numba"):  # some scripts record the versions beside the machine
        if key in machine and key not in versions:
            versions[key] = machine[key]
    commit = versions.pop("git_commit", None) or versions.pop("sweep_git_commit", None)
    dirty = versions.pop("sweep_tree_dirty", None)
    cpu = machine.get("cpu") or machine.get("cpu_model") or "CPU not recorded"
    cpus = machine.get("logical_cpus")
    parts = [f"date {d['date']}" if d.get("date") else "date not recorded",
             f"commit {commit}" + (" (with uncommitted changes)" if dirty else "") if commit else
             "commit not recorded",
             cpu + (f", {cpus} logical CPUs" if cpus else ""),
             machine.get("platform", "platform not recorded")]
    if machine.get("NUMBA_NUM_THREADS"):
        parts.append(f"NUMBA_NUM_THREADS {machine['NUMBA_NUM_THREADS']}")
    text = f"Recorded in `benchmarks/results/{name}.json`: " + "; ".join(parts)
    if versions:
        text += "; " + ", ".join(f"{k} {v}" for k, v in versions.items())
    return text + "."


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    return lines + ["| " + " | ".join(row) + " |" for row in rows]


def _fmt(x: float | None, digits: int = 1) -> str:
    return "-" if x is None else _x(x, digits)


def _peers() -> list[str]:
    d = _json("peers")
    default, corner = d["scenes"]["default"], d["scenes"]["corner"]
    rows = []
    for (level, peer, rs, ex), (_, cpeer, crs, cex) in zip(_peer_rows("default"), _peer_rows("corner"), strict=True):
        rows.append([level, peer or "none reaches it", _fmt(rs), _fmt(ex), cpeer or "none reaches it", _fmt(crs),
                     _fmt(cex)])
    return [
        "## The engine against the tools a user would pick instead", "",
        "`python benchmarks/peers.py` (extra `[bench]`): numbalsoda's LSODA from an njit prange loop, diffrax Tsit5 "
        "under jax.vmap on CPU and scipy, each given the engine's own contact-age formulation and closed-form "
        "tail, on the same points. A tool's figure at an error level is its cheapest run whose largest relative "
        "error over the grid is at most that level; the speed-up is the best peer's time per trajectory per core "
        "over the engine's (one thread; compile time excluded for every tool).", "",
        f"Scenes: the default scene ({default['points']:,} points, model quasistatic) and its corner "
        f"(chi/A <= 0.1 and mu1 < 0, {corner['points']:,} points).", "",
        *_table(["max error", "best peer (default)", "`run_sweep`", "kernel path", "best peer (corner)",
                 "`run_sweep`", "kernel path"], rows), "",
        _record("peers"), "",
    ]


def _work_precision() -> list[str]:
    d = _json("work_precision")
    rows = [[_level(r["level"]), f"`{r['engine_best']}`", f"{r['engine_us']:.2f}", f"`{r['scipy_best']}`",
             f"{r['scipy_us']:.0f}", _x(r["speedup"], 0)] for r in d["summary"]["speedup_by_error_level"]]
    auto = [[_level(r["rtol"]), f"{r['auto_over_fastest']:.2f}"] for r in d["summary"]["auto_vs_fastest"]]
    return [
        "## Work against precision", "",
        f"`python benchmarks/work_precision.py`: achieved error against CPU time per trajectory on "
        f"{len(d['problems'])} stop problems (the stiff corner and a slow tail included), for every engine "
        "configuration and scipy's DOP853, LSODA and Radau, against a reference at relative error 1e-13; one "
        "thread. At each error level, the fastest configuration of each side that reaches it:", "",
        *_table(["error", "engine", "us", "scipy", "us", "speed-up"], rows), "",
        "`method=\"auto\"` at each rtol, time over the fastest float64 configuration that meets the same error "
        "(picked after the fact):", "",
        *_table(["rtol", "auto / fastest"], auto), "",
        _record("work_precision"), "",
    ]


def _throughput() -> list[str]:
    d = _json("throughput")
    one, two = d["engine"]["threads_1"], d["engine"]["threads_2"]
    cold = d["cold_start"]
    lines = [
        "## Throughput, cold start and the dry-run estimate", "",
        f"`python benchmarks/throughput.py` on the default scene at rtol {_sci(d['scene']['rtol'])}, "
        f"method `{d['engine']['method']}` as planned at the recorded commit:", "",
        f"- trajectories per second: {_int(one['traj_per_s'])} on 1 thread, {_int(two['traj_per_s'])} on 2 "
        f"threads; {one['ns_per_stage_eval_per_core']:.1f} ns per stage evaluation (1 thread);",
        f"- a numpy-vectorised RK4 doing the same runs: {d['numpy_rk4']['numpy_over_engine_per_eval']:.1f}x the "
        "engine's time per evaluation;",
        f"- a new process that imports sweep and runs a 10 x 10 sweep with the kernels in numba's cache: "
        f"{cold['process_wall_s_median']:.1f} s (median), {cold['import_only_process_wall_s_median']:.1f} s of it "
        "importing sweep;",
    ]
    for e in d["estimate"]:
        lines.append(f"- `--dry-run`'s time estimate on {e['scene']}: {e['estimate_over_measured']:.2f}x the "
                     "measured time;")
    lines[-1] = lines[-1][:-1] + "."
    return [*lines, "", _record("throughput"), ""]


def _models() -> list[str]:
    d = _json("models")
    default, inertia = d["cost"]["default_scene"], d["cost"]["inertia_scene"]
    acc = d["accuracy_inertia_scene_model_tol_1e-2"]
    tol_rows = [[_level(r["model_tol"]), f"{r['inertial_fraction']:.0%}".replace("%", " %"),
                 _sci(r["max_true_error"]), f"{r['wall_s_best_of_3']:.2f}"] for r in d["model_tol_sweep_inertia_scene"]]
    gamma = inertia["gamma_over_A_range"]
    return [
        "## What the choice of model costs and buys", "",
        "`python benchmarks/models.py`: `model=\"auto\"` against the forced quasi-static and inertial models, "
        "wall time best of 3; true errors against an inertial reference at rtol 1e-9.", "",
        *_table(["scene", "points", "solved with inertia (auto)", "auto / quasistatic", "inertial / quasistatic",
                 "largest quasi-static error"], [
            ["default", f"{default['points']:,}", f"{default['auto']['inertial_points']:,}",
             "next section", _x(default["inertial_over_quasistatic"]["wall"], 0),
             _sci(default["model_error_vs_inertial_rtol_1e-6"]["quasistatic"]["max_true_error"])],
            [f"inertia scene (gamma/A {_sci(gamma[0])}..{gamma[1]:.1f})", f"{inertia['points']:,}",
             f"{inertia['auto']['inertial_points']:,}", _x(inertia["auto_over_quasistatic"]["wall"], 0),
             _x(inertia["inertial_over_quasistatic"]["wall"], 0), _sci(acc["quasistatic"]["max_true_error"])],
        ]), "",
        f"The inertia scene is {d['settings']['inertia_scene']}. On it, at model_tol 1e-2, auto's largest true "
        f"error is {_sci(acc['auto']['max_true_error'])} ({acc['auto']['violations_true_error_above_model_tol']} "
        "points above model_tol). Over model_tol:", "",
        *_table(["model_tol", "solved with inertia", "largest true error", "wall s"], tol_rows), "",
        _record("models"), "",
    ]


def _auto_cost() -> list[str]:
    d = _json("auto_cost")
    rows = [[f"{r['points']:,}", str(r["threads"]), _x(r["auto_over_quasistatic"], 2),
             str(r["auto_inertial_points"])] for r in d["rows"]]
    return [
        "## The cost of `model=\"auto\"` on the default parameters", "",
        "`python benchmarks/auto_cost.py`: `run_sweep` wall time with `model=\"auto\"` over the same sweep forced "
        "quasi-static (sample2, rtol 1e-6):", "",
        *_table(["points", "threads", "auto / quasistatic", "points solved with inertia"], rows), "",
        _record("auto_cost"), "",
    ]


def _end_to_end() -> list[str]:
    d = _json("end_to_end")
    best, scene = d["best"], d["scene"]
    parts = sorted(best["parts_s"].items(), key=lambda kv: -kv[1])[:5]
    return [
        "## End to end", "",
        f"`python benchmarks/end_to_end.py`: `sweep run` of a {scene['shape'][0]} x {scene['shape'][1]} grid "
        f"({scene['points']:,} points, {scene['preset']}, rtol {_sci(scene['rtol'])}, model {scene['model']}) "
        "into a netCDF file and its picture, in process:", "",
        f"- {best['total_s']:.2f} s in all, {best['ratio_total_over_kernel']:.2f}x the kernels' "
        f"{best['parts_s']['kernel']:.2f} s (parts overlap: the journal and the netCDF file are written in helper "
        "threads);",
        "- the largest parts, s: " + ", ".join(f"{k} {v:.2f}" for k, v in parts) + ";",
        f"- the same from a new process (`sweep run` on the command line): {d['fresh_process']['best']['wall_s']:.1f}"
        " s.", "",
        _record("end_to_end"), "",
    ]


def _cold_start() -> list[str]:
    d = _json("cold_start")
    spread = lambda t, key: f"{t[key + '_median']:.1f} ({t[key + '_min']:.1f}-{t[key + '_max']:.1f})"  # noqa: E731
    rows = [[label, t["commit"] or "", str(len(t["runs"])), spread(t, "wall_s"), spread(t, "cpu_s"),
             ", ".join(f"{r['load_before'][0]:.1f}" for r in t["runs"])] for label, t in d["trees"].items()]
    top = d["compile_by_function"]["this tree"][:4]
    targets = d["targets"]
    return [
        "## First run on a machine", "",
        f"`python benchmarks/cold_start.py`: {d['scene']} from an empty numba cache ({d['command']}), the trees "
        "alternated; median (range) of the runs:", "",
        *_table(["tree", "commit", "runs", "wall s", "CPU s", "1-min load average before each run"], rows), "",
        f"Targets (issue 37): wall {targets['wall_s']['target']} s, CPU {targets['cpu_s']['target']} s on two cores. "
        "Compile CPU seconds of this tree's largest functions (without what compiles inside them): "
        + ", ".join(f"`{k['function'].rsplit('.', 1)[-1]}` {k['exclusive_cpu_s']:.1f}" for k in top) + ".", "",
        _record("cold_start"), "",
    ]


def _out_of_core() -> list[str]:
    d = _json("out_of_core")
    rows = []
    for r in d["runs"]:
        rows.append([f"{r['points']:,}", "dask, 2 workers" if r["extra_args"] else "threads", f"{r['wall_s']:.1f}",
                     f"{r['compute_s']:.1f}", f"{r['wall_over_compute']:.2f}", f"{r['peak_rss_bytes'] / 2**30:.2f}",
                     f"{r['file_bytes'] / 2**30:.2f}", f"{r['loadavg_start_end'][0][0]:.1f}"])
    dask = [r for r in d["runs"] if r["extra_args"]]
    merged = d.get("merged_from")
    note = ([f"The rows of {', '.join(f'{r[0]:,}' for r in d['remeasured'])} points were measured again "
             f"(`--merge`); the others come from the run of commit {merged['commit']}.", ""]
            if merged and d.get("remeasured") else [])
    lines = [
        "## Sweeps larger than memory", "",
        "`python benchmarks/out_of_core.py`: `sweep run` of the default scene's ranges (sample2, rtol 1e-6, model "
        "auto) on grids of N points, each in a new process; peak RSS of that process; wall time of the whole command "
        "against its chunk loop (computing, journal and file written as the chunks finish):", "",
        *_table(["points", "backend", "wall s", "chunk loop s", "wall / loop", "peak RSS GiB", "file GiB",
                 "1-min load before"], rows), "", *note,
    ]
    if dask:
        same = "bit for bit" if dask[0].get("bitwise_equal") else f"except {dask[0].get('differing')}"
        lines += [f"The dask run's file equals the threads run's {same} ({dask[0].get('values_compared', 0):,} "
                  "values compared).", ""]
    if "per_chunk" in d:
        c = d["per_chunk"]
        x = c["extrapolation_1e11_on_1000_workers"]
        rows = x["by_chunk_points"]
        lines += [f"Per chunk, the driver pays {c['scheduler_s_per_chunk'] * 1e3:.1f} ms of dask scheduling (over "
                  f"the threads backend) and its writer {c['writer_s_per_chunk'] * 1e3:.2f} ms + "
                  f"{c['writer_s_per_point'] * 1e9:.0f} ns a point. A 1e11-point sweep on 1,000 workers at "
                  f"{_int(x['points_per_core_s'])} points/s each computes in {x['compute_s']:.0f} s; one driver "
                  "would then be busy " + ", ".join(
                      f"{r['scheduler_busy']:.2g} s (scheduling) and {r['writer_busy']:.2g} s (writing) per second "
                      f"with chunks of {int(k):,} points" for k, r in rows.items())
                  + ": above 1 it cannot keep up, so such a cluster needs its regions written by the workers (as "
                  "many writers as the writing's busy seconds) and chunks of ~1e6 points.", ""]
    return lines + [_record("out_of_core"), ""]


def _hopf() -> list[str]:
    d = _json("hopf")
    line, grid, auto = d["line"], d["driven_grid"], d["driven_grid_auto"]
    deep = d["inertial_driven_deep_stick_slip"]
    return [
        "## Hopf line and driven grids", "",
        "`python benchmarks/hopf.py`:", "",
        f"- the Hopf line by simulation over {line['velocities']} velocities: {line['seconds_simulation_1thread']:.3f}"
        f" s on one thread ({line['seconds_simulation_with_type_1thread']:.2f} s with the bifurcation type), "
        f"{_sci(line['simulation_over_analytic'])}x the analytic line; largest relative distance to eq. 3: "
        f"{_sci(line['max_rel_distance_to_linear'])};",
        *([] if "line_ab" not in d else [
            f"- the same {d['line_ab']['velocities']} velocities against the code of {d['line_ab']['base_commit']} "
            f"(A/B in one run, one thread): {d['line_ab']['seconds_with_type_1thread']['base']:.2f} -> "
            f"{d['line_ab']['seconds_with_type_1thread']['new']:.2f} s with the type "
            f"({_x(d['line_ab']['speedup_with_type_1thread'])}), "
            f"{d['line_ab']['seconds_without_type_1thread']['base']:.3f} -> "
            f"{d['line_ab']['seconds_without_type_1thread']['new']:.3f} s without "
            f"({_x(d['line_ab']['speedup_without_type_1thread'])}); simulations per velocity to locate the line "
            f"{d['line_ab']['simulations_per_velocity_mean']['base']:.1f} -> "
            f"{d['line_ab']['simulations_per_velocity_mean']['new']:.1f}; types "
            + ("unchanged" if d['line_ab']['types_equal'] else "CHANGED") + ";"]),
        f"- a quasi-static driven grid of {grid['shape'][0]} x {grid['shape'][1]} points: "
        f"{_int(grid['threads_1']['points_per_s'])} points/s on 1 thread, {_int(grid['threads_2']['points_per_s'])} "
        "on 2;",
        f"- the same grid with `model=\"auto\"` ({auto['points_run_with_inertia']} points run with inertia): "
        f"{_int(auto['points_per_s'])} points/s on {auto['threads']} threads;",
        f"- an inertial driven grid deep in stick-slip ({deep['shape'][0]} x {deep['shape'][1]}): "
        f"{deep['points_per_s']:.0f} points/s on one thread.", "",
        _record("hopf"), "",
    ]


def _scaling() -> list[str]:
    d = _json("scaling")
    rows = [[f"{int(n):,}", _int(v["threads_1"]["points_per_s_wall"]), _int(v["threads_2"]["points_per_s_wall"])]
            for n, v in d["threads"].items()]
    mem = [[f"{int(n):,}", f"{v['process_wall_s']:.1f}", f"{v['peak_rss_bytes'] / 2**30:.2f}"]
           for n, v in d["memory"].items()]
    traj = [[f"{int(n):,} (with `trajectory`)", f"{v['process_wall_s']:.1f}", f"{v['peak_rss_bytes'] / 2**30:.2f}"]
            for n, v in d["memory_trajectories"].items()]
    t = d["targets"]
    return [
        "## Scaling with the number of points, threads and dask", "",
        f"`python benchmarks/scaling.py`: {d['settings']['scene']}; points per second of `run_sweep` wall time:", "",
        *_table(["points", "1 thread", "2 threads"], rows), "",
        f"The dask backend with 2 workers over the threads backend at 1,000,000 points: "
        f"+{_pct(t['dask_overhead_at_1000000_running_cluster'])} on a running cluster, "
        f"+{_pct(t['dask_overhead_at_1000000_new_cluster'])} where the call starts and stops its own. "
        "Peak memory of `sweep run` in a process of its own:", "",
        *_table(["points", "wall s", "peak RSS GiB"], mem + traj), "",
        _record("scaling"), "",
    ]


def _axes() -> list[str]:
    d = _json("axes")
    s, r = d["settings"], d["throughput_ratios"]
    return [
        "## Extra axes", "",
        f"`python benchmarks/axes.py`: points per second of a sweep over (K/M, V, A, m1) over those of a 2-D sweep "
        f"of as many points ({s['n_side']} x {s['n_side']}, rtol {_sci(s['rtol'])}): {r['4d_over_2d']:.2f}; "
        f"with the same physics on both sides: {r['4d_same_physics_over_2d']:.2f}.", "",
        _record("axes"), "",
    ]


def _error_coverage() -> list[str]:
    d = _json("error_coverage")
    rows = [[_level(r["rtol"]), f"{r['points']:,}", str(r["ok_beyond_tol"]), _pct(r["bounded"]),
             f"{r['max_true_over_estimate']:.1f}", str(r["error_above_tol"]), str(r["false_alarms"])]
            for r in d["rows"]]
    return [
        "## Error estimates on a table of extremes", "",
        "`python benchmarks/error_coverage.py`: points over A, chi/A, mu1/A and m2/A far beyond the presets, "
        f"method {d['rows'][0]['method']}, against a scipy reference. *ok beyond tol*: points with status ok whose "
        "true error exceeds the tolerance; *bounded*: the share of points whose estimate is at least the true "
        "error; *false alarms*: `error_above_tol` points whose true error is below rtol/10.", "",
        *_table(["rtol", "points", "ok beyond tol", "bounded", "largest true / estimate", "error_above_tol",
                 "false alarms"], rows), "",
        _record("error_coverage"), "",
    ]


def _fit() -> list[str]:
    d = _json("fit")
    s = d["settings"]
    return [
        "## Fits", "",
        f"`python benchmarks/fit.py`: {', '.join(s['free'])} free, curves of {s['samples']} samples at K/M "
        f"{_sci(s['K_over_M'])} s-2, V {_sci(s['V'])} m/s with relative noise {s['noise_relative_to_relaxed_slip']}"
        " (docs/fit.md):", "",
        f"- one curve with the global stage, least squares and profiles: {d['one_curve']['wall_s']:.3f} s;",
        f"- {d['many_curves']['curves']} curves in one call: {d['many_curves']['wall_s']:.2f} s;",
        f"- scipy's least_squares over solve_ivp ({d['scipy']['method']}, no global stage, no profiles): "
        f"{d['scipy']['wall_s_per_curve']:.2f} s a curve, {d['ratio_per_curve']:.0f}x the engine's time per curve "
        f"by wall time, {d['ratio_per_curve_cpu']:.0f}x by CPU time.", "",
        _record("fit"), "",
    ]


def _against_reference(ref: dict | None) -> list[str]:
    """The quasi-static outputs of both trees against the 1e-12 reference run (driven_lanes.py), one sentence."""
    if not ref:
        return []
    text = "; ".join(
        f"{name} {r['amplitude_rel_err_max']:.1e} (median {r['amplitude_rel_err_median']:.1e}), periods "
        f"{r['period_rel_err_max']:.1e}, growth rates {r['growth_err_per_cycle_max']:.1e} per cycle"
        for name, r in ref.items())
    return ["Quasi-static outputs against the same grid with the driven stepper at 1e-12 (largest relative error of "
            f"the stick-slip amplitudes): {text}.", ""]


def _driven() -> list[str]:
    lanes, scaling, peers = _json("driven_lanes"), _json("driven_scaling"), _json("peers_driven")
    moved = {key: f"{n['moved_firm']} of {n['moved']}" for key, n in lanes["numbers"].items()}
    rows = [[key.replace("_1t", ", 1 thread").replace("_2t", ", 2 threads"), f"{f['points']:,}",
             _int(f["base_points_per_s_per_core"]), _int(f["new_points_per_s_per_core"]),
             _x(f["speedup_new_over_base"]), moved[key]] for key, f in lanes["figures"].items()]
    scale = [[model, f"{f['points']:,}", f"{f['best_wall_s']['1']:.2f}",
              f"{f['best_wall_s'][str(f['threads'])]:.2f}", _x(f["speedup_all_threads"], 2),
              "yes" if f["regimes_equal"] else "NO"]
             for model, f in scaling["figures"].items()]
    peer_rows = []
    def per_model(m: dict) -> tuple[str, str]:  # a scene of both models: each model's best peer
        pm = m.get("best_peer_per_model")
        if not pm:
            return "none reaches it", "-"
        return (" + ".join(f"{p['tool']} ({cls})" for cls, p in pm["models"].items()),
                _fmt(m.get("engine_1t_speedup_vs_best_peer_per_model")))

    for scene, sc in peers["scenes"].items():  # levels with the same best peer and ratio in one row
        kinds = [(scene, lambda m: (m.get("best_peer") or "none reaches it",
                                    _fmt(m.get("engine_1t_speedup_vs_best_peer"))))]
        if any("best_peer_per_model" in m for m in sc["matched"].values()):
            kinds.append((f"{scene}, best peer per model", per_model))
        for label, pick in kinds:
            runs: list[list] = []
            for level, m in sc["matched"].items():
                row = pick(m)
                if runs and runs[-1][2:] == list(row):
                    runs[-1][1] = level
                else:
                    runs.append([level, level, *row])
            peer_rows += [[label, _level(lo) if lo == hi else f"{_level(hi)} .. {_level(lo)}", best, ratio]
                          for lo, hi, best, ratio in runs]
    return [
        "## Driven scene in lanes", "",
        f"`python benchmarks/driven_lanes.py`: {lanes['settings']['grid']}, the code of {lanes['base_commit'][:7]} "
        "(base) against this one in one run; points per second per core; *moved*: points whose regime differs from "
        "the base's (steady, stick_slip or runaway of them / all, undecided and neutral included):", "",
        *_table(["grid, model, threads", "points", "base", "new", "speed-up", "moved"], rows), "",
        *_against_reference(lanes["numbers"]["quasistatic_1t"].get("against_reference")),
        _record("driven_lanes"), "",
        f"`python benchmarks/driven_scaling.py`: {scaling['settings']['grid']}, wall seconds of the driven chunk on "
        "1 thread and on all threads; the regimes of the two agree point for point"
        + (f"; the machine's own gain from a second thread in the same run (a loop that shares nothing): "
           f"{_x(scaling['machine_two_threads_over_one'], 2)}" if "machine_two_threads_over_one" in scaling else "")
        + ":", "",
        *_table(["model", "points", "1 thread s", "all threads s", "speed-up", "regimes equal"], scale), "",
        _record("driven_scaling"), "",
        f"`{peers['benchmark']}`: the engine's time per point per core (1 thread) over the best peer's at each "
        "error level that both reach: growth rate per cycle and amplitude (relative) within it against scipy Radau "
        "at 1e-10, every regime the reference's (benchmarks/README.md):", "",
        *_table(["scene", "error level", "best peer", "engine speed-up"], peer_rows), "",
        _record("peers_driven"), "",
    ]


def _histories() -> list[str]:
    h, read, fit = _json("history"), _json("records_read"), _json("fit_records")
    shs, grid = h["shs_point"]["chunk_1_points"], h["grid"]
    worst = read["targets"]["read_and_segment_s_worst"]
    lines = [
        "## Load histories and laboratory records", "",
        f"`python benchmarks/history.py`: a slide-hold-slide series of 8 holds (1..1000 s) "
        f"{shs['ms_per_point_cpu']:.2f} ms a point, {h['shs_point']['chunk_256_points']['ms_per_point_cpu']:.2f} ms a "
        f"point in a chunk of 256; a {grid['points']:,}-point sweep of it over "
        + " x ".join(f"{k} {v}" for k, v in grid["shape"].items() if v > 1) + f" {grid['wall_s']:.1f} s "
        f"({grid['cpu_s'] / grid['wall_s']:.1f} cores busy).", "",
        _record("history"), "",
        f"`python benchmarks/records_read.py`: files of 1e5 rows read and their load history found in "
        f"{worst:.1f} s at most (" + ", ".join(f"{name.replace('_', ' ')} {f['read_s_best']:.2f} + "
                                            f"{f['segment_s_best']:.2f} s" for name, f in read["files"].items())
        + ").", "",
        _record("records_read"), "",
        f"`python benchmarks/fit_records.py`: one {fit['samples_per_record']:,}-sample velocity-step record (a, b, Dc, "
        f"mu0 free) {fit['one_record_warm_s']:.2f} s warm; {fit['records']} records in one call "
        f"{fit['hundred_records_own_times_s']:.1f} s with their own sample times, {fit['hundred_records_s']:.1f} s "
        f"sharing them; scipy's least_squares over solve_ivp from the same start {fit['scipy_least_squares_s']:.2f} s "
        f"a record: sweep.fit is {_x(fit['speedup_vs_scipy'])} faster with its global stage"
        + (f", {_x(fit['speedup_local_one_record'])} from the same start (`search=\"local\"`)"
           if "speedup_local_one_record" in fit else "")
        + (f", {_x(fit['speedup_local_per_record'])} per record of {fit['records']} fitted together from it"
           if "speedup_local_per_record" in fit else "")
        + (f" ({_x(fit['speedup_local_per_record_fresh'])} where the records are new to it: their steps and slip "
           f"events found in that call)" if "speedup_local_per_record_fresh" in fit else "") + ".", "",
        _record("fit_records"), "",
    ]
    return lines


SECTIONS = [_peers, _work_precision, _throughput, _models, _auto_cost, _end_to_end, _cold_start, _out_of_core,
            _scaling, _axes, _hopf, _driven, _error_coverage, _fit, _histories]


def render_benchmarks() -> str:
    """docs/benchmarks.md, whole, from benchmarks/results/*.json."""
    lines = [
        "# Benchmarks", "",
        "<!-- Generated by `python benchmarks/readme_numbers.py` from benchmarks/results/*.json: do not edit. -->",
        "",
        "What was measured, by which script in `benchmarks/`, and where: each section ends with the machine, date, "
        "commit and versions that its results file records. A figure measured at an older commit stays here until "
        "its script is run again; the scripts, their options and the targets are described in "
        "`benchmarks/README.md`. After a run, `python benchmarks/readme_numbers.py` renders this page again and "
        "fills the numbers quoted elsewhere in the documentation.", "",
    ]
    for section in SECTIONS:
        lines += section()
    return "\n".join(lines).rstrip() + "\n"


def rewrite(text: str) -> str:
    """``text`` with every marked span set to its measured value (KeyError for an unknown key)."""
    return SPAN.sub(lambda m: f"<!-- n:{m['key']} -->{NUMBERS[m['key']]()}<!-- /n -->", text)


def rendered() -> dict[Path, tuple[str, str]]:
    """Path -> (its text now, the text it should have), for every page this script writes."""
    out = {}
    for page in PAGES:
        if page.is_file():
            old = page.read_text()
            out[page] = (old, rewrite(old))
    out[BENCHMARKS_MD] = (BENCHMARKS_MD.read_text() if BENCHMARKS_MD.is_file() else "", render_benchmarks())
    return out


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if a page is not up to date; write nothing")
    ap.add_argument("--out", type=Path, help="write the numbers as JSON here and leave every page alone")
    ap.add_argument("--quick", action="store_true", help="accepted for the smoke run; the script is already quick")
    args = ap.parse_args(argv)
    pages = rendered()
    stale_pages = [p for p, (old, new) in pages.items() if old != new]
    if args.out is not None:
        old = README.read_text()
        spans = [m["key"] for m in SPAN.finditer(old)]
        stale = sorted({m["key"] for m in SPAN.finditer(old) if m["text"] != NUMBERS[m["key"]]()})
        result = {"benchmark": "benchmarks/readme_numbers.py", "results_dir": str(RESULTS),
                  "numbers": {key: value() for key, value in NUMBERS.items()}, "readme_spans": spans,
                  "readme_stale_keys": stale, "readme_up_to_date": README not in stale_pages,
                  "pages_out_of_date": [str(p.relative_to(ROOT)) for p in stale_pages]}
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(result, indent=1) + "\n")
        print(f"{len(spans)} marked numbers in README.md, {len(stale)} stale; {len(stale_pages)} page(s) out of "
              f"date; wrote {args.out} (no page touched)")
    if args.check:
        if stale_pages:
            names = ", ".join(str(p.relative_to(ROOT)) for p in stale_pages)
            print(f"out of date: {names}: run python benchmarks/readme_numbers.py", file=sys.stderr)
            return 1
        return 0
    if args.out is not None:
        return 0
    for page in stale_pages:
        page.write_text(pages[page][1])
    spans = sum(len(SPAN.findall(new)) for _, new in pages.values())
    print(f"{len(stale_pages)} page(s) rewritten; {spans} marked numbers and docs/benchmarks.md from "
          "benchmarks/results")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
