#!/usr/bin/env python
"""How the stop sweep scales with the number of points, the threads, a dask cluster, and memory (issue 5).

    python benchmarks/scaling.py [--quick] [--out benchmarks/results/scaling.json] [--no-png] [--no-wait] [--replot]

Stop scenes (preset sample2, observables xi_inf only, rtol 1e-6, model "auto"), square-ish grids of exactly N
points: K/M logspace(3, 6, n_k) x V logspace(-7, -4, n_v), n_k the smallest divisor of N >= sqrt(N) (40 x 25,
100 x 100, 400 x 250, 1000 x 1000, 3200 x 3125). Everything through the public ``sweep.run_sweep``:

1. threads   points per second for N = 1e3, 1e4, 1e5, 1e6 with 1 and 2 numba threads (numba.set_num_threads),
             best of 3 (best of 2 at 1e6), from the wall time of run_sweep and from ds.attrs["elapsed_seconds"]
             (the chunks' kernel work); speed-up 2 threads / 1 thread. The thread counts alternate per N.
2. dask      against the threads backend with 2 threads on the same grid, N = 1e5 and 1e6, best of 2 each,
             alternating: run_sweep(backend="dask", scheduler=address) on a LocalCluster of two one-thread workers
             started once (sweep.local_cluster(2), its workers warmed by a 100-point run), and
             run_sweep(backend="dask", workers=2), which starts and shuts down its own cluster per call (its
             start-up is also measured alone: a 100-point run, best of 3). Overhead = dask wall / threads wall - 1;
             issue 5's target: under 10 % at 1e6 points (judged on the running cluster; the per-call start-up and
             shutdown, ~2 s here, are reported beside it).
3. memory    N = 1e5, 1e6 and one run of 1e7 with 2 threads and output= a temporary .nc file (the journaled
             path), each in a fresh process (sys.executable -c ...) started through ``/usr/bin/time -f %M``; its
             peak RSS: time's %M (the ru_maxrss of the python process, from wait4), the child's own VmHWM read
             from /proc/self/status after run_sweep returned, and its RSS sampled from /proc every 0.5 s; the
             netCDF file size. Issue 5's target: 1e7 points under 2 GiB peak RSS. A run longer than 8 min is
             killed and recorded as such.
             Why not getrusage(RUSAGE_CHILDREN) or os.wait4 on a child that this process starts: on Linux a
             process's ru_maxrss keeps the high-water RSS of the memory image it replaced at exec, and the python
             child is vforked from this process, so its ru_maxrss is at least this process's own peak (573 MiB
             after part 2's 1e6-point Datasets: both 1e5 and 1e6 then read 572.8 MiB). /usr/bin/time is a small
             process that forks the python child, so its %M is the child's own. The wait4 value of time (= this
             process's peak) and RUSAGE_CHILDREN are recorded, labelled as such.

Before each part the script waits until no pytest runs (pgrep -f pytest) and the 1-minute load average is below
0.8 (polled every 20 s; --no-wait skips this): the development machine has 2 cores and is shared. The load
average is recorded before and after every measurement.

4. memory with trajectories: N = 2e5 with observables xi_inf and trajectory (61 times), as in 3: the
             trajectories go into the file chunk by chunk; the peak against what the four arrays would take whole.

Writes benchmarks/results/scaling.json and scaling.png (left: points/s vs N; right: peak RSS vs N with the 2 GiB
line). ~10 min on the 2-core machine.

--quick (a smoke run: does every part work; give --out elsewhere): N = 1e3 with 1 and 2 threads, one call each;
dask at 1e3 points, one call per variant and one start-up run (which also imports distributed); memory at 1e4
points; trajectories at 1e3 points; no waiting for a quiet machine (a smoke run is itself run under pytest).
~20 s with the kernels in numba's cache (three LocalCluster starts, ~2 s each on an idle 2-core machine).

dask.distributed is optional (the [distributed] extra): without it part 2 is recorded as skipped, with the reason,
under "dask" and "tools_missing", and the rest runs.
"""

from __future__ import annotations

import argparse
import json
import math
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
from sweep.protocols.stop.protocol import CHUNKS_AT_LEAST, LARGE_CHUNK_POINTS, PROTOCOL  # noqa: E402

