#!/usr/bin/env python
"""The first run on a machine: `sweep run` of the default scene from an empty numba cache, and where its time goes.

    python benchmarks/cold_start.py                      # this tree, 3 cold runs (~2 min on 2 cores)
    python benchmarks/cold_start.py --tree before=DIR    # also another sweep tree (a git worktree), alternated
    python benchmarks/cold_start.py --quick --out /tmp/c.json   # a 10 x 10 scene, one run (~30 s)

1. cold runs  ``python -m sweep.cli run -o TMP/landscape.nc -q`` (the default scene, sweep.default_scene: what a new
              user runs first), ``--runs`` times per tree, each in a new process with NUMBA_CACHE_DIR a new empty
              folder (numba then keeps its whole cache there: nothing of an earlier run is found) and PYTHONPATH the
              tree; the trees alternate. Recorded per run: wall time (the process from start to exit), CPU time
              (user + sys of the process and the processes it waited for, from os.wait4), the load average before
              and after. CPU time is the steadier figure on a shared machine: wall time counts the time the
              process waits while other processes run.
2. by kernel  one more cold process per tree runs the same command in process with a listener on numba's
              ``numba:compile`` events: the CPU seconds of the compiling thread for each compiled function,
              exclusive (without the functions compiled inside its compilation) and inclusive, the largest first.

Targets (issue 37): the cold default run <= 25 s of wall time and <= 30 s of CPU time on two cores.

Writes benchmarks/results/cold_start.json.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import cpu_model, loadavg, usable_cpus

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "cold_start.json"
TARGET_WALL_S, TARGET_CPU_S = 25.0, 30.0
QUICK_SCENE = """protocol = "stop"
preset = "sample2"
K_over_M = {start = 1e3, stop = 1e6, num = 10, spacing = "log"}
V = {start = 1e-7, stop = 1e-4, num = 10, spacing = "log"}
"""
"""--quick: a 10 x 10 grid of the default scene's ranges (the same kernels compile)."""

BY_KERNEL = r"""
import json, sys, time
from numba.core import event
spent, stack = {}, []


class Listener(event.Listener):
    def on_start(self, ev):  # CPU time of the compiling thread (a compilation runs in the thread that calls)
        f = ev.data["dispatcher"].py_func
        stack.append([f"{f.__module__}.{f.__qualname__}", time.thread_time(), 0.0])

    def on_end(self, ev):
        name, t0, inner = stack.pop()
        dt = time.thread_time() - t0
        mine = spent.setdefault(name, [0.0, 0.0])
        mine[0] += dt - inner
        mine[1] += dt
        if stack:
            stack[-1][2] += dt


event.register("numba:compile", Listener())
from sweep.cli import main
try:
    main(sys.argv[1:])
except SystemExit:
    pass
print(json.dumps(spent))
"""


def _git(tree: Path, *args: str) -> str | None:
    try:
        out = subprocess.run(["git", *args], cwd=tree, capture_output=True, text=True, timeout=10)
        return out.stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        return None


def _env(tree: Path, cache: str) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(tree), "NUMBA_CACHE_DIR": cache, "MPLBACKEND": "Agg"}


def _run_args(work: Path, scene: Path | None) -> list[str]:
    return ["run", *([str(scene)] if scene else []), "-o", str(work / "landscape.nc"), "-q"]


def cold_run(tree: Path, scene: Path | None) -> dict:
    """One `sweep run` in a new process on an empty numba cache: wall and CPU seconds, load averages."""
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as work:
        before = loadavg()
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "sweep.cli", *_run_args(Path(work), scene)], cwd=work,
                                env=_env(tree, cache), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        err = proc.stderr.read().decode(errors="replace")
        proc.stderr.close()
        if proc.returncode:
            raise RuntimeError(f"sweep run failed in {tree} ({proc.returncode}):\n{err[-3000:]}")
        return {"wall_s": round(wall, 2), "cpu_s": round(usage.ru_utime + usage.ru_stime, 2),
                "load_before": before, "load_after": loadavg()}


