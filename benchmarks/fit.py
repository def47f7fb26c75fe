"""Cost of a fit (issue 21's benchmark): sweep.fit against scipy.optimize.least_squares driving solve_ivp.

    python benchmarks/fit.py [--quick] [--repeats 3] [--out benchmarks/results/fit.json] [--no-png]
    python benchmarks/fit.py --first-call 5

``--first-call N`` times instead the first fit of a new process with numba's cache warm (issue 37): N fresh
processes each run ``import sweep``, then one sweep.fit of a 50-sample curve (3 free parameters, profiles), and
print the seconds of each (wall and CPU); nothing is written. The cache is warmed first by one such process.

* one relaxation curve of 200 samples (sample2 at K/M = 2.8e5 s-2, V = 1 um/s, t = 0.1 .. 3160 s, 0.5 % noise),
  3 free parameters (A, m1, m2), the global stage, least squares and the profile likelihoods: target < 10 s;
* N_MANY such curves, each with its own parameters (A, m1, m2 of sample2 times 0.8..1.25 each), in one call
  (each its own sample: all their engine runs merged): target < 100 s for 100 curves;
* the obvious alternative on the first N_SCIPY of those curves, one at a time: scipy.optimize.least_squares (trf,
  the same bounds, start and x_scale, Jacobian by its own finite differences) driving scipy.integrate.solve_ivp
  (LSODA at rtol 1e-8: the fastest of RK45, DOP853, LSODA, Radau and BDF on this curve, 4.3 ms a solve, error 3e-8
  of the relaxed slip), its 95 % intervals +-1.96 standard errors from the Jacobian. It does less than sweep.fit (no
  global stage, no profiles): the ratio per curve is scipy's seconds per curve over the engine's seconds per curve
  in the many-curve call (target >= 100x); ``ratio_least_squares_stage`` compares like with like (scipy's fit
  against sweep.fit's least-squares stage alone, per curve), and the seconds per forward solve and the forward
  solves per curve of each say where the time goes;
* both fits' estimates side by side: they fit the same data, so they must agree within their uncertainties
  (|engine - scipy| / sqrt(se_engine^2 + se_scipy^2) < 1 for every parameter).

The data come from the independent scipy reference of the tests (tests/fit_reference.py, rtol 1e-13), never from
the engine. Times: wall (what a user waits for) and CPU of this process (all threads; on a loaded machine the CPU
time is the steadier one). The engine's kernels are compiled or loaded before the timed calls (a first fit on one
curve; its time is reported as warm_up_s). Each fit (the engine's one curve and many curves, scipy's on each of its
curves) runs --repeats times, the engine's and scipy's alternated, and the best wall time of each is kept (the
machine is shared: one scipy fit took 1.49 s of wall for 0.37 s of CPU). --quick: N_MANY = 4, N_SCIPY = 1, one
repeat (seconds; checks the script works).
Writes JSON and a PNG (seconds per curve; estimates of both fits over the truth with their 95 % intervals).
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))
import _common as common  # noqa: E402
from fit_reference import relaxed_slip, slip_curve  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402

import sweep  # noqa: E402
from sweep.fit import Curve  # noqa: E402
from sweep.fit import stack as _stack  # noqa: E402
from sweep.fit.space import make_space  # noqa: E402

DEFAULT_OUT = HERE / "results" / "fit.json"
SAMPLE2 = dict(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)
FREE = ("A", "m1", "m2")
KM, V, G, V0 = 2.8e5, 1e-6, 9.81, 1e-6
T = np.logspace(-1, 3.5, 200)
NOISE = 0.005
"""Noise of every sample, relative to the curve's relaxed slip."""
SPREAD = (0.8, 1.25)
"""Each curve's A, m1, m2: sample2's times a factor uniform in SPREAD."""
N_MANY, N_SCIPY = 100, 5
N_MANY_QUICK, N_SCIPY_QUICK = 4, 1
REPEATS = 3
SEED = 20261125
SCIPY_METHOD, SCIPY_RTOL, SCIPY_ATOL = "LSODA", 1e-8, 1e-12
TARGETS = {"one_curve_wall_s": 10.0, "many_curves_wall_s_per_100": 100.0, "ratio_per_curve": 100.0}


