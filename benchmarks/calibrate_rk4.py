#!/usr/bin/env python
"""Measure the RK4 error constant C = |err(xi_inf)/xi_inf| / h^4 behind the plan's step rule (sweep/plan/plan.py).

    python benchmarks/calibrate_rk4.py [--quick] [--out benchmarks/results/calibrate_rk4.json]

h is the step in sigma of the run whose value the engine returns (the fine run of the Richardson pair; its
coarse run has 2h); the plan picks h = min(H_MAX/2, (rtol / (STEP_SAFETY * ERROR_GAIN * C))^(1/4)) with
C = C_STABLE or C_UNSTABLE. Stable (chi > mu1) and unstable points are reported apart (the plan uses one
constant for each). Every point goes through the public engine: a 1 x 1 Scene (method "rk4", step h, rtol 1e-10,
the smallest a Scene takes, so the tail test adds < 1e-13 relative; atol 1e-14) whose friction parameters
reproduce the point's reduced k = chi/A, a = mu1/A, b = m2/A (A = 0.01, D0 = 1e-6 m, V = V0), run by
sweep.make_plan + sweep.protocols.stop.engine.execute. Also recorded per step: the engine's own error estimate over
the true
error (the plan assumes it is ~ERROR_GAIN).
Points: 400 random (chi/A 1e-2..1e3; m2/A = 0 with m1/A 0.3..3, or m2/A 1e-3..3 with mu1/A -3..3) plus a
structured set of corners (--quick: 40 random, two steps). Reference per point: the same engine at h = 0.008
(error ~1e-12, i.e. far below the errors measured; tests/plan/test_accuracy.py checks the rule against the
independent scipy reference).

Changed in the port to the current engine: the old script called the scalar per-point kernel with rtol 1e-12
(measurements) and 1e-13 (reference); a Scene accepts rtol >= 1e-10, so both now use 1e-10. The measured h now
also includes 0.35, the plan's largest fine step (H_MAX/2).

Writes benchmarks/results/calibrate_rk4.json (or --out).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from _common import cpu_model, git_commit, sweep_tree_dirty, versions

import sweep
from sweep.plan.plan import C_STABLE, C_UNSTABLE, H_MAX, STEP_SAFETY
from sweep.plan.plan import ERROR_GAIN as PLAN_ERROR_GAIN
from sweep.protocols.stop.chunk import execute

HERE = Path(__file__).resolve().parent
DEFAULT_OUT = HERE / "results" / "calibrate_rk4.json"
A = 0.01  # any A > 0: the stop problem depends on k, a, b only
D0, V0, G = 1e-6, 1e-6, 9.81
RTOL = 1e-10  # smallest rtol a Scene accepts: it only sets the tail test and the status here
ATOL = 1e-14
H_REF = 0.008
STEPS = (0.7, 0.5, 0.35, 0.3, 0.1, 0.05)
STEPS_QUICK = (0.35, 0.1)
VALUE_STATUSES = (int(sweep.Status.OK), int(sweep.Status.ERROR_ABOVE_TOL))  # a fixed step need not meet rtol


def xi_inf(k, a, b, h):
    """(xi_inf, its error estimate, fine-run steps) of the reduced point (k, a, b) at the fixed step h in sigma,
    through the public engine; NaN where the engine computed no value."""
    params = sweep.FrictionParams(A=A, m1=a * A, m2=b * A, D0=D0, V0=V0, g=G)  # mu1(V0) = m1
    scene = sweep.Scene(protocol="stop", params=params, K_over_M=[k * A * G / D0], V=[V0], rtol=RTOL,
                        atol={"xi_inf": ATOL}, method="rk4", step=h, max_steps=10**8)
    res = execute(scene, sweep.make_plan(scene), progress=False)
    ok = int(res.status[0]) in VALUE_STATUSES
    return (float(res.xi_inf[0]) if ok else math.nan), (float(res.xi_inf_err[0]) if ok else math.nan), \
        int(res.steps[0])


def points(seed=7, n_random=400):
    rng = np.random.default_rng(seed)
    pts = []
    for _ in range(n_random):
        k = 10 ** rng.uniform(-2, 3)
        b = rng.choice([0.0, 10 ** rng.uniform(-3, 0.5)])
        a = 10 ** rng.uniform(math.log10(0.3), math.log10(3)) if b == 0 else rng.uniform(-3, 3)
        pts.append((float(k), float(a), float(b)))
    for k in (0.01, 0.1, 1, 10, 100, 1000):
        for a, b in ((0.3, 0), (3, 0), (-2.56, 0.47), (1.79, 0.47), (0.3, 0.001), (-3, 3), (3, 3)):
            pts.append((float(k), float(a), float(b)))
    return pts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="40 random points + the structured set, steps 0.35 and 0.1")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args(argv)
    pts = points(n_random=40 if args.quick else 400)
    steps = STEPS_QUICK if args.quick else STEPS
    t0 = time.perf_counter()
    ref = np.array([xi_inf(k, a, b, H_REF)[0] for k, a, b in pts])
    stable = np.array([k > a for k, a, _ in pts])
    rows = []
    for h in steps:
        res = [xi_inf(k, a, b, h) for k, a, b in pts]
        x = np.array([r[0] for r in res])
        err = np.abs(x / ref - 1)
        C = err / h**4
        ratio = np.array([r[1] for r in res]) / np.abs(x) / np.maximum(err, 1e-300)  # estimate / true error
        resolved = err > 1e-11  # true error well above the reference's own
        row = {"h": h, "mean_steps": float(np.mean([r[2] for r in res])), "failures": int(np.isnan(x).sum())}
        for side, mask in (("stable", stable), ("unstable", ~stable)):
            if not np.any(np.isfinite(C[mask])):
                row[side] = {"points": int(mask.sum()), "C_max": None}
                print(f"h={h:<5} {side:>8}: no point computed", flush=True)
                continue
            worst = int(np.flatnonzero(mask)[np.nanargmax(C[mask])])
            sel = mask & resolved & np.isfinite(ratio)
            row[side] = {"points": int(mask.sum()), "C_max": float(np.nanmax(C[mask])),
                         "C_p99": float(np.nanpercentile(C[mask], 99)), "C_median": float(np.nanmedian(C[mask])),
                         "worst_point_k_a_b": pts[worst],
                         "estimate_over_true_min": float(ratio[sel].min()) if sel.any() else None,
                         "estimate_over_true_median": float(np.median(ratio[sel])) if sel.any() else None,
                         "estimate_over_true_max": float(ratio[sel].max()) if sel.any() else None}
            est = row[side]
            print(f"h={h:<5} {side:>8} ({mask.sum()} points): C max {est['C_max']:.2e} p99 {est['C_p99']:.2e} "
                  f"median {est['C_median']:.2e}  worst (k, a, b) = {pts[worst]}; estimate/true "
                  + (f"{est['estimate_over_true_min']:.3g}..{est['estimate_over_true_max']:.3g}"
                     if sel.any() else "-"), flush=True)
        rows.append(row)
    out = {"benchmark": "benchmarks/calibrate_rk4.py" + (" --quick" if args.quick else ""),
           "points": len(pts), "reference_failures": int(np.isnan(ref).sum()),
           "setup": {"path": "sweep.make_plan + sweep.protocols.stop.chunk.execute on a 1 x 1 Scene per point and "
                              "step",
                     "method": "rk4", "rtol": RTOL, "atol": ATOL, "h_reference": H_REF,
                     "h": "fine-run step in sigma (the returned value's run; the coarse run has 2h)"},
           "rows": rows,
           "plan_constants": {"C_STABLE": C_STABLE, "C_UNSTABLE": C_UNSTABLE, "STEP_SAFETY": STEP_SAFETY,
                              "ERROR_GAIN": PLAN_ERROR_GAIN, "H_MAX": H_MAX},
           "machine": {"cpu": cpu_model()},
           "versions": {**versions(), "git_commit": git_commit(), "sweep_tree_dirty": sweep_tree_dirty()},
           "seconds": time.perf_counter() - t0}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2) + "\n")
    c_max = {side: max((r[side]["C_max"] for r in rows if r[side]["C_max"] is not None), default=math.nan)
             for side in ("stable", "unstable")}
    print(f"plan: C_STABLE {C_STABLE} (max measured {c_max['stable']:.2e}), C_UNSTABLE {C_UNSTABLE} (max measured "
          f"{c_max['unstable']:.2e}); wrote {args.out}")


if __name__ == "__main__":
    main()
