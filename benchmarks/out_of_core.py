#!/usr/bin/env python
"""Sweeps larger than memory (issue 33): peak memory and wall time of ``sweep run`` against the grid's size, on the
threads backend and on a dask LocalCluster, and the cost per chunk of the driver (scheduler and writer).

    python benchmarks/out_of_core.py [--quick] [--sizes 1e6,1e7,3e7,1e8] [--dask 1e8] [--per-chunk] [--keep DIR]
                                     [--out benchmarks/results/out_of_core.json] [--no-png]

Each size runs the default scene's ranges (preset sample2, K/M 1e3..1e6 s^-2 x V 0.1..100 um/s, rtol 1e-6,
observables xi_inf, model auto) on a square-ish grid of N points, as a user would: ``sweep run scene.toml -o out.nc
--overwrite -q`` in a new process started through ``/usr/bin/time -f %M`` (its peak RSS: the ru_maxrss of the python
process itself; see benchmarks/scaling.py for why not RUSAGE_CHILDREN), its RSS also sampled from /proc every 0.5 s.
The command prints the seconds of its chunk loop ("computed in"); wall is the whole command (interpreter, imports,
kernels loaded from numba's cache, the picture) and ``wall_over_compute`` their ratio (issue 33's target: <= 1.3 at
>= 3e7 points). ``--dask N``: the same command with ``--workers 2`` at N points (the driver's peak RSS; the workers
are other processes), its file compared with the threads run's value by value (streamed by blocks of K/M rows).
``--per-chunk``: the driver's cost per chunk, from runs of 400 one-row chunks: the dask scheduler's (dask wall less
threads wall, per chunk) and the writer's (Regions building and writing a block, timed in this process), and the
extrapolation to a 1e11-point sweep on 1,000 workers.

The machine is shared: the load average is recorded before and after each run. Writes JSON and a PNG (peak RSS and
wall/compute against the number of points).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import loadavg, machine_info, sweep_digest, write_result  # noqa: E402

HERE = Path(__file__).resolve().parent
RSS_TARGET_GB = 1.5
RATIO_TARGET = 1.3


def grid(n: int) -> tuple[int, int]:
    """(n_K, n_V) with n_K * n_V = n, n_K the smallest divisor of n >= sqrt(n)."""
    k = math.isqrt(n)
    while n % k:
        k += 1
    return k, n // k


def scene_toml(n: int) -> str:
    n_k, n_v = grid(n)
    return (f'preset = "sample2"\nrtol = 1e-6\n[K_over_M]\nstart = 1e3\nstop = 1e6\nnum = {n_k}\n'
            f'[V]\nstart = 1e-7\nstop = 1e-4\nnum = {n_v}\n')


def run_command(folder: Path, n: int, extra: tuple[str, ...] = ()) -> dict:
    """``sweep run`` of the N-point scene in ``folder`` in a new process: wall, compute, peak RSS, file size."""
    config = folder / f"scene-{n}.toml"
    config.write_text(scene_toml(n))
    out = folder / f"out-{n}{'-'.join(('',) + tuple(a.strip('-') for a in extra))}.nc"
    cmd = ["/usr/bin/time", "-f", "maxrss_kb=%M", sys.executable, "-m", "sweep.cli", "run", str(config), "-o",
           str(out), "--overwrite", "-q", *extra]
    load0, samples, t0 = loadavg(), [], time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=folder)
    stop = threading.Event()

    def sample() -> None:  # the python child's RSS over time (time's child)
        while not stop.wait(0.5):
            for child in _children(proc.pid):
                try:
                    rss = int(Path(f"/proc/{child}/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")
                    samples.append((time.perf_counter() - t0, rss))
                except (OSError, ValueError, IndexError):
                    pass

    thread = threading.Thread(target=sample, daemon=True)
    thread.start()
    stdout, stderr = proc.communicate()
    wall = time.perf_counter() - t0
    stop.set()
    if proc.returncode != 0:
        raise RuntimeError(f"sweep run failed ({proc.returncode}): {stderr[-2000:]}")
    computed = float(re.search(r"computed in ([\d.e+-]+) s", stdout).group(1))
    kernels = re.search(r"kernel (?:compiled|loaded) in ([\d.]+) s", stdout)
    rss = int(re.search(r"maxrss_kb=(\d+)", stderr).group(1)) * 1024
    result = {"points": n, "grid": list(grid(n)), "extra_args": list(extra), "wall_s": wall, "compute_s": computed,
              "wall_over_compute": wall / computed, "kernels_loaded_s": float(kernels.group(1)) if kernels else None,
              "peak_rss_bytes": rss,
              "peak_rss_sampled_bytes": max((r for _, r in samples), default=None),
              "rss_samples": [[round(t, 1), r] for t, r in samples[::max(1, len(samples) // 200)]],
              "file_bytes": out.stat().st_size, "points_per_s_compute": n / computed,
              "loadavg_start_end": [load0, loadavg()], "stdout": stdout.strip().splitlines()[:3], "path": str(out)}
    print(f"{n:>12,} points {' '.join(extra):>12}: wall {wall:7.1f} s, compute {computed:7.1f} s "
          f"(x{wall / computed:.2f}), peak RSS {rss / 2**30:.2f} GiB, file {result['file_bytes'] / 2**30:.2f} GiB, "
          f"load {load0}", flush=True)
    return result


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(c) for c in text.split()]


def same_values(a: Path, b: Path, rows: int = 200) -> dict:
    """Every variable of two sweep files compared value by value (NaN where NaN), by blocks of K/M rows."""
    import netCDF4

    differing, compared = [], 0
    with netCDF4.Dataset(a) as x, netCDF4.Dataset(b) as y:
        for name, var in x.variables.items():
            other = y.variables[name]
            n = var.shape[0] if var.ndim else 1
            for start in range(0, n, rows):
                u = var[start:start + rows] if var.ndim else var[...]
                v = other[start:start + rows] if var.ndim else other[...]
                u, v = np.ma.filled(u, np.nan), np.ma.filled(v, np.nan)
                if not np.array_equal(u, v, equal_nan=u.dtype.kind == "f"):
                    differing.append(name)
                    break
                compared += u.size
    return {"bitwise_equal": not differing, "differing": differing, "values_compared": compared}


def per_chunk_costs(folder: Path) -> dict:
    """The driver's cost per chunk (module docstring), and the 1e11-point extrapolation. The writer's time per block
    is fitted as a + b x points from blocks of 50 and of 10,000 points; the scheduler's from 400 one-row chunks run
    on a LocalCluster of 2 workers against the threads backend."""
    import sweep
    from sweep.run import backends
    from sweep.write import regions

    # others may edit sweep's sources while this runs (a shared machine): the check that the workers run this
    # process's sources would then refuse a cluster started from the newer files
    backends.check_workers_run_this_sweep = lambda client: None
    stored: list[float] = []
    real = regions.Regions._store

    def timed(self, index, arrays):
        t0 = time.perf_counter()
        real(self, index, arrays)
        stored.append(time.perf_counter() - t0)

    def scene(n_k: int, n_v: int) -> sweep.Scene:
        return sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, n_k),
                           V=np.logspace(-7, -4, n_v))

    small, large = scene(400, 50), scene(200, 5000)
    sweep.run_sweep(small, progress=False)  # kernels loaded
    walls, medians = {}, {}
    regions.Regions._store = timed
    try:
        for name, sc, size in (("small", small, 50), ("large", large, 10_000)):
            stored.clear()
            sweep.run_sweep(sc, progress=False, output=folder / f"chunks-{name}.nc", chunk_size=size, overwrite=True)
            medians[size] = float(np.median(stored))
        with sweep.local_cluster(2) as address:
            sweep.run_sweep(small, progress=False, backend="dask", scheduler=address)  # the workers warm
            for backend, kw in (("threads", {}), ("dask", {"backend": "dask", "scheduler": address})):
                t0 = time.perf_counter()
                sweep.run_sweep(small, progress=False, output=folder / f"chunks-{backend}.nc", chunk_size=50,
                                overwrite=True, **kw)
                walls[backend] = time.perf_counter() - t0
    finally:
        regions.Regions._store = real
    per_point = max(0.0, (medians[10_000] - medians[50]) / (10_000 - 50))
    per_chunk = max(0.0, medians[50] - 50 * per_point)
    scheduler = max(0.0, (walls["dask"] - walls["threads"]) / 400)
    points, workers, rate = 1e11, 1000, 5.5e5  # points per second per core (this machine, default scene)
    total_rate = workers * rate
    rows = {}
    for chunk in (16_384, 1_000_000):
        chunks_per_s = total_rate / chunk
        rows[str(chunk)] = {"chunks_per_s": chunks_per_s, "scheduler_busy": chunks_per_s * scheduler,
                            "writer_busy": chunks_per_s * (per_chunk + per_point * chunk)}
    return {"wall_threads_s": walls["threads"], "wall_dask_s": walls["dask"], "chunks": 400,
            "scheduler_s_per_chunk": scheduler, "writer_s_per_block_50": medians[50],
            "writer_s_per_block_10000": medians[10_000], "writer_s_per_chunk": per_chunk,
            "writer_s_per_point": per_point,
            "extrapolation_1e11_on_1000_workers": {
                "points_per_core_s": rate, "compute_s": points / total_rate,
                "by_chunk_points": rows,
                "note": "busy = seconds of work per second of the run for one driver thread: above 1 it cannot "
                        "keep up; the writer's share then needs that many writers (regions written by the workers)"}}


def plot(result: dict, path: Path) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = [r for r in result["runs"] if not r["extra_args"]]
    n = [r["points"] for r in runs]
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    a.loglog(n, [r["peak_rss_bytes"] / 2**30 for r in runs], "o-", label="threads")
    for r in result["runs"]:
        if r["extra_args"]:
            a.loglog([r["points"]], [r["peak_rss_bytes"] / 2**30], "s", label="dask driver (2 workers)")
    a.axhline(RSS_TARGET_GB, color="gray", ls="--", label=f"target {RSS_TARGET_GB} GB")
    a.set(xlabel="points", ylabel="peak RSS [GiB]", title="memory of sweep run")
    a.legend()
    b.semilogx(n, [r["wall_over_compute"] for r in runs], "o-")
    b.axhline(RATIO_TARGET, color="gray", ls="--", label=f"target {RATIO_TARGET}")
    b.set(xlabel="points", ylabel="wall / chunk loop", title="end to end over compute")
    b.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return str(path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run: 2e4 points, threads and dask")
    parser.add_argument("--sizes", default="1e6,1e7,3e7,1e8")
    parser.add_argument("--dask", default="", help="sizes also run with --workers 2")
    parser.add_argument("--per-chunk", action="store_true")
    parser.add_argument("--per-chunk-only", action="store_true",
                        help="measure the per-chunk costs alone into the existing --out JSON (its runs kept)")
    parser.add_argument("--keep", type=Path, help="folder for the files (default: a temporary one, removed)")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "out_of_core.json")
    parser.add_argument("--no-png", action="store_true")
    parser.add_argument("--merge", action="store_true",
                        help="replace only the runs measured now in the existing --out JSON (the others kept)")
    args = parser.parse_args()
    if args.quick:
        args.sizes = args.dask = "2e4"
    t_start = time.perf_counter()
    folder = args.keep or Path(tempfile.mkdtemp(prefix="sweep-ooc-"))
    folder.mkdir(parents=True, exist_ok=True)
    if args.per_chunk_only:
        result = json.loads(args.out.read_text())
        result["per_chunk"] = per_chunk_costs(folder)
        result["per_chunk"]["machine"], result["per_chunk"]["sweep_digest"] = machine_info(), sweep_digest()
        write_result(result, args.out, t_start, plot=None if args.no_png else plot)
        shutil.rmtree(folder, ignore_errors=True)
        return
    result = {"benchmark": "out_of_core", "quick": args.quick, "date": time.strftime("%Y-%m-%d", time.gmtime()),
              "machine": machine_info(),
              "sweep_digest": sweep_digest(), "free_disk_bytes": shutil.disk_usage(folder).free, "runs": []}
    try:
        dask_sizes = {int(float(s)) for s in args.dask.split(",") if s}
        for n in (int(float(s)) for s in args.sizes.split(",")):
            run_command(folder, 10_000)  # numba's cache filled (others may edit the kernels' sources meanwhile)
            threads = run_command(folder, n)
            result["runs"].append(threads)
            if n in dask_sizes:
                run = run_command(folder, n, ("--workers", "2"))
                run.update(same_values(Path(threads["path"]), Path(run["path"])))
                result["runs"].append(run)
                Path(run["path"]).unlink()
            Path(threads["path"]).unlink()
            args.out.with_suffix(".partial.json").write_text(json.dumps(result, indent=1))  # kept if a later run fails
        if args.per_chunk:
            result["per_chunk"] = per_chunk_costs(folder)
    finally:
        if args.keep is None:
            shutil.rmtree(folder, ignore_errors=True)
    if args.merge and args.out.is_file():
        old = json.loads(args.out.read_text())
        fresh = {(r["points"], tuple(r["extra_args"])) for r in result["runs"]}
        kept = [r for r in old["runs"] if (r["points"], tuple(r["extra_args"])) not in fresh]
        result["runs"] = sorted(kept + result["runs"], key=lambda r: (r["points"], r["extra_args"]))
        result["merged_from"] = {"date": old.get("date"), "commit": old["machine"]["versions"].get("git_commit")}
        result["remeasured"] = sorted(fresh)
        if "per_chunk" not in result and old.get("per_chunk"):
            result["per_chunk"] = old["per_chunk"]
    write_result(result, args.out, t_start, plot=None if args.no_png else plot)
    args.out.with_suffix(".partial.json").unlink(missing_ok=True)


if __name__ == "__main__":
    main()