HERE = Path(__file__).resolve().parent
OUT = HERE / "results"
PRESET = "sample2"
RTOL = 1e-6
GIB = 2**30
RSS_TARGET_BYTES = 2 * GIB
DASK_OVERHEAD_TARGET = 0.10
LOAD_QUIET = 0.8
POLL_S = 20.0
MEMORY_TIMEOUT_S = 480.0
STARTUP_POINTS = 100
TRAJECTORY_OBSERVABLES = ("xi_inf", "trajectory")

# The child of part 3 builds its scene itself (importing this module would import scipy via _common and inflate its
# RSS); the parent checks that the child's scene (its canonical TOML) is the one make_scene() gives.
CHILD = r"""
import hashlib, json, resource, sys, time
import numba, numpy as np
import sweep

def status_kib(field):
    for line in open("/proc/self/status"):
        if line.startswith(field + ":"):
            return int(line.split()[1])

n_k, n_v, threads, path = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
observables = tuple(sys.argv[5].split(","))
numba.set_num_threads(threads)
scene = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, n_k),
                    V=np.logspace(-7, -4, n_v), observables=observables, rtol=1e-6)
before = status_kib("VmRSS")
t0 = time.perf_counter()
ds = sweep.run_sweep(scene, progress=False, output=path)
wall = time.perf_counter() - t0
print(json.dumps({"vmhwm_kib": status_kib("VmHWM"), "rss_before_run_kib": before, "rss_after_run_kib":
                  status_kib("VmRSS"), "self_ru_maxrss_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
                  "wall_s": wall, "elapsed_seconds": ds.attrs["elapsed_seconds"], "threads": numba.get_num_threads(),
                  "finite_xi_inf": int(np.isfinite(ds["xi_inf"].values).sum()),
                  "scene_sha": hashlib.sha256(scene.to_toml().encode()).hexdigest()[:16]}))
"""


def grid_shape(n: int) -> tuple[int, int]:
    """(n_k, n_v) with n_k * n_v = n exactly, n_k the smallest divisor of n that is >= sqrt(n)."""
    n_k = math.isqrt(n - 1) + 1 if n > 1 else 1
    while n % n_k:
        n_k += 1
    return n_k, n // n_k


def make_scene(n: int, observables: tuple[str, ...] = ("xi_inf",)) -> sweep.Scene:
    n_k, n_v = grid_shape(n)
    return sweep.Scene(protocol="stop", params=sweep.presets[PRESET], K_over_M=np.logspace(3, 6, n_k),
                       V=np.logspace(-7, -4, n_v), observables=observables, rtol=RTOL)


def dirty_files() -> list[str]:
    """git status --porcelain of sweep/ (the numbers belong to the commit plus these changes)."""
    return subprocess.run(["git", "status", "--porcelain", "sweep"], cwd=HERE.parent, capture_output=True,
                          text=True).stdout.splitlines()


def pytest_running() -> bool:
    return subprocess.run(["pgrep", "-f", "pytest"], capture_output=True).returncode == 0


def conditions() -> dict:
    return {"loadavg": loadavg(), "pytest_running": pytest_running()}


def wait_quiet(enabled: bool, max_wait_s: float) -> dict:
    """Wait until no pytest runs and the 1-minute load average is below LOAD_QUIET (polled every POLL_S)."""
    t0 = time.perf_counter()
    while enabled:
        busy, load = pytest_running(), loadavg()
        if not busy and load is not None and load[0] < LOAD_QUIET:
            break
        if time.perf_counter() - t0 > max_wait_s:
            print(f"  not quiet after {max_wait_s:.0f} s (pytest {busy}, load {load}): measuring anyway", flush=True)
            return {"waited_s": time.perf_counter() - t0, "quiet": False, **conditions()}
        print(f"  waiting: pytest running {busy}, load {load}", flush=True)
        time.sleep(POLL_S)
    return {"waited_s": time.perf_counter() - t0, "quiet": enabled, **conditions()}


