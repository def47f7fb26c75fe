"""What the per-point model choice of the stop scene costs and buys (Scene.model, Scene.model_tol).

Side by side, in one run, through the public ``sweep.run_sweep``:

1. cost: the default scene (``sweep.default_scene()``: sample2, 200 x 100 points) and a scene where inertia matters
   (``INERTIA_SCENE``: sample1 with D0 = 0.1 um, so that gamma/A = V^2/(g D0 A) runs from 1e-6 to 8.5 over
   K/M 1e3..1e6 s^-2 (100) x V 0.1..316 um/s (50)), each with model "quasistatic", "auto" and "inertial": wall time
   of ``run_sweep`` (best of 3 after a warm-up call; it also locates the simulated Hopf line of the model),
   ``elapsed_seconds`` of the Dataset (the kernels and the model choice), the line alone (``locate_hopf``), the
   points solved with inertia and the ratios to "quasistatic";
2. what "auto" buys on the inertia scene: the true relative model error of auto's and of quasistatic's xi_inf
   against the inertial model at rtol 1e-9 (the reference), max and 99th percentile, the points where auto's
   error exceeds model_tol (there should be none), and true error / model_error (the first-order estimate) over
   the points auto left quasi-static;
3. the trade the user chooses: model_tol 1e-1 .. 1e-4 on the inertia scene, fraction of inertial points, time,
   achieved true error.

Writes benchmarks/results/models.json (machine, versions, every number) and models.png (left: model_error over
(K/M, V) with the model_tol contour and the inertial points; right: wall time vs model_tol). numba runs with its
default threads (recorded). Run: python benchmarks/models.py (~2-3 min on 2 cores).

    python benchmarks/models.py [--quick] [--out benchmarks/results/models.json] [--no-png]

--quick: both scenes on coarse grids (every 20th K/M and 10th V of the default scene: 10 x 10; every 10th K/M and
V of the inertia scene: 10 x 5), model_tol 1e-1 and 1e-3 only, one timed call after the warm-up: checks that the
script works (seconds); its numbers are not results.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from dataclasses import asdict
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import loadavg, machine_info, sweep_digest  # noqa: E402

import sweep  # noqa: E402
from sweep.protocols.stop.model_choice import ESTIMATE_MARGIN, FIRST_ORDER_TRUST  # noqa: E402
from sweep.status import Status  # noqa: E402

OUT = Path(__file__).resolve().parent / "results"
MODELS = ("quasistatic", "auto", "inertial")
MODEL_TOLS = (1e-1, 1e-2, 1e-3, 1e-4)
REFERENCE_RTOL = 1e-9
RATIO_MIN_TRUE_ERROR = 1e-4
"""true error / model_error is taken only where the true error is >= this (100 x the scene's rtol 1e-6: the
numerical error of both values then changes the ratio by < 2 %)."""
INERTIA_PARAMS = sweep.presets["sample1"].replace(D0=1e-7)
INERTIA_SCENE = sweep.Scene(protocol="stop", params=INERTIA_PARAMS, K_over_M=np.logspace(3, 6, 100),
                            V=np.logspace(-7, -3.5, 50), rtol=1e-6)


def best_of(fn, repeats=3):
    """fn() once untimed (warm-up), then ``repeats`` timed calls: (best wall seconds, all, last result)."""
    out = fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), times, out


def with_model(scene, model, **kw):
    return sweep.Scene(protocol="stop", params=scene.params, K_over_M=scene.K_over_M, V=scene.V, rtol=scene.rtol,
                       model=model, **kw)


def status_counts(ds):
    values, counts = np.unique(ds["status"].values, return_counts=True)
    return {Status(int(v)).name.lower(): int(c) for v, c in zip(values, counts)}


def gamma_over_A(scene):
    p = scene.params
    return scene.V**2 / (p.g * p.D0) / p.A


def time_models(scene, label, model_tol=1e-2, repeats=3):
    """Part 1 for one scene: every model, best-of-``repeats`` run_sweep, elapsed_seconds, the line alone."""
    rows, datasets = {}, {}
    for model in MODELS:
        sc = with_model(scene, model, model_tol=model_tol)
        wall, walls, ds = best_of(lambda sc=sc: sweep.run_sweep(sc, progress=False), repeats)
        line_s, _, _ = best_of(lambda sc=sc: sweep.locate_hopf(sc.params, sc.V, model=sc.model, bifurcation=False,
                                                              model_tol=sc.model_tol), repeats)
        n_in = int(ds["model"].values.sum())
        rows[model] = {"wall_s_best_of_3": wall, "wall_s_all": walls, "elapsed_seconds": ds.attrs["elapsed_seconds"],
                       "line_s_best_of_3": line_s, "inertial_points": n_in,
                       "inertial_fraction": n_in / scene.n_points, "status": status_counts(ds),
                       "plan_model": ds.attrs.get("plan_model")}
        datasets[model] = ds
        print(f"  {label:9s} {model:11s} wall {wall:7.3f} s  elapsed {ds.attrs['elapsed_seconds']:7.3f} s  "
              f"line {line_s:6.3f} s  inertial {n_in:5d} ({n_in / scene.n_points:6.1%})  {rows[model]['status']}",
              flush=True)
    q = rows["quasistatic"]
    for model in ("auto", "inertial"):
        rows[f"{model}_over_quasistatic"] = {
            "wall": rows[model]["wall_s_best_of_3"] / q["wall_s_best_of_3"],
            "elapsed": rows[model]["elapsed_seconds"] / q["elapsed_seconds"]}
    rows["auto_model_choice_s"] = rows["auto"]["elapsed_seconds"] - q["elapsed_seconds"]
    g = gamma_over_A(scene)
    return {"points": scene.n_points, "shape": list(scene.shape), "params": asdict(scene.params),
            "K_over_M_range": [float(scene.K_over_M[0]), float(scene.K_over_M[-1])],
            "V_range": [float(scene.V[0]), float(scene.V[-1])], "gamma_over_A_range": [float(g.min()), float(g.max())],
            "rtol": scene.rtol, "model_tol": model_tol, **rows}, datasets


def auto_reasons(scene, ds_auto, mask=False):
    """Why auto solved its inertial points: outside the first-order expansion's trusted range, or estimate above
    model_tol / ESTIMATE_MARGIN (sweep/protocols/stop/model_choice.py; recomputed here from the plan and the file).
    mask=True:
    the (K/M, V) mask of the untrusted points instead."""
    plan = sweep.make_plan(scene)
    G = np.tile(gamma_over_A(scene), scene.K_over_M.size)
    untrusted = (G * (1.0 + plan.k + np.abs(plan.a)) > FIRST_ORDER_TRUST).reshape(scene.shape)
    inertial = ds_auto["model"].values == 1
    if mask:
        return untrusted
    return {"inertial_points": int(inertial.sum()), "untrusted": int((inertial & untrusted).sum()),
            "trusted_estimate_above_tol_over_margin": int((inertial & ~untrusted).sum()),
            "untrusted_points_in_grid": int(untrusted.sum())}


def numerics_vs_reference(ds, ref, rtol, atol=1e-12):
    """The numerical error of the inertial points of a run against the reference: points whose true error exceeds
    rtol |x| + atol, how many of them the status flags (error_above_tol), and the estimate/true ratio."""
    x, err_est = ds["xi_inf"].values, ds["xi_inf_error"].values
    both = np.isfinite(x) & np.isfinite(ref) & (ds["model"].values == 1)
    if not both.any():  # (a --quick grid may have no inertial point)
        return {"inertial_points_compared": 0}
    true = np.abs(x - ref)[both]
    bound = rtol * np.abs(x[both]) + atol
    flagged = ds["status"].values[both] == Status.ERROR_ABOVE_TOL
    miss = true > bound
    use = true > 10 * atol
    ratio = err_est[both][use] / true[use]
    return {"inertial_points_compared": int(both.sum()), "max_true_rel_error": float(np.max(true / np.abs(ref[both]))),
            "max_true_error_over_bound": float(np.max(true / bound)),
            "max_estimate_over_bound": float(np.nanmax(err_est[both] / bound)),
            "points_true_error_above_bound": int(miss.sum()), "of_which_flagged": int((miss & flagged).sum()),
            "points_flagged": int(flagged.sum()),
            "estimate_over_true_min_median_max": [float(ratio.min()), pct(ratio, 50), float(ratio.max())]
            if ratio.size else None}


def pct(x, q):
    return float(np.percentile(x, q)) if x.size else None


def accuracy(ds_auto, ds_qs, ds_ref, model_tol):
    """Part 2: true model error of auto and quasistatic against the inertial reference."""
    ref = ds_ref["xi_inf"].values
    ref_ok = ds_ref["status"].values == Status.OK
    out = {}
    for name, ds in (("auto", ds_auto), ("quasistatic", ds_qs)):
        x = ds["xi_inf"].values
        both = np.isfinite(x) & np.isfinite(ref) & (ref != 0)
        err = np.abs(x[both] / ref[both] - 1.0)
        out[name] = {"compared_points": int(both.sum()), "max_true_error": float(err.max()),
                     "p99_true_error": pct(err, 99), "median_true_error": pct(err, 50),
                     "points_above_model_tol": int(np.count_nonzero(err > model_tol))}
        if name == "auto":
            inertial = ds["model"].values[both] == 1
            for key, sel in (("quasistatic", ~inertial), ("inertial", inertial)):
                out[name][f"max_true_error_on_{key}_points"] = float(err[sel].max()) if sel.any() else None
            out[name]["violations_true_error_above_model_tol"] = out[name].pop("points_above_model_tol")
            worst = np.flatnonzero(both)[int(np.argmax(err))]
            i, j = np.unravel_index(worst, ds["xi_inf"].shape)
            out[name]["worst_point"] = {"K_over_M": float(ds["K_over_M"].values[i]), "V": float(ds["V"].values[j]),
                                        "model": int(ds["model"].values[i, j]),
                                        "model_error": float(ds["model_error"].values[i, j])}
    out["quasistatic"]["points_true_error_above_model_tol"] = out["quasistatic"].pop("points_above_model_tol")
    # true gap / model_error, per kind of auto point: where auto kept the quasi-static model its model_error is the
    # estimate, where it solved with inertia the measured gap (the gap as sweep/protocols/stop/model_choice.py defines
    # it: relative
    # to the quasi-static value, |x_in / x_qs - 1|)
    def gap_ratio(model_flag: int) -> dict:
        sel = (ds_auto["model"].values == model_flag) & np.isfinite(ds_qs["xi_inf"].values) & np.isfinite(ref)
        true = np.abs(ref[sel] / ds_qs["xi_inf"].values[sel] - 1.0)
        est = ds_auto["model_error"].values[sel]
        use = (true >= RATIO_MIN_TRUE_ERROR) & (est > 0)
        ratio = true[use] / est[use]
        return {"points_of_this_model": int(sel.sum()), "points_used": int(use.sum()),
                "min_true_error_used": RATIO_MIN_TRUE_ERROR, "min": float(ratio.min()) if ratio.size else None,
                "median": pct(ratio, 50), "max": float(ratio.max()) if ratio.size else None, "p1": pct(ratio, 1),
                "p99": pct(ratio, 99), "points_outside_0.5_2": int(np.count_nonzero((ratio < 0.5) | (ratio > 2.0)))}

    out["true_over_model_error_on_auto_quasistatic_points"] = gap_ratio(0)
    out["true_over_measured_gap_on_auto_inertial_points"] = gap_ratio(1)
    ref_est = ds_ref["xi_inf_error"].values / np.abs(ref)
    out["reference"] = {"model": "inertial", "rtol": REFERENCE_RTOL, "status": status_counts(ds_ref),
                        "points_not_ok": int((~ref_ok).sum()),
                        "max_estimated_rel_error": float(np.nanmax(ref_est)), "p99_estimated_rel_error":
                        pct(ref_est[np.isfinite(ref_est)], 99)}
    return out


def tol_sweep(scene, ref, tols=MODEL_TOLS, repeats=3):
    """Part 3: model_tol 1e-1 .. 1e-4 on the inertia scene."""
    rows, datasets = [], {}
    for tol in tols:
        sc = with_model(scene, "auto", model_tol=tol)
        wall, walls, ds = best_of(lambda sc=sc: sweep.run_sweep(sc, progress=False), repeats)
        x = ds["xi_inf"].values
        both = np.isfinite(x) & np.isfinite(ref)
        err = np.abs(x[both] / ref[both] - 1.0)
        n_in = int(ds["model"].values.sum())
        rows.append({"model_tol": tol, "wall_s_best_of_3": wall, "wall_s_all": walls,
                     "elapsed_seconds": ds.attrs["elapsed_seconds"], "inertial_points": n_in,
                     "inertial_fraction": n_in / scene.n_points, "max_true_error": float(err.max()),
                     "p99_true_error": pct(err, 99), "violations": int(np.count_nonzero(err > tol)),
                     "status": status_counts(ds)})
        datasets[tol] = ds
        print(f"  model_tol {tol:g}: wall {wall:.3f} s elapsed {ds.attrs['elapsed_seconds']:.3f} s inertial "
              f"{n_in} ({n_in / scene.n_points:.1%}) max true error {err.max():.3g} "
              f"violations {rows[-1]['violations']}", flush=True)
    return rows, datasets


def plot(path, ds_auto, untrusted, model_tol, tol_rows, timing):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13.0, 5.2), dpi=110)
    K, V = ds_auto["K_over_M"].values, ds_auto["V"].values * 1e6
    me = ds_auto["model_error"].values.T
    pos = me[np.isfinite(me) & (me > 0)]
    m = ax.pcolormesh(K, V, np.where(me > 0, me, np.nan), norm=LogNorm(vmin=max(pos.min(), 1e-8), vmax=pos.max()),
                      shading="nearest", cmap="viridis")
    fig.colorbar(m, ax=ax, label="model_error (relative error of xi_inf with the quasi-static model)")
    ax.contour(K, V, me, levels=[model_tol / ESTIMATE_MARGIN, model_tol], colors=["w", "r"], linewidths=[0.8, 1.4])
    kk, vv = np.meshgrid(K, V)
    inertial = ds_auto["model"].values.T == 1
    by_estimate, outside = inertial & ~untrusted.T, inertial & untrusted.T
    ax.plot(kk[by_estimate], vv[by_estimate], "r.", ms=1.5,
            label=f"inertia: 1.5 x estimate > model_tol ({int(by_estimate.sum())} points)")
    ax.plot(kk[outside], vv[outside], "k.", ms=1.5,
            label=f"inertia: outside the estimate's trusted range ({int(outside.sum())})")
    ax.plot([], [], "r-", label=f"model_error = model_tol = {model_tol:g}")
    ax.plot([], [], "w-", label="model_error = model_tol / 1.5")
    ax.set(xscale="log", yscale="log", xlabel="K/M [s$^{-2}$]", ylabel="V [µm/s]",
           title="inertia scene (sample1, D0 = 0.1 µm), model = auto")
    ax.legend(fontsize=7, loc="lower left", framealpha=0.9)
    tols = [r["model_tol"] for r in tol_rows]
    ax2.plot(tols, [r["wall_s_best_of_3"] for r in tol_rows], "o-", label="auto: run_sweep wall")
    ax2.plot(tols, [r["elapsed_seconds"] for r in tol_rows], "s--", label="auto: elapsed_seconds (kernels)")
    ax2.plot(tols, [r["wall_s_best_of_3"] - r["elapsed_seconds"] for r in tol_rows], "^:",
             label="auto: wall - elapsed (Hopf line, inertial where gamma/A > model_tol)")
    for model, style in (("quasistatic", "g:"), ("inertial", "k:")):
        ax2.axhline(timing[model]["wall_s_best_of_3"], color=style[0], ls=":", label=f"{model} (forced): wall")
    for r in tol_rows:
        ax2.annotate(f"{r['inertial_fraction']:.0%} inertial\nmax err {r['max_true_error']:.1e}",
                     (r["model_tol"], r["wall_s_best_of_3"]), fontsize=7, textcoords="offset points", xytext=(4, 6))
    ax2.set(xscale="log", xlabel="model_tol", ylabel="seconds (best of 3)", ylim=(0, None),
            title=f"cost of model_tol (inertia scene, {numba.get_num_threads()} threads)")
    ax2.invert_xaxis()
    ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def coarse(scene, every_k, every_v):
    """Every ``every_k``-th K/M and ``every_v``-th V of a scene (--quick)."""
    return dataclasses.replace(scene, K_over_M=scene.K_over_M[::every_k], V=scene.V[::every_v])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="coarse grids, two model_tols, one timed call (a smoke run)")
    ap.add_argument("--out", type=Path, default=OUT / "models.json", help="the JSON (the PNG beside it, .png)")
    ap.add_argument("--no-png", action="store_true")
    args = ap.parse_args(argv)
    quick = args.quick
    repeats = 1 if quick else 3
    inertia_scene = coarse(INERTIA_SCENE, 10, 10) if quick else INERTIA_SCENE
    model_tols = MODEL_TOLS[::2] if quick else MODEL_TOLS
    t_start = time.perf_counter()
    digest0, load0 = sweep_digest(), loadavg()
    threads = numba.get_num_threads()
    print(f"numba threads: {threads}", flush=True)
    default = coarse(sweep.default_scene(), 20, 10) if quick else sweep.default_scene()
    print("1. cost per model", flush=True)
    timing_default, ds_default = time_models(default, "default", repeats=repeats)
    timing_default["auto_reasons"] = auto_reasons(default, ds_default["auto"])
    # no rtol-1e-9 reference on the default scene (too slow): the forced inertial run at rtol 1e-6 stands in
    # (its own error, < 5e-6 on the inertia scene, is far below model_tol)
    acc_default = accuracy(ds_default["auto"], ds_default["quasistatic"], ds_default["inertial"], 1e-2)
    timing_default["model_error_vs_inertial_rtol_1e-6"] = {
        "auto": acc_default["auto"], "quasistatic": acc_default["quasistatic"],
        "true_over_model_error_on_auto_quasistatic_points": acc_default[
            "true_over_model_error_on_auto_quasistatic_points"]}
    timing_inertia, ds = time_models(inertia_scene, "inertia", repeats=repeats)
    load_after_cost = loadavg()
    print("2. reference (inertial, rtol 1e-9)", flush=True)
    ref_scene = sweep.Scene(protocol="stop", params=INERTIA_PARAMS, K_over_M=inertia_scene.K_over_M,
                            V=inertia_scene.V, rtol=REFERENCE_RTOL, model="inertial")
    t0 = time.perf_counter()
    ds_ref = sweep.run_sweep(ref_scene, progress=False)
    ref_s = time.perf_counter() - t0
    acc = accuracy(ds["auto"], ds["quasistatic"], ds_ref, 1e-2)
    acc["reference"]["wall_s"] = ref_s
    # the forced inertial model at the scene's rtol against the reference (its own numerical error)
    x_in, ref = ds["inertial"]["xi_inf"].values, ds_ref["xi_inf"].values
    both = np.isfinite(x_in) & np.isfinite(ref)
    acc["inertial_rtol_1e-6_vs_reference_max_rel_diff"] = float(np.max(np.abs(x_in[both] / ref[both] - 1.0)))
    acc["numerics_vs_reference"] = {model: numerics_vs_reference(ds[model], ref, inertia_scene.rtol)
                                    for model in ("inertial", "auto")}
    acc["auto_reasons"] = auto_reasons(inertia_scene, ds["auto"])
    print(json.dumps(acc, indent=1), flush=True)
    print("3. model_tol sweep", flush=True)
    tol_rows, _ = tol_sweep(inertia_scene, ref, model_tols, repeats)
    g = gamma_over_A(inertia_scene)
    result = {
        "benchmark": "models" + (" --quick (coarse grids: a check of the script, not a result)" if quick else ""),
        "quick": quick, "date": time.strftime("%Y-%m-%dT%H:%M:%S%z", time.gmtime()), "machine": machine_info(),
        "numba_threads": threads, "sweep_source_digest_start_end": [digest0, sweep_digest()],
        "loadavg_start_end": [load0, loadavg()], "loadavg_after_part1": load_after_cost,
        "settings": {"estimate_margin": ESTIMATE_MARGIN, "first_order_trust": FIRST_ORDER_TRUST,
                     "reference_rtol": REFERENCE_RTOL,
                     "timing": f"best of {repeats} wall (perf_counter) after 1 warm-up",
                     "inertia_scene": "sample1 with D0 = 1e-7 m, K/M logspace(3, 6, 100), V logspace(-7, -3.5, 50)"
                                      + (", every 10th K/M and V" if quick else ""),
                     "default_scene": "sweep.default_scene()" + (", every 20th K/M and 10th V" if quick else ""),
                     "inertia_scene_gamma_over_A": [float(g.min()), float(g.max())]},
        "cost": {"default_scene": timing_default, "inertia_scene": timing_inertia},
        "accuracy_inertia_scene_model_tol_1e-2": acc,
        "model_tol_sweep_inertia_scene": tol_rows,
        "benchmark_wall_s": time.perf_counter() - t_start,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1, default=str))
    if not args.no_png:
        try:
            plot(args.out.with_suffix(".png"), ds["auto"], auto_reasons(inertia_scene, ds["auto"], mask=True), 1e-2,
                 tol_rows, timing_inertia)
        except ImportError:
            print("matplotlib not installed: no PNG")
    print(f"wrote {args.out} ({result['benchmark_wall_s']:.0f} s)")
    print(f"{'scene':9s} {'model':11s} {'wall s':>8s} {'elapsed s':>9s} {'inertial':>8s} {'wall/qs':>7s} {'el/qs':>6s}")
    for label, t in (("default", timing_default), ("inertia", timing_inertia)):
        for model in MODELS:
            r = t[model]
            ratio = t.get(f"{model}_over_quasistatic", {"wall": 1.0, "elapsed": 1.0})
            print(f"{label:9s} {model:11s} {r['wall_s_best_of_3']:8.3f} {r['elapsed_seconds']:9.3f} "
                  f"{r['inertial_fraction']:8.1%} {ratio['wall']:7.2f} {ratio['elapsed']:6.1f}")


if __name__ == "__main__":
    main()
