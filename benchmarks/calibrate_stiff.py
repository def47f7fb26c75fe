#!/usr/bin/env python
"""Calibration of the Rosenbrock (ros4) lanes against RK4 in the stiff region: sweep.plan.plan.STIFF_K_MAX,
STIFF_WORK_MIN and C_STIFF come from this script.

    python benchmarks/calibrate_stiff.py [--quick] [--out benchmarks/results/calibrate_stiff.json]

A grid of reduced points (k = chi/A 1e-3..1, a = mu1/A -0.3..-6, b = m2/A 0.01..3) with a creep manifold
(work = |a|^3/(4 b k) > 30) is solved by RK4 at h = 0.02 (reference, error ~1e-11) and by ros4 and RK4 at
h = 0.5..0.0625 (the lane kernels of the engine, float64). For each subset (k <= k_max, work >= w_min) it
reports the largest ros4 error constant C = |err/xi_inf| / h^4, and the cost of ros4 relative to RK4 at equal
error (steps x evaluations per step x err^(1/4), both methods being of order 4).

It calls the lane kernels directly (sweep.integrate.lanes: one run per point at the step h, no step ladder), so it
follows their signature. --quick: a 5 x 4 x 3 grid and steps 0.5 and 0.125 (a few seconds: does it work).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from sweep.integrate.lanes import LaneOutputs, LanePoints, LaneRuns, lane_kernels
from sweep.plan.plan import time_scale

HERE = Path(__file__).resolve().parent
EVALS_PER_STEP = {"rk4": 4, "ros4": 3}


def run(method, h, k, a, b, rtol=1e-11):
    """Relaxed slip, steps and status of every point with the lane kernel of ``method`` at fixed h."""
    relax_batch = lane_kernels(np.dtype(np.float64), method)[1]
    n = k.size
    out = LaneOutputs(np.full(n, np.nan), np.full(n, np.nan), np.empty(0), np.zeros(n, np.int8), np.zeros(n, np.int32))
    relax_batch(LanePoints(k, a, b, time_scale(k, a), np.zeros(n)), LaneRuns(np.arange(n), np.full(n, h), rtol, 1e-12,
                2_000_000), 2, out)
    return out.xi_inf, out.steps, out.status


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a 5 x 4 x 3 grid, steps 0.5 and 0.125")
    ap.add_argument("--out", default=str(HERE / "results" / "calibrate_stiff.json"))
    args = ap.parse_args(argv)
    n_k, n_a, n_b = (5, 4, 3) if args.quick else (13, 9, 8)
    grids = np.meshgrid(np.geomspace(1e-3, 1.0, n_k), -np.geomspace(0.3, 6, n_a), np.geomspace(0.01, 3, n_b),
                        indexing="ij")
    k, a, b = (g.ravel() for g in grids)
    work = np.abs(a) ** 3 / (4 * b * k)
    sel = work > 30
    k, a, b, work = k[sel], a[sel], b[sel], work[sel]
    ref, _, ref_status = run("rk4", 0.02, k, a, b)
    ok = ref_status == 0
    rows = []
    for h in (0.5, 0.125) if args.quick else (0.5, 0.25, 0.125, 0.0625):
        xr, sr, _ = run("ros4", h, k, a, b)
        xk, sk, _ = run("rk4", h, k, a, b)
        er, ek = np.abs(xr / ref - 1), np.abs(xk / ref - 1)
        for k_max in (0.03, 0.1, 1.0):
            for w_min in (100.0, 300.0, 1000.0):
                m = ok & (k <= k_max) & (work >= w_min)
                if not m.any():  # (a --quick grid may leave a subset empty)
                    rows.append({"h": h, "k_max": k_max, "work_min": w_min, "points": 0})
                    print(f"h={h:.3g} k_max={k_max:.3g} work_min={w_min:.3g} points=0")
                    continue
                cost = ((sr[m] * EVALS_PER_STEP["ros4"] * er[m] ** 0.25)
                        / (sk[m] * EVALS_PER_STEP["rk4"] * ek[m] ** 0.25))
                row = {"h": h, "k_max": k_max, "work_min": w_min, "points": int(m.sum()),
                       "ros4_C_max": float((er[m] / h**4).max()), "ros4_C_median": float(np.median(er[m] / h**4)),
                       "rk4_C_max": float((ek[m] / h**4).max()), "cost_ros4_over_rk4_median": float(np.median(cost)),
                       "cost_ros4_over_rk4_max": float(cost.max()), "steps_ros4_mean": float(sr[m].mean()),
                       "steps_rk4_mean": float(sk[m].mean())}
                rows.append(row)
                print(" ".join(f"{key}={val:.3g}" if isinstance(val, float) else f"{key}={val}"
                               for key, val in row.items()))
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps({"what": __doc__.splitlines()[0], "quick": args.quick, "points": int(k.size),
                                          "reference_failures": int((~ok).sum()), "rows": rows}, indent=1))
    print("wrote", args.out)


if __name__ == "__main__":
    main()
