"""Measure the RK4 error constant C = |err(xi_inf)/xi_inf| / h^4 behind the plan's step rule (sweep/plan.py).

Stable (chi > mu1) and unstable points are reported apart (the plan uses one constant for each).
Points: 400 random (chi/A 1e-2..1e3; m2/A = 0 with m1/A 0.3..3, or m2/A 1e-3..3 with mu1/A -3..3) plus a
structured set of corners. Reference per point: the same kernel at h = 0.008 (error ~1e-12, i.e. far below
the errors measured; tests/test_accuracy.py checks the rule against the independent scipy reference).
Writes benchmarks/results/calibrate_rk4.json. Run: python benchmarks/calibrate_rk4.py
"""

import json
import math
import time
from pathlib import Path

import numpy as np

from sweep.models.stop import solve_stop_point
from sweep.plan import C_STABLE, C_UNSTABLE, H_MAX, SAFETY, time_scale

NONE = np.empty(0)


def xi_inf(k, a, b, h, rtol):
    finite = b > 0 or (b == 0 and a > 0)
    status, x, n = solve_stop_point(k, a, b, h, time_scale(k, a), 10**8, finite, rtol, 1e-14, NONE, NONE, NONE,
                                    NONE, np.empty(2))
    return x if status == 0 else math.nan, n


def points(seed=7):
    rng = np.random.default_rng(seed)
    pts = []
    for _ in range(400):
        k = 10 ** rng.uniform(-2, 3)
        b = rng.choice([0.0, 10 ** rng.uniform(-3, 0.5)])
        a = 10 ** rng.uniform(math.log10(0.3), math.log10(3)) if b == 0 else rng.uniform(-3, 3)
        pts.append((k, a, b))
    for k in (0.01, 0.1, 1, 10, 100, 1000):
        for a, b in ((0.3, 0), (3, 0), (-2.56, 0.47), (1.79, 0.47), (0.3, 0.001), (-3, 3), (3, 3)):
            pts.append((k, a, b))
    return pts


def main():
    pts = points()
    t0 = time.perf_counter()
    ref = np.array([xi_inf(k, a, b, 0.008, 1e-13)[0] for k, a, b in pts])
    stable = np.array([k > a for k, a, _ in pts])
    rows = []
    for h in (0.7, 0.5, 0.3, 0.1, 0.05):
        res = [xi_inf(k, a, b, h, 1e-12) for k, a, b in pts]
        C = np.array([abs(x / r - 1) for (x, _), r in zip(res, ref)]) / h**4
        row = {"h": h, "mean_steps": float(np.mean([n for _, n in res]))}
        for side, mask in (("stable", stable), ("unstable", ~stable)):
            worst = int(np.flatnonzero(mask)[np.nanargmax(C[mask])])
            row[side] = {"points": int(mask.sum()), "C_max": float(np.nanmax(C[mask])),
                         "C_p99": float(np.nanpercentile(C[mask], 99)), "C_median": float(np.nanmedian(C[mask])),
                         "worst_point_k_a_b": pts[worst]}
            print(f"h={h:<5} {side:>8} ({mask.sum()} points): C max {row[side]['C_max']:.2e} "
                  f"p99 {row[side]['C_p99']:.2e} median {row[side]['C_median']:.2e}  worst (k, a, b) = {pts[worst]}")
        rows.append(row)
    out = {"points": len(pts), "reference_failures": int(np.isnan(ref).sum()), "rows": rows,
           "plan_constants": {"C_STABLE": C_STABLE, "C_UNSTABLE": C_UNSTABLE, "SAFETY": SAFETY, "H_MAX": H_MAX},
           "seconds": time.perf_counter() - t0}
    path = Path(__file__).parent / "results" / "calibrate_rk4.json"
    path.write_text(json.dumps(out, indent=2))
    print(f"plan: C_STABLE {C_STABLE} (max measured {max(r['stable']['C_max'] for r in rows):.2e}), "
          f"C_UNSTABLE {C_UNSTABLE} (max measured {max(r['unstable']['C_max'] for r in rows):.2e}); wrote {path}")


if __name__ == "__main__":
    main()