def make_curves(n: int) -> tuple[list[Curve], list[dict]]:
    """n noisy reference curves, each with its own parameters (returned too)."""
    rng = np.random.default_rng(SEED)
    curves, truths = [], []
    for i in range(n):
        p = {**SAMPLE2, **{k: SAMPLE2[k] * rng.uniform(*SPREAD) for k in FREE}}
        sigma = NOISE * relaxed_slip(p, KM, V)
        x = np.abs(slip_curve(p, KM, V, T) + sigma * rng.standard_normal(T.size))
        curves.append(Curve(T, x, KM, V, noise=sigma, sample=f"c{i}", name=f"c{i}"))
        truths.append(p)
    return curves, truths


class PointCounter:
    """Counts the engine's calls and points inside sweep.fit (wraps the forward model the problem stack calls)."""

    def __init__(self):
        self.calls = self.points = 0

    def __enter__(self):
        self._orig = _stack.forward

        def counted(points, *args, **kwargs):
            self.calls += 1
            self.points += points.n
            return self._orig(points, *args, **kwargs)

        _stack.forward = counted
        return self

    def __exit__(self, *exc):
        _stack.forward = self._orig


def engine_fit(curves: list[Curve]) -> dict:
    """sweep.fit of ``curves`` (each its own sample), timed; estimates, standard errors and intervals per curve."""
    with PointCounter() as count:
        c0, t0 = time.process_time(), time.perf_counter()
        ds = sweep.fit(curves, free=FREE, params="sample2")
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    est = {n: {"value": ds[n].values.tolist(), "stderr": ds[f"{n}_stderr"].values.tolist(),
               "lower": ds[f"{n}_lower"].values.tolist(), "upper": ds[f"{n}_upper"].values.tolist(),
               "label": [ds[f"{n}_label"].attrs["flag_meanings"].split()[int(v)] for v in ds[f"{n}_label"].values]}
           for n in FREE}
    return {"curves": len(curves), "wall_s": wall, "cpu_s": cpu, "wall_s_per_curve": wall / len(curves),
            "cpu_s_per_curve": cpu / len(curves), "engine_calls": count.calls, "forward_points": count.points,
            "forward_points_per_curve": count.points / len(curves), "stage_seconds": ds.attrs["fit_seconds"],
            "stage_rounds": ds.attrs["fit_rounds"], "estimates": est}


def scipy_model(theta: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, int]:
    """x(t) [m] of the quasi-static stop (docs/physics.md 3a) in reduced time tau = V t/D0 with solve_ivp:
    xi' = exp(-(chi xi + mu1 u + m2 u^2)/A - u), u' = exp(-u) - xi', xi(0) = u(0) = 0; and its nfev."""
    A, m1, m2 = theta
    D0 = SAMPLE2["D0"]
    chi, mu1 = KM * D0 / G, m1 - 2.0 * m2 * math.log(V / V0)

    def rhs(_tau, y):
        xi, u = y
        v = math.exp(min(-(chi * xi + mu1 * u + m2 * u * u) / A - u, 700.0))
        return [v, math.exp(-u) - v]

    tau = V * t / D0
    sol = solve_ivp(rhs, (0.0, tau[-1]), [0.0, 0.0], method=SCIPY_METHOD, t_eval=tau, rtol=SCIPY_RTOL,
                    atol=SCIPY_ATOL)
    x = D0 * sol.y[0] if sol.success and sol.y.shape[1] == t.size else np.full(t.size, np.nan)
    return x, sol.nfev