def runs(scene, repeats: int, **kw) -> dict:
    """run_sweep(scene, **kw) ``repeats`` times: wall and elapsed_seconds of each, best of each, points/s."""
    walls, elapsed, ds = [], [], None
    before = conditions()
    for _ in range(repeats):
        t0 = time.perf_counter()
        ds = sweep.run_sweep(scene, progress=False, **kw)
        walls.append(time.perf_counter() - t0)
        elapsed.append(float(ds.attrs["elapsed_seconds"]))
    n = scene.n_points
    return {"wall_s_all": walls, "elapsed_s_all": elapsed, "wall_s_best": min(walls), "elapsed_s_best": min(elapsed),
            "points_per_s_wall": n / min(walls), "points_per_s_elapsed": n / min(elapsed),
            "conditions_before": before, "conditions_after": conditions()}, ds


def part_threads(sizes, log, quick=False) -> dict:
    out = {}
    for n in sizes:
        scene = make_scene(n)
        repeats = 1 if quick else 3 if n <= 100_000 else 2
        row = {"shape": list(scene.shape), "repeats": repeats}
        for threads in (1, 2):
            numba.set_num_threads(threads)
            row[f"threads_{threads}"], _ = runs(scene, repeats)
            r = row[f"threads_{threads}"]
            log(f"  N {n:>9,d} threads {threads}: wall {r['wall_s_best']:8.3f} s ({r['points_per_s_wall']:9,.0f} "
                f"pts/s)  elapsed {r['elapsed_s_best']:8.3f} s ({r['points_per_s_elapsed']:9,.0f} pts/s)  "
                f"load {r['conditions_after']['loadavg'][0]:.2f}")
        row["speedup_2_vs_1_wall"] = row["threads_1"]["wall_s_best"] / row["threads_2"]["wall_s_best"]
        row["speedup_2_vs_1_elapsed"] = row["threads_1"]["elapsed_s_best"] / row["threads_2"]["elapsed_s_best"]
        out[str(n)] = row
    return out


def dask_missing() -> str | None:
    """Why the dask backend cannot run here (dask.distributed not importable), or None."""
    try:
        import distributed  # noqa: F401
    except Exception as exc:  # ImportError, or a broken installation
        return f"not installed ({type(exc).__name__}: {exc})"
    return None


def part_dask(sizes, log, quick=False) -> dict:
    numba.set_num_threads(2)
    small = make_scene(STARTUP_POINTS)
    if quick:  # one LocalCluster start fewer: the start-up run includes importing distributed
        startup, _ = runs(small, 1, backend="dask", workers=2)
        first = startup["wall_s_best"]
    else:
        t0 = time.perf_counter()
        sweep.run_sweep(small, progress=False, backend="dask", workers=2)  # imports distributed: not the start-up
        first = time.perf_counter() - t0
        startup, _ = runs(small, 3, backend="dask", workers=2)
    small_threads, _ = runs(small, 1 if quick else 3)
    log(f"  dask {STARTUP_POINTS}-point run (start-up): best {startup['wall_s_best']:.3f} s of "
        f"{[round(w, 3) for w in startup['wall_s_all']]} (first in the process {first:.3f} s); threads "
        f"{small_threads['wall_s_best']:.3f} s")
    out = {"startup": {"points": STARTUP_POINTS, "first_dask_run_in_process_s": first, "dask": startup,
                       "threads_2": small_threads}}
    s_dask = startup["wall_s_best"]
    with sweep.local_cluster(2) as address:
        sweep.run_sweep(small, progress=False, backend="dask", scheduler=address)  # its workers load the kernels
        variants = (("threads_2", {}), ("dask_2_workers", {"backend": "dask", "workers": 2}),
                    ("dask_running_cluster", {"backend": "dask", "scheduler": address}))
        for n in sizes:
            out[str(n)] = dask_row(make_scene(n), variants, s_dask, log, rounds=1 if quick else 2)
    out["note"] = ("dask_2_workers: run_sweep(backend='dask', workers=2), a LocalCluster started and shut down by "
                   "each call; dask_running_cluster: run_sweep(backend='dask', scheduler=address) on a "
                   "sweep.local_cluster(2) started once by this script (what the start-up costs is not paid per "
                   "sweep). overhead_* = dask wall / threads wall - 1; overhead_new_cluster_excluding_startup "
                   f"subtracts the dask {STARTUP_POINTS}-point run's wall")
    return out