def by_kernel(tree: Path, scene: Path | None, top: int) -> list[dict]:
    """Compile CPU seconds per compiled function of one cold run in process, the ``top`` largest by exclusive time."""
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as work:
        proc = subprocess.run([sys.executable, "-c", BY_KERNEL, *_run_args(Path(work), scene)], cwd=work,
                              env=_env(tree, cache), capture_output=True, text=True, timeout=900)
        if proc.returncode:
            raise RuntimeError(f"the by-kernel run failed in {tree}:\n{proc.stderr[-3000:]}")
        spent = json.loads(proc.stdout.strip().splitlines()[-1])
    rows = sorted(spent.items(), key=lambda kv: -kv[1][0])
    return [{"function": name, "exclusive_cpu_s": round(own, 2), "inclusive_cpu_s": round(total, 2)}
            for name, (own, total) in rows[:top]]


def summary(runs: list[dict]) -> dict:
    wall, cpu = [r["wall_s"] for r in runs], [r["cpu_s"] for r in runs]
    return {"wall_s_median": statistics.median(wall), "wall_s_min": min(wall), "wall_s_max": max(wall),
            "cpu_s_median": statistics.median(cpu), "cpu_s_min": min(cpu), "cpu_s_max": max(cpu)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3, help="cold runs per tree (default 3)")
    ap.add_argument("--tree", action="append", default=[], metavar="LABEL=DIR",
                    help="another sweep tree to measure beside this one (repeatable)")
    ap.add_argument("--top", type=int, default=8, help="functions listed by compile time (default 8)")
    ap.add_argument("--quick", action="store_true", help="a 10 x 10 scene, one run per tree")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    trees = {"this tree": ROOT, **{label: Path(d).resolve() for label, d in (t.split("=", 1) for t in args.tree)}}
    runs = 1 if args.quick else args.runs
    with tempfile.TemporaryDirectory() as tmp:
        scene = None
        if args.quick:
            scene = Path(tmp) / "scene.toml"
            scene.write_text(QUICK_SCENE)
        measured = {label: [] for label in trees}
        for i in range(runs):
            for label, tree in trees.items():
                measured[label].append(cold_run(tree, scene))
                r = measured[label][-1]
                print(f"cold run {i + 1}/{runs} {label}: {r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} s CPU, "
                      f"load {r['load_before']}", flush=True)
        kernels = {}
        for label, tree in trees.items():
            kernels[label] = by_kernel(tree, scene, args.top)
            print(f"by kernel, {label}: " + ", ".join(f"{k['function'].rsplit('.', 1)[-1]} {k['exclusive_cpu_s']:.1f} s"
                                                     for k in kernels[label][:3]), flush=True)
    mine = summary(measured["this tree"])
    result = {
        "benchmark": "cold_start",
        "quick": args.quick,
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "machine": {"cpu": cpu_model(), "logical_cpus": os.cpu_count(), "usable_cpus": usable_cpus(),
                    "platform": platform.platform(), "versions": _versions(ROOT)},
        "scene": "a 10 x 10 grid of the default scene's ranges (--quick)" if args.quick else
                 "the default scene (sweep.default_scene: sample2, 200 x 100, rtol 1e-6, model auto)",
        "command": "python -m sweep.cli run " + ("scene.toml " if args.quick else "") + "-o landscape.nc -q, "
                   "NUMBA_CACHE_DIR a new empty folder, PYTHONPATH the tree",
        "trees": {label: {"path": str(tree), "commit": _git(tree, "rev-parse", "--short", "HEAD"),
                          "uncommitted_changes_in_sweep": bool(_git(tree, "status", "--porcelain", "sweep")),
                          "runs": measured[label], **summary(measured[label])} for label, tree in trees.items()},
        "compile_by_function": kernels,
        "targets": {"wall_s": {"value": mine["wall_s_median"], "target": f"<= {TARGET_WALL_S:g}",
                               "met": mine["wall_s_median"] <= TARGET_WALL_S},
                    "cpu_s": {"value": mine["cpu_s_median"], "target": f"<= {TARGET_CPU_S:g}",
                              "met": mine["cpu_s_median"] <= TARGET_CPU_S}},
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


def _versions(tree: Path) -> dict:
    """python, numpy, numba, llvmlite versions, the tree's commit and whether its sweep/ has uncommitted changes."""
    from importlib.metadata import version

    return {"python": platform.python_version(), "numpy": version("numpy"), "numba": version("numba"),
            "llvmlite": version("llvmlite"), "git_commit": _git(tree, "rev-parse", "--short", "HEAD"),
            "sweep_tree_dirty": bool(_git(tree, "status", "--porcelain", "sweep"))}


if __name__ == "__main__":
    sys.exit(main())