def scipy_fit(curve: Curve) -> dict:
    """least_squares over (A, m1, m2) from sample2 within sweep.fit's default bounds, x_scale as sweep.fit."""
    space = make_space(FREE, sweep.presets["sample2"])
    nfev = [0, 0]

    def resid(theta):
        x, n = scipy_model(theta, curve.t)
        nfev[0] += 1
        nfev[1] += n
        r = (x - curve.x) / curve.noise
        return np.where(np.isfinite(r), r, 1e3)

    c0, t0 = time.process_time(), time.perf_counter()
    sol = least_squares(resid, space.start, bounds=(space.lower, space.upper), x_scale=space.scale, method="trf")
    cov = np.linalg.inv(sol.jac.T @ sol.jac)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    se = np.sqrt(np.diag(cov))
    return {"wall_s": wall, "cpu_s": cpu, "model_evaluations": nfev[0], "rhs_evaluations": nfev[1],
            "seconds_per_model_evaluation": cpu / nfev[0], "status": int(sol.status),
            "estimates": {n: {"value": float(sol.x[j]), "stderr": float(se[j]), "lower": float(sol.x[j] - 1.96 * se[j]),
                              "upper": float(sol.x[j] + 1.96 * se[j])} for j, n in enumerate(FREE)}}


def side_by_side(engine: dict, scipy_fits: list[dict], truths: list[dict]) -> list[dict]:
    rows = []
    for i, sf in enumerate(scipy_fits):
        row = {"curve": i}
        for n in FREE:
            e = {k: engine["estimates"][n][k][i] for k in ("value", "stderr", "lower", "upper")}
            s = sf["estimates"][n]
            z = abs(e["value"] - s["value"]) / math.hypot(e["stderr"], s["stderr"])
            truth = truths[i][n]
            row[n] = {"truth": truth, "engine": e, "scipy": s, "difference_over_combined_stderr": z,
                      "agree": bool(z < 1.0), "truth_in_engine_interval": bool(e["lower"] <= truth <= e["upper"]),
                      "truth_in_scipy_interval": bool(s["lower"] <= truth <= s["upper"])}
        rows.append(row)
    return rows


def plot(result: dict, png: Path) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    one, many, sc = result["one_curve"], result["many_curves"], result["scipy"]
    labels = ["sweep.fit\none curve", f"sweep.fit\n{many['curves']} curves,\nper curve", "scipy\nper curve"]
    vals = [one["wall_s"], many["wall_s_per_curve"], sc["wall_s_per_curve"]]
    ax.bar(labels, vals, color=["C0", "C0", "C1"])
    ax.axhline(TARGETS["one_curve_wall_s"], color="k", ls="--", lw=0.8, label="targets: 10 s one curve, 1 s per curve")
    ax.axhline(TARGETS["many_curves_wall_s_per_100"] / 100, color="k", ls=":", lw=0.8)
    ax.set_yscale("log")
    ax.set_ylabel("wall seconds")
    ax.set_title(f"ratio per curve (scipy / engine) {result['ratio_per_curve']:.3g}x (target >= 100x)")
    ax.legend(fontsize=7)
    for k, n in enumerate(FREE):
        for i, row in enumerate(result["side_by_side"]):
            for dx, who, c in ((-0.12, "engine", "C0"), (0.12, "scipy", "C1")):
                e, tr = row[n][who], row[n]["truth"]
                bx.errorbar(k + dx + 0.03 * i, e["value"] / tr, yerr=[[(e["value"] - e["lower"]) / tr],
                            [(e["upper"] - e["value"]) / tr]], fmt="o", ms=3, color=c,
                            label=who if (k, i) == (0, 0) else None)
    bx.axhline(1.0, color="k", lw=0.8)
    bx.set_xticks(range(len(FREE)), FREE)
    bx.set_ylabel("estimate / truth (95 % interval)")
    bx.set_title("the same curves fitted by both")
    bx.legend(fontsize=7)
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return str(png)


