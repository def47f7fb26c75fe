"""Where the time of a whole ``sweep run`` goes, against the time its numba kernels take (issue 17, "End to end").

    python benchmarks/end_to_end.py [--quick] [--repeats 3] [--out PATH] [--no-png]

Runs ``sweep run scene.toml -o out.nc --overwrite -q`` (``sweep.cli.main``, in this process) on the default scene's
ranges (sample2, K/M 1e3..1e6 s^-2 x V 0.1..100 um/s, rtol 1e-6, xi_inf, model auto) on a 1000 x 1000 grid: 1e6
points (``--quick``: 20 x 10, one timed run: a smoke run whose numbers mean nothing). One untimed run first loads
the kernels from numba's cache, so the timed runs measure the steady state; the best of ``--repeats`` by total wall
time is the result, every run is kept with its load average (the machine is shared).

The breakdown comes from timing wrappers put around the package's functions for the duration of the run (the
package is not changed; a wrapper costs ~1 us a call, a few hundred calls a run):

* ``kernel``: inside the compiled batch kernels (the lane kernels, fixed-step and adaptive, the per-point and slip
  batches, the inertial points of the model choice), wherever they are called from in the chunk loop;
* ``ladder_numpy``: the step ladder or the adaptive lanes' tolerance ladder (sweep/integrate/ladder.py ``climb``,
  tolerance_ladder.py ``climb_tolerances``) less its kernel calls: the serial numpy between two kernel calls;
* ``model_choice`` (less its kernels), ``chunk_other`` (the rest of the chunks' computing: error marks, the
  assembling of each chunk's arrays), ``journal`` (``Journal.write``: each chunk's checksum and atomic write, in
  the helper thread of ``Journal.background`` where the package has it), ``journal_wait`` (handing a chunk to that
  thread, waiting for it where it is behind, and for the last chunks at the end), ``consolidate`` (the rest of the
  chunk loop: chunks into the flat arrays, the progress bar);
* ``planning`` (``make_plan``), ``prepare_other`` (the checks before the work, the journal's opening),
  ``warm_up`` (kernels loaded, one point each), ``dataset`` (``build_block``: a chunk's variables, beside its
  computing), ``netcdf`` (``NetCDFRegions.put``: a block into the file, in the writer's helper thread),
  ``png`` (``plot_file``), ``cli_other`` (the rest: imports, summaries, the journal's removal);
* ``total``: the wall time of ``main``; ``ratio_total_over_kernel`` = total / kernel (issue 17's target: <= 1.3).

Then the same command in a new Python process (``fresh_process``, best of 2): what a user waits for, the
interpreter's start, the imports (xarray's netCDF writer imports dask.distributed, the picture matplotlib) and the
loading of the kernels from numba's cache included; ``wall_over_kernel`` divides it by the best in-process run's
kernel time.

Parts that run in other threads at the same time (the netCDF written while the picture is drawn, chunks journaled
in the background) are timed in their own thread, so their sum can exceed ``total``; ``overlapped_s`` says by how
much. Chunks computed side by side (sweep/run/concurrent_chunks.py: one chunk per numba thread, N at once) count their
parts at 1/N of their time in each thread: ``kernel`` is then the kernels' thread-seconds over the N threads, the
wall time the kernels alone would take on them with nothing serial between (one chunk at a time on N numba threads,
it is the wall time inside the kernel calls, as before). Writes JSON (machine, versions, load average) and a PNG
bar chart of the best run's breakdown under benchmarks/results/.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import functools
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numba
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _common import loadavg, machine_info, sweep_digest, write_result  # noqa: E402

import sweep  # noqa: E402
import sweep.api  # noqa: E402
import sweep.cli  # noqa: E402
import sweep.plot.files  # noqa: E402
import sweep.protocols.stop.chunk  # noqa: E402
import sweep.protocols.stop.engine  # noqa: E402
import sweep.protocols.stop.model_choice  # noqa: E402
import sweep.protocols.stop.schema  # noqa: E402
import sweep.run.journal  # noqa: E402
import sweep.run.runner  # noqa: E402
import sweep.write.netcdf  # noqa: E402

DEFAULT_OUT = HERE / "results" / "end_to_end.json"
CHUNK_THREAD = "sweep-chunk"
"""Name prefix of the threads that compute chunks side by side (sweep/run/concurrent_chunks.py)."""
TARGET_RATIO = 1.3
SIDES = {"full": (1000, 1000), "quick": (20, 10)}
FRESH_REPEATS = 2
"""Runs in a new process (``fresh_process``), at most."""
PARTS = ("kernel", "ladder_numpy", "model_choice", "chunk_other", "journal", "journal_wait", "consolidate", "planning",
         "prepare_other", "warm_up", "dataset", "netcdf", "png", "cli_other")
"""The parts of the breakdown, in the order of a run (module docstring)."""


class Stopwatch:
    """Seconds per named section; a section's own time leaves out the timed sections called inside it (per thread,
    so a section timed in a helper thread is not subtracted from its caller's)."""

    def __init__(self, workers: int = 1) -> None:
        self.workers = workers
        """Chunks computed side by side (the run's numba threads, sweep/run/concurrent_chunks.py)."""
        self.own: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self.helper: set[str] = set()
        """Sections timed in a thread other than the main one (overlapped with it)."""
        self._lock = threading.Lock()
        self._local = threading.local()

    @contextlib.contextmanager
    def section(self, key: str):
        stack = self._local.__dict__.setdefault("stack", [])
        stack.append(0.0)  # seconds of the sections inside this one
        t0 = time.perf_counter()
        try:
            yield
        finally:
            spent = time.perf_counter() - t0
            inner = stack.pop()
            if stack:
                stack[-1] += spent
            thread = threading.current_thread()
            # a chunk computed side by side with others (sweep/run/concurrent_chunks.py) holds 1/workers of the machine
            share = 1.0 / self.workers if thread.name.startswith(CHUNK_THREAD) else 1.0
            with self._lock:
                self.own[key] = self.own.get(key, 0.0) + (spent - inner) * share
                self.calls[key] = self.calls.get(key, 0) + 1
                if thread is not threading.main_thread() and share == 1.0:
                    self.helper.add(key)

    def wrap(self, fn, key: str):
        @functools.wraps(fn)
        def timed(*args, **kwargs):
            with self.section(key):
                return fn(*args, **kwargs)

        return timed


