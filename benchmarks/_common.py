"""Pieces shared by the benchmark scripts (throughput.py, work_precision.py, calibrate_rk4.py).

* machine and version information (CPU model, usable CPUs, numba threading layer, package versions, git commit,
  whether sweep/ has uncommitted changes, a digest of the sweep sources, the load average);
* the timing helper: CPU time (``time.process_time``) and wall time (``time.perf_counter``) of repeated calls;
* the scipy solver of one stop point in the engine's own formulation (:func:`scipy_point`), stopped by a
  plain-Python copy of the engine's tail test (:func:`tail_ok`, checked against the original by
  :func:`check_tail_ok`) and completed by the engine's closed-form tail.

Import it from a script in this folder as ``from _common import ...`` (a script's own folder is on sys.path).
"""

from __future__ import annotations

import datetime
import hashlib
import json
import math
import os
import platform
import subprocess
import time
from pathlib import Path

import numba
import numpy as np
import scipy
from _machine import cpu_model, loadavg, usable_cpus  # noqa: F401 (re-exported)
from scipy.integrate import BDF, LSODA, Radau

import sweep
from sweep.integrate.models.stop import E_TAIL_MAX, EXP_MAX, TAIL_SAFETY, tail_is_accurate, tail_slip

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

# ------------------------------------------------------------------------------------ machine, versions


def threading_layer() -> str | None:
    """numba's threading layer (None before the first parallel call has chosen one)."""
    try:
        return numba.threading_layer()
    except ValueError:
        return None


def versions() -> dict:
    """python, numpy, numba, scipy and sweep versions."""
    return {"python": platform.python_version(), "numpy": np.__version__, "numba": numba.__version__,
            "scipy": scipy.__version__, "sweep": getattr(sweep, "__version__", None)}


def git_commit() -> str | None:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True, timeout=10).stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        return None


def sweep_tree_dirty() -> bool | None:
    """True if sweep/ has uncommitted changes (the numbers then belong to no commit), None if git cannot say."""
    try:
        return bool(subprocess.run(["git", "status", "--porcelain", "sweep"], cwd=ROOT, capture_output=True,
                                   text=True, timeout=10).stdout.strip())
    except (OSError, subprocess.SubprocessError):
        return None


def sweep_digest() -> str:
    """sha256 (16 hex) of the sweep package's sources: other people may edit sweep/ while a benchmark runs."""
    h = hashlib.sha256()
    for f in sorted((ROOT / "sweep").rglob("*.py")):
        h.update(f.relative_to(ROOT).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:16]


def machine_info() -> dict:
    """CPU, CPUs, numba threading, platform, versions, git commit and whether sweep/ was dirty."""
    return {"cpu": cpu_model(), "logical_cpus": os.cpu_count(), "usable_cpus": usable_cpus(),
            "numba_threading_layer": threading_layer(), "NUMBA_NUM_THREADS": numba.config.NUMBA_NUM_THREADS,
            "platform": platform.platform(),
            "versions": {**versions(), "git_commit": git_commit(), "sweep_tree_dirty": sweep_tree_dirty()}}


# ---------------------------------------------------------------------------------------------- timing


def timings(fn, repeats):
    """fn() called ``repeats`` times: (CPU seconds of each call, wall seconds of each call, last result).

    CPU time (time.process_time, all threads of this process) leaves out the time this process waits while
    another one runs; wall time (time.perf_counter) is what a user waits for."""
    cpu, wall, out = [], [], None
    for _ in range(repeats):
        c0, t0 = time.process_time(), time.perf_counter()
        out = fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return cpu, wall, out


def timed(fn, repeats):
    """Best of ``repeats`` calls of fn(): (best CPU seconds of this process, best wall seconds, last result).

    CPU time is the primary measure on a shared machine (uncontended, best CPU and best wall time agree to ~1 %)."""
    cpu, wall, out = timings(fn, repeats)
    return min(cpu), min(wall), out


# --------------------------------------------------------------------------------- scipy reference point