def print_table(result: dict) -> None:
    one, many, sc = result["one_curve"], result["many_curves"], result["scipy"]
    print(f"one curve:      wall {one['wall_s']:.2f} s, cpu {one['cpu_s']:.2f} s (target < 10 s), "
          f"{one['forward_points']} forward points in {one['engine_calls']} engine calls")
    print(f"{many['curves']} curves:      wall {many['wall_s']:.2f} s ({many['wall_s_per_curve']:.3f} s per curve), "
          f"cpu {many['cpu_s']:.2f} s; per 100 curves {100 * many['wall_s_per_curve']:.1f} s (target < 100 s)")
    print(f"scipy:          {sc['wall_s_per_curve']:.3f} s per curve (wall; {sc['curves']} curves, "
          f"{sc['model_evaluations_per_curve']:.0f} solve_ivp calls each)")
    print(f"ratio per curve {result['ratio_per_curve']:.3g}x (target >= 100x); least-squares stages alone "
          f"{result['ratio_least_squares_stage']:.3g}x; fits agree: {result['fits_agree']}")
    per = result["seconds_per_forward_solve"]
    print(f"per forward solve (cpu): engine {1e3 * per['engine_many_curves_cpu']:.3f} ms (all stages, rtol 1e-4 "
          f"and 1e-6), scipy {1e3 * per['scipy_cpu']:.2f} ms; forward solves per curve: engine "
          f"{many['forward_points_per_curve']:.0f}, scipy {sc['model_evaluations_per_curve']:.0f}")
    for row in result["side_by_side"]:
        print("  curve", row["curve"], "  ".join(
            f"{n}: {row[n]['engine']['value']:.5g} vs {row[n]['scipy']['value']:.5g} "
            f"(z {row[n]['difference_over_combined_stderr']:.2g})" for n in FREE))


FIRST_CALL = """
import json, sys, time
import numpy as np
t0, c0 = time.perf_counter(), time.process_time()
import sweep
from sweep.fit import Curve
t1, c1 = time.perf_counter(), time.process_time()
d = np.load(sys.argv[1])
sweep.fit(Curve(d["t"], d["x"], float(d["km"]), float(d["v"]), noise=float(d["s"])), free=("A", "m1", "m2"),
          params="sample2")
t2, c2 = time.perf_counter(), time.process_time()
print(json.dumps({"import_s": t1 - t0, "first_fit_wall_s": t2 - t1, "first_fit_cpu_s": c2 - c1}))
"""