def dask_row(scene, variants, s_dask: float, log, rounds: int = 2) -> dict:
    """The variants on ``scene``, alternating, one call each, ``rounds`` times (drift of the machine hits them
    alike)."""
    n = scene.n_points
    walls = {name: [] for name, _ in variants}
    values = {}
    for _ in range(rounds):
        for name, kw in variants:
            r, ds = runs(scene, 1, **kw)
            walls[name].append(r)
            values[name] = ds["xi_inf"].values
    row = {"shape": list(scene.shape),
           "bitwise_equal_xi_inf": all(np.array_equal(values["threads_2"], v, equal_nan=True)
                                       for v in values.values())}
    for name, rs in walls.items():
        w = [r["wall_s_all"][0] for r in rs]
        e = [r["elapsed_s_all"][0] for r in rs]
        row[name] = {"wall_s_all": w, "elapsed_s_all": e, "wall_s_best": min(w), "elapsed_s_best": min(e),
                     "points_per_s_wall": n / min(w),
                     "conditions": [{"before": r["conditions_before"], "after": r["conditions_after"]} for r in rs]}
    t = row["threads_2"]["wall_s_best"]
    d, c = row["dask_2_workers"]["wall_s_best"], row["dask_running_cluster"]["wall_s_best"]
    for name in ("dask_2_workers", "dask_running_cluster"):
        row[name]["elapsed_note"] = "summed over the chunks of both workers (~2 x the wall of the kernels)"
    # compute per worker (chunk seconds summed over both workers / 2) against the threads run's kernel time
    row["dask_chunk_seconds_per_worker_over_threads_elapsed"] = (row["dask_running_cluster"]["elapsed_s_best"] / 2
                                                                 / row["threads_2"]["elapsed_s_best"])
    row["dask_2_workers"]["points_per_s_wall_excluding_startup"] = n / (d - s_dask)
    row["overhead_new_cluster"] = d / t - 1.0
    row["overhead_new_cluster_excluding_startup"] = (d - s_dask) / t - 1.0
    row["overhead_running_cluster"] = c / t - 1.0
    log(f"  N {n:>9,d}: threads {t:8.3f} s  dask on a running cluster {c:8.3f} s "
        f"({row['overhead_running_cluster']:+.1%})"
        f"  dask starting its cluster {d:8.3f} s ({row['overhead_new_cluster']:+.1%}; without the start-up "
        f"{row['overhead_new_cluster_excluding_startup']:+.1%})  bitwise equal {row['bitwise_equal_xi_inf']}")
    return row


TIME = Path("/usr/bin/time")


def python_pid(pid: int) -> int:
    """The python child of /usr/bin/time (pid itself when the child was started without it)."""
    if not TIME.exists():
        return pid
    try:
        kids = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except OSError:
        return pid
    return int(kids[0]) if kids else pid


def rss_kib_of(pid: int) -> int | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    except (OSError, ValueError):
        return None
    return None


