"""How well ``xi_inf_error`` keeps its promise: coverage on a table of extreme stop points (issue 20).

    python benchmarks/error_coverage.py [--quick] [--methods auto,dp5] [--rtols 1e-4,1e-6,1e-8] [--out PATH]

The table: A in {3e-4, 1e-3, 7e-3, 3e-2}, m2/A in {0, 0.5, 2}, m1 in {-0.02, 0.002, 0.02} (m1 < 0 only with
m2 > 0, where a finite relaxed slip exists), each over K/M 1e1..1e7 (8 values) x V 1e-8..1e-3 (6 values): 1,536
points per rtol with small and large chi/A, mu1 < 0, the stiff corner and small A (``--quick``: A 1e-3 only, K/M
1e5..1e7 (3) x V (3): a smoke run, ~10 s; the soft springs K/M <= 1e3 with mu1 < 0 cost the reference ~70 s of a
4 x 3 grid's 72 s, so they are left out there). Every point is solved by the engine (``sweep.run_sweep``,
quasi-static, relaxed slip) and by the independent scipy reference of tests/reference.py (DOP853/Radau at 1e-13 in
its own formulation, closed-form tail).

Reported per method and rtol, over the points the reference resolves:

* ``ok_beyond_tol``: points with status ok whose true error exceeds rtol |xi_inf| + atol (the promise that matters
  most: never a wrong number marked ok);
* ``bounded``: the fraction of points where the true error <= xi_inf_error (the estimate floored at what the
  reference resolves, 1e-13 relative); ``max_true_over_estimate`` the worst ratio;
* ``error_above_tol`` and ``false_alarms``: points flagged error_above_tol whose true error is <= rtol/10 of |xi_inf|.

Writes JSON (and a PNG of true error vs estimate) under benchmarks/results/.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE))
import reference as refmod  # noqa: E402  (tests/reference.py: scipy only, independent of sweep)
from _common import machine_info, write_result  # noqa: E402

import sweep  # noqa: E402

DEFAULT_OUT = HERE / "results" / "error_coverage.json"
REFERENCE_RESOLVES = 1e-13
"""Relative accuracy of the reference's xi_inf (tests/integrate/test_error_estimates.py: REFERENCE_REL 1e-12 is what
the tests
trust; DOP853 and Radau agree to 1e-13 on the case table)."""
FALSE_ALARM = 0.1
"""A flag error_above_tol is a false alarm where the true error is at most this fraction of the tolerance."""


def scenes(quick: bool) -> list[sweep.Scene]:
    """The table's scenes (module docstring)."""
    base = sweep.default_scene()
    out = []
    for A in (1e-3,) if quick else (3e-4, 1e-3, 7e-3, 3e-2):
        for m2 in (0.0, 0.5 * A, 2.0 * A):
            for m1 in ((0.002, 0.02) if m2 == 0.0 else (-0.02, 0.002, 0.02)):
                params = dataclasses.replace(base.params, A=A, m2=m2, m1=m1)
                K = np.logspace(5, 7, 3) if quick else np.logspace(1, 7, 8)  # quick: the reference's cheap points
                out.append(dataclasses.replace(base, params=params, K_over_M=K,
                                               V=np.logspace(-8, -3, 3 if quick else 6), model="quasistatic"))
    return out


def reference(chi: float, A: float, mu1: float, m2: float, cache: dict) -> float:
    """The reference's relaxed slip (NaN where it cannot resolve the point)."""
    key = (chi, A, mu1, m2)
    if key not in cache:
        try:
            cache[key] = refmod.reference_stop(chi, A, mu1, m2).xi_inf
        except (OverflowError, RuntimeError, ValueError):
            cache[key] = float("nan")
    return cache[key]