@contextlib.contextmanager
def instrumented(watch: Stopwatch):
    """The package's functions wrapped in ``watch``'s sections (module docstring) for the duration of the block."""
    patches = [
        (sweep.protocols.stop.engine, "climb", "ladder_numpy"),
        (sweep.protocols.stop.engine, "climb_tolerances", "ladder_numpy"),
        (sweep.protocols.stop.engine, "stop_batch", "kernel"),
        (sweep.protocols.stop.engine, "slip_batch", "kernel"),
        (sweep.protocols.stop.model_choice, "relax_points", "kernel"),
        (sweep.protocols.stop.chunk, "choose_stop_models", "model_choice"),
        (sweep.protocols.stop.chunk, "run_points", "chunk_other"),
        (sweep.run.journal.Journal, "write", "journal"),
        (sweep.api, "run_chunks", "consolidate"),
        (sweep.run.runner, "make_plan", "planning"),
        (sweep.api, "prepare_run", "prepare_other"),
        (sweep.api, "warm_up_kernels", "warm_up"),
        (sweep.run.runner, "build_block", "dataset"),
        (sweep.write.netcdf.NetCDFRegions, "put", "netcdf"),
        (sweep.plot.files, "plot_file", "png"),
    ]
    engine = sweep.protocols.stop.engine
    lane_kernels, adaptive_kernels = engine.lane_kernels, engine.adaptive_lane_kernels
    if hasattr(sweep.run.journal.Journal, "background"):  # chunks journaled in a helper thread
        patches.append((sweep.run.journal.Journal, "background", "journal_wait"))
    saved = [(owner, name, getattr(owner, name)) for owner, name, _ in patches]
    try:
        for owner, name, key in patches:
            original = getattr(owner, name)
            if name == "prepare_run":  # a context manager: time its setup (entering) only
                setattr(owner, name, _timed_enter(watch, original, key))
            elif name == "background":  # a context manager yielding keep(index, arrays): time keep and the exit
                setattr(owner, name, _timed_background(watch, original, key))
            else:
                setattr(owner, name, watch.wrap(original, key))
        engine.lane_kernels = lambda *a, **k: _lane_kernels_timed(watch, lane_kernels, *a, **k)
        engine.adaptive_lane_kernels = lambda *a, **k: _lane_kernels_timed(watch, adaptive_kernels, *a, **k)
        yield
    finally:
        engine.lane_kernels, engine.adaptive_lane_kernels = lane_kernels, adaptive_kernels
        for owner, name, original in saved:
            setattr(owner, name, original)