def tail_ok(k, a, b, u, E, tol):
    """sweep.integrate.models.stop.tail_is_accurate in plain Python (same expression, same order of operations).

    Calling the njit original from Python costs ~1.7 us per call (dispatch), comparable to a scipy step;
    scipy gets this copy so that the per-step test does not inflate its cost. check_tail_ok() verifies that
    both agree."""
    g = a + 2.0 * b * u
    if g <= 0.0 or E > E_TAIL_MAX:
        return False
    return E * E * E * (1.0 / (3.0 * g) + k / (2.0 * g * g)) <= TAIL_SAFETY * tol


def check_tail_ok(n=20000):
    """Compare tail_ok with the engine's tail_is_accurate on n random inputs; returns n (raises on a mismatch)."""
    rng = np.random.default_rng(1)
    args = np.column_stack([10 ** rng.uniform(-2, 2, n), rng.uniform(-4, 4, n), rng.uniform(0, 1, n),
                            rng.uniform(-5, 20, n), 10 ** rng.uniform(-6, 0, n), 10 ** rng.uniform(-14, -4, n)])
    bad = sum(tail_ok(*map(float, r)) != tail_is_accurate(*map(float, r)) for r in args)
    assert bad == 0, f"plain-Python tail test disagrees with the engine's on {bad} of {n} inputs"
    return n


WITH_JACOBIAN = (LSODA, Radau, BDF)
"""scipy solvers that get the analytic Jacobian (the implicit ones; DOP853 does not use one)."""


def scipy_point(cls, k, a, b, rtol, atol, tail_tol_rel, tail_tol_abs):
    """One stop point with a scipy OdeSolver class in the engine's formulation: dxi/ds = E(xi, s), u = s - xi,
    xi(0) = 0 (reduced: k = chi/A, a = mu1/A, b = m2/A), stepped until the engine's tail test passes with
    tolerance tail_tol_rel * xi + tail_tol_abs, then the engine's closed-form tail is added. LSODA, Radau and
    BDF get the analytic Jacobian. Returns (xi_inf, steps, nfev)."""
    def fun(s, y):
        xi = y[0]
        u = s - xi
        return np.array([math.exp(min(-(k * xi + u * (a + b * u)), EXP_MAX))])

    def jac(s, y):
        xi = y[0]
        u = s - xi
        return np.array([[-math.exp(min(-(k * xi + u * (a + b * u)), EXP_MAX)) * (k - a - 2.0 * b * u)]])

    extra = {"jac": jac} if cls in WITH_JACOBIAN else {}
    solver = cls(fun, 0.0, np.zeros(1), 1e12, rtol=rtol, atol=atol, **extra)
    steps = 0
    while True:
        msg = solver.step()
        steps += 1
        if solver.status != "running":
            raise RuntimeError(f"{cls.__name__} stopped before the tail test passed: {msg}")
        xi, s = float(solver.y[0]), float(solver.t)
        u = s - xi
        E = math.exp(min(-(k * xi + u * (a + b * u)), EXP_MAX))
        if tail_ok(k, a, b, u, E, tail_tol_rel * xi + tail_tol_abs):
            return xi + tail_slip(k, a, b, u, E), steps, solver.nfev


def write_result(result: dict, out: Path, t_start: float, plot=None, print_table=None) -> None:
    """End a benchmark run: its wall time and (unless the script set them) the date and the load average at the
    end into ``result``, the picture (``plot(result, png_path)`` unless None),
    the JSON at ``out``, the table (``print_table(result)``) and the line naming what was written."""
    result["benchmark_wall_s"] = time.perf_counter() - t_start
    result.setdefault("date", datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"))
    result.setdefault("loadavg_end", loadavg())
    out.parent.mkdir(parents=True, exist_ok=True)
    if plot is not None:
        result["png"] = plot(result, out.with_suffix(".png"))
    out.write_text(json.dumps(result, indent=1) + "\n")
    if print_table is not None:
        print_table(result)
    print(f"\nwrote {out}" + (f" and {result['png']}" if result.get("png") else ""))