def first_call(n: int) -> None:
    """``--first-call``: the first fit of n fresh processes, numba's cache warm (module docstring)."""
    import subprocess
    import tempfile

    t = np.logspace(-1, 3.5, 50)
    sigma = NOISE * relaxed_slip(SAMPLE2, KM, V)
    x = slip_curve(SAMPLE2, KM, V, t) + sigma * np.random.default_rng(SEED).standard_normal(t.size)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "curve.npz"
        np.savez(path, t=t, x=x, s=sigma, km=KM, v=V)
        rows = []
        for i in range(n + 1):  # the first warms the cache
            out = subprocess.run([sys.executable, "-c", FIRST_CALL, str(path)], capture_output=True, text=True,
                                 check=True)
            row = json.loads(out.stdout.strip().splitlines()[-1])
            print(("warm-up: " if i == 0 else f"{i}/{n}: ") + ", ".join(f"{k} {v:.2f}" for k, v in row.items()),
                  flush=True)
            rows += [row] if i else []
    for key in rows[0]:
        v = np.array([r[key] for r in rows])
        print(f"{key}: min {v.min():.2f}, median {np.median(v):.2f}, max {v.max():.2f} (load {common.loadavg()})")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help=f"{N_MANY_QUICK} curves in one call, scipy on "
                                                         f"{N_SCIPY_QUICK}: seconds, checks that the script works")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--no-png", action="store_true")
    ap.add_argument("--repeats", type=int, default=None, help=f"fits of each kind, alternated, the best kept "
                                                                 f"(default {REPEATS}; --quick: 1)")
    ap.add_argument("--first-call", type=int, default=None, metavar="N",
                    help="time the first fit of N fresh processes (warm cache) instead; writes nothing")
    args = ap.parse_args(argv)
    if args.first_call:
        first_call(args.first_call)
        return
    repeats = max(1, args.repeats or (1 if args.quick else REPEATS))
    t_start = time.perf_counter()
    load0, digest0 = common.loadavg(), common.sweep_digest()
    n_many, n_scipy = (N_MANY_QUICK, N_SCIPY_QUICK) if args.quick else (N_MANY, N_SCIPY)

    c0 = time.perf_counter()
    curves, truths = make_curves(n_many)
    data_s = time.perf_counter() - c0
    c0 = time.perf_counter()
    sweep.fit(curves[0], free=FREE, params="sample2", profiles=False)  # kernels compiled or loaded
    warm_up_s = time.perf_counter() - c0
    print(f"data {data_s:.1f} s, warm-up {warm_up_s:.1f} s", flush=True)
    one = many = None
    fits: list[dict | None] = [None] * n_scipy
    best = lambda old, new: new if old is None or new["wall_s"] < old["wall_s"] else old  # noqa: E731
    walls = {"one_curve": [], "many_curves": [], "scipy": []}
    for r in range(repeats):  # the engine's and scipy's fits alternated, the best of each kept: the machine is shared
        one = best(one, engine_fit(curves[:1]))
        many = best(many, engine_fit(curves))
        walls["one_curve"].append(one["wall_s"])
        walls["many_curves"].append(many["wall_s"])
        fits = [best(f, scipy_fit(c)) for f, c in zip(fits, curves[:n_scipy])]
        walls["scipy"].append(sum(f["wall_s"] for f in fits))
        print(f"repeat {r + 1}/{repeats}: one curve {one['wall_s']:.2f} s, {n_many} curves {many['wall_s']:.2f} s, "
              f"scipy {sum(f['wall_s'] for f in fits) / n_scipy:.3f} s a curve (best so far)", flush=True)
    sc = {"curves": n_scipy, "method": SCIPY_METHOD, "rtol": SCIPY_RTOL, "atol": SCIPY_ATOL,
          "wall_s_per_curve": float(np.mean([f["wall_s"] for f in fits])),
          "cpu_s_per_curve": float(np.mean([f["cpu_s"] for f in fits])),
          "model_evaluations_per_curve": float(np.mean([f["model_evaluations"] for f in fits])), "fits": fits}
    rows = side_by_side(many, fits, truths)
    result = {
        "benchmark": "benchmarks/fit.py" + (" --quick" if args.quick else ""),
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "machine": common.machine_info(),
        "sweep_source_digest_start_end": [digest0, common.sweep_digest()],
        "loadavg_start_end": [load0, common.loadavg()],
        "settings": {"params": SAMPLE2, "free": list(FREE), "K_over_M": KM, "V": V, "samples": T.size,
                     "t_range_s": [float(T[0]), float(T[-1])], "noise_relative_to_relaxed_slip": NOISE,
                     "spread": SPREAD, "seed": SEED, "start": "sample2 (both fits)",
                     "data": "tests/fit_reference.py (scipy reference, rtol 1e-13)",
                     "engine": "sweep.fit defaults: global stage, least squares at rtol 1e-6, profiles",
                     "scipy": f"least_squares trf from sample2, sweep.fit's default bounds and x_scale; solve_ivp "
                              f"{SCIPY_METHOD} rtol {SCIPY_RTOL:g} atol {SCIPY_ATOL:g}; intervals +-1.96 stderr "
                              f"(no global stage, no profiles)"},
        "data_s": data_s, "warm_up_s": warm_up_s, "repeats": repeats,
        "best_so_far_wall_s_by_repeat": walls,
        "one_curve": one, "many_curves": many, "scipy": sc,
        "ratio_per_curve": sc["wall_s_per_curve"] / many["wall_s_per_curve"],
        "ratio_per_curve_cpu": sc["cpu_s_per_curve"] / many["cpu_s_per_curve"],
        "ratio_least_squares_stage": sc["wall_s_per_curve"] * n_many
        / json.loads(many["stage_seconds"])["least_squares"],
        "seconds_per_forward_solve": {"engine_many_curves_cpu": many["cpu_s"] / many["forward_points"],
                                      "scipy_cpu": float(np.mean([f["seconds_per_model_evaluation"] for f in fits]))},
        "side_by_side": rows,
        "fits_agree": all(row[n]["agree"] for row in rows for n in FREE),
        "targets": TARGETS,
        "meets": {"one_curve": one["wall_s"] < TARGETS["one_curve_wall_s"],
                  "many_curves": 100 * many["wall_s_per_curve"] < TARGETS["many_curves_wall_s_per_100"],
                  "ratio": sc["wall_s_per_curve"] / many["wall_s_per_curve"] >= TARGETS["ratio_per_curve"]},
        "benchmark_wall_s": None,
    }
    common.write_result(result, args.out, t_start, None if args.no_png else plot, print_table)


if __name__ == "__main__":
    main()