def _lane_kernels_timed(watch: Stopwatch, lane_kernels, *args, **kwargs):
    """A lane kernel factory (sweep.integrate.lanes.lane_kernels, lanes_adaptive.adaptive_lane_kernels) with its batch
    (element 1, what the engine calls) timed as kernel."""
    kernels = lane_kernels(*args, **kwargs)
    return (kernels[0], watch.wrap(kernels[1], "kernel"), *kernels[2:])


def _timed_enter(watch: Stopwatch, prepare_run, key: str):
    """prepare_run whose setup (everything before it yields) is timed as ``key``."""
    @contextlib.contextmanager
    def timed(*args, **kwargs):
        manager = prepare_run(*args, **kwargs)
        with watch.section(key):
            run = manager.__enter__()
        try:
            yield run
        except BaseException:
            if not manager.__exit__(*sys.exc_info()):
                raise
        else:
            manager.__exit__(None, None, None)

    return timed


def _timed_background(watch: Stopwatch, background, key: str):
    """Journal.background whose keep() calls and whose end (waiting for the last writes) are timed as ``key``."""
    @contextlib.contextmanager
    def timed(journal):
        manager = background(journal)
        keep = manager.__enter__()
        try:
            yield watch.wrap(keep, key)
        except BaseException:
            if not manager.__exit__(*sys.exc_info()):
                raise
        else:
            with watch.section(key):
                manager.__exit__(None, None, None)

    return timed


def scene_for(quick: bool) -> sweep.Scene:
    """The default scene's ranges on the benchmark's grid (module docstring)."""
    n_km, n_v = SIDES["quick" if quick else "full"]
    return dataclasses.replace(sweep.default_scene(), K_over_M=np.logspace(3, 6, n_km), V=np.logspace(-7, -4, n_v))


def one_run(toml: Path, out: Path) -> dict:
    """``sweep run`` of ``toml`` into ``out`` (and out.png) with the breakdown (module docstring)."""
    watch = Stopwatch(numba.get_num_threads())
    load = loadavg()
    argv = ["run", str(toml), "-o", str(out), "--overwrite", "-q"]
    with instrumented(watch), open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):
        t0 = time.perf_counter()
        rc = sweep.cli.main(argv)
        total = time.perf_counter() - t0
    if rc != 0:
        raise RuntimeError(f"sweep {' '.join(argv)} exited {rc}")
    parts = {key: watch.own.get(key, 0.0) for key in PARTS if key != "cli_other"}
    parts["cli_other"] = max(0.0, total - sum(parts.values()))
    overlapped = max(0.0, sum(parts.values()) - total)
    return {"total_s": total, "parts_s": parts, "calls": watch.calls, "overlapped_s": overlapped,
            "in_helper_threads": sorted(watch.helper),
            "ratio_total_over_kernel": total / parts["kernel"] if parts["kernel"] > 0 else None,
            "netcdf_bytes": out.stat().st_size, "loadavg_before": load, "loadavg_after": loadavg()}


def fresh_process_run(toml: Path, out: Path) -> dict:
    """``sweep run`` as a user starts it: a new Python process (kernels in numba's cache), timed from outside
    (interpreter start, imports, kernel loading, the run, the file and the picture); ``computed_s`` is what the
    command itself prints as its computing time (the chunk loop's wall time)."""
    load = loadavg()
    cmd = [sys.executable, "-m", "sweep.cli", "run", str(toml), "-o", str(out), "--overwrite", "-q"]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {proc.returncode}: {proc.stderr[-2000:]}")
    found = re.search(r"computed in ([0-9.e+-]+) s", proc.stdout)
    return {"wall_s": wall, "computed_s": float(found.group(1)) if found else None, "loadavg_before": load}