def measure(method: str, rtol: float, table: list[sweep.Scene], cache: dict) -> dict:
    """Coverage figures of one method at one rtol (module docstring), with the worst points."""
    rows = []
    t0 = time.perf_counter()
    for scene in table:
        scene = dataclasses.replace(scene, rtol=rtol, method=method)
        ds = sweep.run_sweep(scene, progress=False)
        plan = sweep.make_plan(scene)
        names = dict(zip(ds["status"].attrs["flag_values"], ds["status"].attrs["flag_meanings"].split()))
        x, e, st = (ds[v].values.ravel() for v in ("xi_inf", "xi_inf_error", "status"))
        for f in range(x.size):
            if names[st[f]] not in ("ok", "error_above_tol"):
                continue
            exact = reference(float(plan.chi[f]), scene.params.A, float(plan.mu1[f]), scene.params.m2, cache)
            if np.isfinite(exact):
                rows.append((float(x[f]), float(e[f]), abs(float(x[f]) - exact), abs(exact), names[st[f]] == "ok",
                             float(plan.k[f]), float(plan.a[f]), float(plan.b[f]), scene.params.A))
    x, e, true, exact, ok = (np.array([r[i] for r in rows]) for i in range(5))
    tol = rtol * exact + scene.atol["xi_inf"]
    floored = np.maximum(e, REFERENCE_RESOLVES * exact)
    ratio = true / floored
    false_alarm = ~ok & (true <= FALSE_ALARM * tol)
    worst = np.argsort(-ratio)[:5]
    return {"method": method, "rtol": rtol, "points": len(rows), "ok": int(ok.sum()),
            "ok_beyond_tol": int((ok & (true > tol)).sum()), "bounded": float((ratio <= 1.0).mean()),
            "max_true_over_estimate": float(ratio.max()), "error_above_tol": int((~ok).sum()),
            "false_alarms": int(false_alarm.sum()), "seconds": time.perf_counter() - t0,
            "worst": [{"k": rows[i][5], "a": rows[i][6], "b": rows[i][7], "A": rows[i][8], "true": float(true[i]),
                       "estimate": float(e[i]), "ok": bool(ok[i])} for i in worst],
            "pairs": np.column_stack((true, e)).__truediv__(np.maximum(exact, 1e-300)[:, None]).tolist()}


def plot(result: dict, path: Path) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 5))
    for row in result["rows"]:
        pairs = np.array(row["pairs"])
        ax.loglog(np.maximum(pairs[:, 1], 1e-17), np.maximum(pairs[:, 0], 1e-17), ".", ms=2,
                  label=f"{row['method']} rtol {row['rtol']:g}")
    ax.plot([1e-17, 1], [1e-17, 1], "k-", lw=0.8, label="true = estimate")
    ax.set_xlabel("xi_inf_error / |xi_inf| (estimate)")
    ax.set_ylabel("true error / |xi_inf| (scipy reference)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def print_table(result: dict) -> None:
    print(f"\n{'method':8s}{'rtol':>8s}{'points':>8s}{'ok>tol':>8s}{'bounded':>9s}{'max t/e':>9s}{'flagged':>9s}"
          f"{'false':>7s}")
    for r in result["rows"]:
        print(f"{r['method']:8s}{r['rtol']:8.0e}{r['points']:8d}{r['ok_beyond_tol']:8d}{100 * r['bounded']:8.1f}%"
              f"{r['max_true_over_estimate']:9.2f}{r['error_above_tol']:9d}{r['false_alarms']:7d}")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="A = 1e-3 only, 3 x 3 grids (K/M >= 1e5), rtol 1e-6 (a smoke "
                                                         "run)")
    ap.add_argument("--methods", default="auto", help="comma-separated Scene.method values (default auto)")
    ap.add_argument("--rtols", default=None, help="comma-separated (default 1e-4,1e-6,1e-8)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--no-png", action="store_true")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    rtols = [float(v) for v in (args.rtols or ("1e-6" if args.quick else "1e-4,1e-6,1e-8")).split(",")]
    table, cache = scenes(args.quick), {}
    result = {"benchmark": "benchmarks/error_coverage.py", "command": " ".join(sys.argv), "quick": args.quick,
              "machine": machine_info(), "rows": []}
    for method in args.methods.split(","):
        for rtol in rtols:
            result["rows"].append(measure(method, rtol, table, cache))
            print_table({"rows": result["rows"][-1:]})
    write_result(result, args.out, t_start, None if args.no_png else plot, print_table)


if __name__ == "__main__":
    main()