def memory_run(n: int, threads: int = 2, timeout_s: float = MEMORY_TIMEOUT_S,
               observables: tuple[str, ...] = ("xi_inf",)) -> dict:
    """One fresh process running make_scene(n, observables) with output= a temporary .nc file; its peak RSS and
    file size."""
    import hashlib
    import resource

    n_k, n_v = grid_shape(n)
    with tempfile.TemporaryDirectory(prefix="sweep_scaling_") as tmp:
        path = Path(tmp) / f"scaling_{n}.nc"
        out_f, err_f = open(Path(tmp) / "stdout", "w+"), open(Path(tmp) / "stderr", "w+")
        before = conditions()
        t0 = time.perf_counter()
        maxrss_f = Path(tmp) / "maxrss_kib"
        prefix = [str(TIME), "-f", "%M", "-o", str(maxrss_f)] if TIME.exists() else []
        proc = subprocess.Popen(prefix + [sys.executable, "-c", CHILD, str(n_k), str(n_v), str(threads), str(path),
                                          ",".join(observables)], stdout=out_f, stderr=err_f, cwd=tmp)
        samples, status, usage, killed, child_pid = [], None, None, False, None
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            elapsed = time.perf_counter() - t0
            if child_pid is None or child_pid == proc.pid:
                child_pid = python_pid(proc.pid)
            if elapsed > timeout_s and not killed:
                if child_pid != proc.pid:
                    os.kill(child_pid, 9)  # the python child; time then exits and reports its peak
                else:
                    proc.kill()
                killed = True
            rss = rss_kib_of(child_pid)
            if rss is not None:
                samples.append((round(elapsed, 2), rss))
            time.sleep(0.5)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        out_f.seek(0)
        err_f.seek(0)
        stdout, stderr = out_f.read(), err_f.read()
        out_f.close()
        err_f.close()
        time_kib = None
        try:
            time_kib = int(maxrss_f.read_text().split()[-1])
        except (OSError, ValueError, IndexError):
            pass
        sampled = np.array([s[1] for s in samples] or [0]) * 1024
        row = {"points": n, "shape": [n_k, n_v], "observables": list(observables), "threads": threads,
               "process_wall_s": wall,
               "returncode": proc.returncode, "killed_after_timeout_s": timeout_s if killed else None,
               "usr_bin_time_maxrss_bytes": None if time_kib is None else time_kib * 1024,
               "sampled_rss_max_bytes": int(sampled.max()), "sampled_rss_median_bytes": int(np.median(sampled)),
               "sampled_rss_peak_at_s": max(samples, key=lambda s: s[1])[0] if samples else None,
               "wait4_maxrss_bytes_includes_parent_peak": usage.ru_maxrss * 1024,
               "parent_own_maxrss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
               "rusage_children_maxrss_bytes_so_far": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024,
               "rss_timeline_s_mib": [(t, round(r / 1024, 1)) for t, r in samples[:: max(1, len(samples) // 60)]],
               "conditions_before": before, "conditions_after": conditions()}
        if proc.returncode == 0 and path.is_file():
            child = json.loads(stdout.strip().splitlines()[-1])
            expected = hashlib.sha256(make_scene(n, observables).to_toml().encode()).hexdigest()[:16]
            assert child["scene_sha"] == expected, "the child's scene differs from make_scene()"
            row.update(child=child, netcdf_bytes=path.stat().st_size,
                       journal_left_behind=(Path(tmp) / f"scaling_{n}.nc.journal").exists())
        else:
            row.update(failed=True, stderr_tail=stderr[-3000:], stdout_tail=stdout[-1000:])
    # the peak: time's %M where it ran, else the child's VmHWM, else (killed, failed) the largest sample
    peak = row["usr_bin_time_maxrss_bytes"] or (row["child"]["vmhwm_kib"] * 1024 if "child" in row else None)
    row["peak_rss_source"] = ("/usr/bin/time %M" if row["usr_bin_time_maxrss_bytes"] else
                              "child VmHWM" if "child" in row else "largest 0.5 s sample (lower bound)")
    row["peak_rss_bytes"] = peak or row["sampled_rss_max_bytes"]
    row["peak_rss_gib"] = row["peak_rss_bytes"] / GIB
    row["meets_rss_target"] = bool(not row.get("failed") and row["peak_rss_bytes"] < RSS_TARGET_BYTES)
    return row


def part_memory(sizes, log, observables: tuple[str, ...] = ("xi_inf",)) -> dict:
    out = {}
    for n in sizes:
        row = memory_run(n, observables=observables)
        if "trajectory" in observables:  # what the four sampled arrays (xi, psi and errors) would take held whole
            n_tau = make_scene(1, observables).tau_samples.size
            row["trajectories_held_whole_bytes"] = n * 4 * n_tau * 8
            log(f"  trajectories of {n:,d} points x {n_tau} times held whole would take "
                f"{row['trajectories_held_whole_bytes'] / 2**20:.0f} MiB (4 float64 arrays)")
        out[str(n)] = row
        if row.get("failed"):
            log(f"  N {n:>10,d}: FAILED (returncode {row['returncode']}, killed after timeout: "
                f"{row['killed_after_timeout_s']}) peak RSS {row['peak_rss_gib']:.3f} GiB")
        else:
            log(f"  N {n:>10,d}: peak RSS {row['peak_rss_bytes'] / 2**20:8.1f} MiB (VmHWM "
                f"{row['child']['vmhwm_kib'] / 1024:.1f}, sampled max {row['sampled_rss_max_bytes'] / 2**20:.1f}, "
                f"median {row['sampled_rss_median_bytes'] / 2**20:.1f}; before the run "
                f"{row['child']['rss_before_run_kib'] / 1024:.0f} MiB)  run_sweep wall {row['child']['wall_s']:7.1f} s"
                f"  elapsed {row['child']['elapsed_seconds']:7.1f} s  file {row['netcdf_bytes'] / 2**20:7.1f} MiB  "
                f"load {row['conditions_after']['loadavg'][0]:.2f}")
    return out


def plot(result, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13.0, 5.0), dpi=110)
    th = result["threads"]
    ns = [int(n) for n in th]
    for threads, color in ((1, "C0"), (2, "C1")):
        ax.plot(ns, [th[str(n)][f"threads_{threads}"]["points_per_s_wall"] for n in ns], "o-", color=color,
                label=f"threads, {threads} thread{'s' * (threads > 1)}: run_sweep wall")
        ax.plot(ns, [th[str(n)][f"threads_{threads}"]["points_per_s_elapsed"] for n in ns], "s--", color=color,
                alpha=0.7, label=f"threads, {threads} thread{'s' * (threads > 1)}: elapsed_seconds (kernels)")
    dk = {int(k): v for k, v in result["dask"].items() if k.isdigit()}
    dn = sorted(dk)
    if dn:
        ax.plot(dn, [dk[n]["dask_running_cluster"]["points_per_s_wall"] for n in dn], "D-", color="C2",
                label="dask, running LocalCluster of 2 workers: run_sweep wall")
        ax.plot(dn, [dk[n]["dask_2_workers"]["points_per_s_wall"] for n in dn], "D:", color="C2", alpha=0.7,
                label="dask, run_sweep(workers=2): wall with its cluster's start-up and shutdown")
        for n in dn:
            y = dk[n]["dask_running_cluster"]["points_per_s_wall"]
            ax.annotate(f"{dk[n]['overhead_running_cluster']:+.1%}", (n, y), textcoords="offset points",
                        xytext=(5, -12), fontsize=8, color="C2")
    mem = {int(k): v for k, v in result["memory"].items()}
    ok = [n for n in sorted(mem) if not mem[n].get("failed")]
    if ok:
        ax.plot(ok, [n / mem[n]["child"]["wall_s"] for n in ok], "v-", color="0.4", ms=5, lw=0.8,
                label="2 threads, output= .nc, fresh process (part 3, one run): wall")
        ax.plot(ok, [n / mem[n]["child"]["elapsed_seconds"] for n in ok], "v--", color="0.4", ms=5, lw=0.8,
                alpha=0.7, label="2 threads, output= .nc, fresh process (part 3, one run): elapsed_seconds")
    ax.set(xscale="log", yscale="log", xlabel="points N", ylabel="points per second (best)",
           title="stop scene, sample2, xi_inf, rtol 1e-6, model auto")
    ax.set_ylim(3e3, None)  # room for the legend below the lines
    ax.legend(fontsize=6.5, loc="lower right")
    mn = sorted(mem)
    ax2.plot(mn, [mem[n]["peak_rss_bytes"] / GIB for n in mn], "o-", color="C3", label="peak RSS of the process")
    ax2.plot(ok, [mem[n]["child"]["rss_before_run_kib"] * 1024 / GIB for n in ok], "s:", color="0.5",
             label="RSS before run_sweep (import, kernels)")
    ax2.plot(ok, [mem[n]["netcdf_bytes"] / GIB for n in ok], "^--", color="C4", label="netCDF file size")
    for n in mn:
        r = mem[n]
        txt = "FAILED" if r.get("failed") else f"{r['peak_rss_bytes'] / 2**20:.0f} MiB\n{r['child']['wall_s']:.0f} s"
        ax2.annotate(txt, (n, r["peak_rss_bytes"] / GIB), textcoords="offset points", xytext=(5, 4), fontsize=8)
    ax2.axhline(RSS_TARGET_BYTES / GIB, color="k", ls="--", lw=1, label="target: 2 GiB at 1e7 points")
    ax2.set(xscale="log", xlabel="points N", ylabel="GiB", ylim=(0, None),
            title="one fresh process, 2 threads, output= .nc (journaled)")
    ax2.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="N = 1e3, memory 1e4, trajectories 1e3, one call each, "
                                                         "no waiting for a quiet machine (a smoke run)")
    ap.add_argument("--out", type=Path, default=OUT / "scaling.json")
    ap.add_argument("--no-png", action="store_true")
    ap.add_argument("--no-wait", action="store_true", help="do not wait for a quiet machine before each part")
    ap.add_argument("--max-wait", type=float, default=1800.0, help="longest wait for a quiet machine, s")
    ap.add_argument("--replot", action="store_true", help="only redraw the PNG from the JSON at --out")
    args = ap.parse_args()
    if args.replot:
        plot(json.loads(args.out.read_text()), args.out.with_suffix(".png"))
        return
    quick = args.quick
    sizes = [1_000] if quick else [1_000, 10_000, 100_000, 1_000_000]
    dask_sizes = [1_000] if quick else [100_000, 1_000_000]
    mem_sizes = [10_000] if quick else [100_000, 1_000_000, 10_000_000]
    traj_sizes = [1_000] if quick else [200_000]
    wait = not (args.no_wait or quick)  # a smoke run runs under pytest: it would wait for itself
    t_start = time.perf_counter()
    digest0, load0 = sweep_digest(), loadavg()

    def log(msg):
        print(f"[{time.perf_counter() - t_start:6.0f} s] {msg}", flush=True)

    log(f"numba threads available {numba.config.NUMBA_NUM_THREADS}; load {load0}")
    for threads in (1, 2):  # load the kernels (numba's on-disk cache) outside the timings
        numba.set_num_threads(threads)
        sweep.run_sweep(make_scene(1_000), progress=False)
    waits, digests = {}, {}
    log("1. threads backend")
    waits["threads"] = wait_quiet(wait, args.max_wait)
    digests["threads"] = sweep_digest()
    threads = part_threads(sizes, log, quick)
    log("2. dask LocalCluster (2 workers) vs threads (2 threads)")
    waits["dask"] = wait_quiet(wait, args.max_wait)
    digests["dask"] = sweep_digest()
    tools_missing = {}
    why = dask_missing()
    if why is None:
        dask = part_dask(dask_sizes, log, quick)
    else:
        tools_missing["dask.distributed"] = why
        dask = {"skipped": f"dask.distributed {why}: pip install '.[distributed]'"}
        log(f"  skipped: {dask['skipped']}")
    log("3. peak memory, fresh processes, output= .nc")
    waits["memory"] = wait_quiet(wait, args.max_wait)
    digests["memory"] = sweep_digest()
    memory = part_memory(mem_sizes, log)
    log("4. peak memory with trajectories (written into the file chunk by chunk), fresh process")
    memory_traj = part_memory(traj_sizes, log, TRAJECTORY_OBSERVABLES)
    n_big, n_mem = str(dask_sizes[-1]), str(mem_sizes[-1])
    big_mem = memory[n_mem]
    targets = {"dask_overhead_target": DASK_OVERHEAD_TARGET}
    if "skipped" not in dask:
        targets.update({
            f"dask_overhead_at_{n_big}_running_cluster": dask[n_big]["overhead_running_cluster"],
            f"dask_overhead_at_{n_big}_new_cluster": dask[n_big]["overhead_new_cluster"],
            f"dask_overhead_at_{n_big}_new_cluster_excluding_startup":
                dask[n_big]["overhead_new_cluster_excluding_startup"],
            "dask_overhead_pass_running_cluster": dask[n_big]["overhead_running_cluster"] < DASK_OVERHEAD_TARGET,
            "dask_overhead_pass_new_cluster": dask[n_big]["overhead_new_cluster"] < DASK_OVERHEAD_TARGET})
    targets.update({
        f"peak_rss_gib_at_{n_mem}": big_mem["peak_rss_gib"],
        "peak_rss_target_gib": RSS_TARGET_BYTES / GIB,
        "peak_rss_pass": bool(not big_mem.get("failed") and big_mem["peak_rss_bytes"] < RSS_TARGET_BYTES)})
    result = {
        "benchmark": "scaling" + (" --quick (tiny sizes: a check of the script, not a result)" if quick else ""),
        "tools_missing": tools_missing, "date": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.gmtime()),
        "machine": machine_info(),
        "quick": args.quick, "sweep_source_digest_start_end": [digest0, sweep_digest()],
        "sweep_source_digest_before_part": digests, "sweep_uncommitted_files": dirty_files(),
        "loadavg_start_end": [load0, loadavg()], "waits_for_quiet_machine": waits,
        "settings": {"scene": f"stop, preset {PRESET}, observables xi_inf, rtol {RTOL}, model auto, K/M logspace(3, 6, "
                              "n_k) x V logspace(-7, -4, n_v), n_k the smallest divisor of N >= sqrt(N)",
                     "chunk_size": f"plan.chunk_size_for: {PROTOCOL.default_chunk}, doubled up to {LARGE_CHUNK_POINTS} "
                                   f"while >= {CHUNKS_AT_LEAST} chunks",
                     "timing": "time.perf_counter around run_sweep; best of 3 "
                     "(N <= 1e5) or 2 (1e6), one call with --quick; elapsed = ds.attrs['elapsed_seconds'] (the "
                     "chunks' compute time, summed)",
                     "quiet": f"no pytest and 1-min load < {LOAD_QUIET} before each part (poll {POLL_S:.0f} s)",
                     "memory_timeout_s": MEMORY_TIMEOUT_S},
        "threads": threads, "dask": dask, "memory": memory, "memory_trajectories": memory_traj, "targets": targets,
        "benchmark_wall_s": time.perf_counter() - t_start,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1, default=str))
    if not args.no_png:
        try:
            plot(result, args.out.with_suffix(".png"))
        except ImportError:
            print("matplotlib not installed: no PNG")
    log(f"wrote {args.out}")
    print(f"\n{'N':>10s} {'1 thr pts/s':>12s} {'2 thr pts/s':>12s} {'speed-up':>8s} {'dask pts/s':>11s} "
          f"{'ovh run.':>9s} {'ovh new':>9s} {'peak RSS MiB':>12s}")
    for n in sorted({*sizes, *mem_sizes}):
        t, d, m = threads.get(str(n)), dask.get(str(n)), memory.get(str(n))
        cells = [f"{t['threads_1']['points_per_s_wall']:12,.0f}" if t else f"{'':12s}",
                 f"{t['threads_2']['points_per_s_wall']:12,.0f}" if t else f"{'':12s}",
                 f"{t['speedup_2_vs_1_wall']:8.2f}" if t else f"{'':8s}",
                 f"{d['dask_running_cluster']['points_per_s_wall']:11,.0f}" if d else f"{'':11s}",
                 f"{d['overhead_running_cluster']:+9.1%}" if d else f"{'':9s}",
                 f"{d['overhead_new_cluster']:+9.1%}" if d else f"{'':9s}",
                 f"{m['peak_rss_bytes'] / 2**20:12.0f}" if m else f"{'':12s}"]
        print(f"{n:>10,d} " + " ".join(cells))
    if "skipped" in dask:
        print(f"\ndask: {dask['skipped']}")
    else:
        print(f"\ndask overhead at {int(n_big):,d} points (target < 10 %): "
              f"{'PASS' if targets['dask_overhead_pass_running_cluster'] else 'MISS'} on a running LocalCluster "
              f"({dask[n_big]['overhead_running_cluster']:+.1%}); "
              f"{'PASS' if targets['dask_overhead_pass_new_cluster'] else 'MISS'} with a LocalCluster started and "
              f"shut down by the call ({dask[n_big]['overhead_new_cluster']:+.1%}, of which the start-up "
              f"{dask[n_big]['overhead_new_cluster'] - dask[n_big]['overhead_new_cluster_excluding_startup']:.1%})")
    for n, r in memory_traj.items():
        if not r.get("failed"):
            print(f"trajectories, {int(n):,d} points: peak RSS {r['peak_rss_bytes'] / 2**20:.0f} MiB; held whole "
                  f"they would take {r['trajectories_held_whole_bytes'] / 2**20:.0f} MiB")
    print(f"peak RSS at {int(n_mem):,d} points (target < 2 GiB): {'PASS' if targets['peak_rss_pass'] else 'MISS'} "
          f"({big_mem['peak_rss_gib']:.3f} GiB)")


if __name__ == "__main__":
    main()