def print_table(result: dict) -> None:
    best = result["best"]
    print(f"\n{result['scene']['points']:,} points, best of {len(result['runs'])} (load before "
          f"{best['loadavg_before']}):")
    for key in PARTS:
        print(f"  {key:>14s} {best['parts_s'][key]:8.3f} s")
    print(f"  {'total':>14s} {best['total_s']:8.3f} s   total / kernel = {best['ratio_total_over_kernel']:.2f} "
          f"(target <= {TARGET_RATIO})")
    print("totals of every run: " + ", ".join(f"{r['total_s']:.2f} s" for r in result["runs"]))
    fresh = result.get("fresh_process")
    if fresh:
        print(f"a new process (python -m sweep.cli run), best of {len(fresh['runs'])}: {fresh['best']['wall_s']:.2f} s "
              f"= {fresh['wall_over_kernel']:.2f} x the kernel above (its chunk loop {fresh['best']['computed_s']} s)")


def plot(result: dict, path: Path) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    best = result["best"]
    seconds = [best["parts_s"][k] for k in PARTS]
    fig, ax = plt.subplots(figsize=(8.0, 4.8), dpi=110, layout="constrained")
    helper = set(best.get("in_helper_threads", ()))
    colours = ["C2" if k == "kernel" else "0.65" if k in helper else "C0" for k in PARTS]
    ax.barh(PARTS[::-1], seconds[::-1], color=colours[::-1])
    if helper:
        ax.barh([], [], color="0.65", label="in a helper thread, overlapped with the main one (wall time there, "
                                           "waiting for the GIL included)")
    for i, s in enumerate(seconds[::-1]):
        ax.annotate(f"{s:.2f} s", (s, i), xytext=(3, 0), textcoords="offset points", va="center", fontsize=8)
    ax.axvline(best["parts_s"]["kernel"] * (TARGET_RATIO - 1.0), color="0.5", ls=":", lw=1,
               label=f"all but the kernel within the target ({TARGET_RATIO - 1:.1f} x kernel)")
    ax.set(xlabel="seconds (best run; overlapped parts each in their own thread)",
           title=f"sweep run, {result['scene']['points']:,} points: total {best['total_s']:.2f} s = "
                 f"{best['ratio_total_over_kernel']:.2f} x kernel {best['parts_s']['kernel']:.2f} s")
    ax.legend(fontsize=8, loc="lower right")
    fig.savefig(path)
    plt.close(fig)
    return str(path)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a 20 x 10 grid, one timed run (a smoke run)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--no-png", action="store_true")
    ap.add_argument("--keep", type=Path, default=None, help="copy the last run's netCDF file here (to compare)")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    digest0 = sweep_digest()
    scene = scene_for(args.quick)
    repeats = 1 if args.quick else args.repeats
    with tempfile.TemporaryDirectory(prefix="sweep-e2e-") as tmp:
        toml, out = Path(tmp) / "scene.toml", Path(tmp) / "out.nc"
        toml.write_text(scene.to_toml())
        sweep.cli.main(["run", str(toml), "-o", str(out), "--overwrite", "-q"])  # untimed: kernels loaded
        runs = [one_run(toml, out) for _ in range(repeats)]
        fresh_runs = [fresh_process_run(toml, out) for _ in range(min(repeats, FRESH_REPEATS))]
        if args.keep is not None:
            args.keep.write_bytes(out.read_bytes())
    best = min(runs, key=lambda r: r["total_s"])
    result = {"benchmark": "benchmarks/end_to_end.py", "command": " ".join(sys.argv), "quick": args.quick,
              "machine": machine_info(), "sweep_digest": digest0, "sweep_changed_during_run": sweep_digest() != digest0,
              "scene": {"shape": list(scene.shape), "points": scene.n_points, "rtol": scene.rtol,
                        "model": scene.model, "observables": list(scene.observables), "preset": "sample2"},
              "runs": runs, "best": best, "ratio_total_over_kernel": best["ratio_total_over_kernel"],
              "target": {"ratio_total_over_kernel_max": TARGET_RATIO}}
    fresh_best = min(fresh_runs, key=lambda r: r["wall_s"])
    result["fresh_process"] = {"runs": fresh_runs, "best": fresh_best,
                               "wall_over_kernel": fresh_best["wall_s"] / best["parts_s"]["kernel"]}
    write_result(result, args.out, t_start, None if args.no_png else plot, print_table)


if __name__ == "__main__":
    main()
