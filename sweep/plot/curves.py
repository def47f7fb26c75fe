"""Curves: a stop observable along one axis of the grid (with the eq. 10 estimate), transients xi(tau) and psi(tau)
(with the eq. 12 early stage and the asymptotes of psi), the Hopf line of a Hopf file, and driven regimes along a
line."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import physics
from .maps import REGIME_COLOURS
from .style import (
    CHI_LABEL,
    KM_LABEL,
    TAU_LABEL,
    V_LABEL,
    file_params,
    flag_names,
    label,
    mark_failed,
    mark_no_hopf_line,
    thinned,
    um_per_s,
)

__all__ = ["along", "draw_curve", "draw_hopf", "draw_hopf_gap", "draw_psi", "draw_regime_curve", "draw_xi",
           "trajectory_points"]

AXIS_LABELS = {"K_over_M": KM_LABEL, "V": V_LABEL, "chi": CHI_LABEL}


def along(ds: xr.Dataset) -> str:
    """The axis a one-line grid runs along ("V" where it has a single K/M, else "K_over_M")."""
    return "V" if ds.sizes["K_over_M"] == 1 else "K_over_M"


def _x(line: xr.Dataset, x: str) -> np.ndarray:
    return line[x].values * (1e6 if x == "V" else 1.0)


def draw_curve(ax, ds: xr.Dataset, variable: str, x: str | None = None, yscale: str = "auto",
               eq10: bool = True) -> None:
    """``variable`` of a one-line stop grid against ``x`` ("K_over_M", "chi" or "V"; default the axis it runs
    along): solid where steady sliding is stable, dashed where it is not (a stop from there is not the paper's
    experiment: the slider would be in stick-slip), with the crude estimate eq. 10 as a broken line where it
    exists (mu1(V) > 0; for xi_inf and the stress relaxation), the V range without a Hopf line marked and failed
    points crossed. ``yscale``: "log", "linear" or "auto" (log where the values span more than a decade)."""
    x = x or along(ds)
    line = ds.squeeze()
    xs = _x(line, x)
    y = np.where(line["status"].values == 0, line[variable].values, np.nan)
    stable = line["stable"].values == 1
    marker = "o" if xs.size < 4 else None  # a line of one to three points would not show
    ax.plot(xs, np.where(stable, y, np.nan), "-", marker=marker, color="C0", lw=1.8,
            label="engine, steady sliding stable")
    if not stable.all():
        # the unstable part reaches its stable neighbours, so the curve has no gap where stability changes
        near = ~stable
        near[1:] |= ~stable[:-1]
        near[:-1] |= ~stable[1:]
        ax.plot(xs, np.where(near, y, np.nan), "--", marker=marker, color="0.45", lw=1.4, zorder=1.9,
                label="engine, steady sliding unstable (stick-slip)")
        _shade(ax, xs, ~stable, "stick-slip: steady sliding unstable")
    if eq10 and variable in ("xi_inf", "stress_relaxation"):
        crude = np.broadcast_to(eq10_estimate(ds), ds["xi_inf"].shape).squeeze()
        crude = crude * (line["chi"].values if variable == "stress_relaxation" else 1.0)
        if np.isfinite(crude).any():
            ax.plot(xs, crude, ls=(0, (6, 3)), marker=marker, color="C1", lw=1.4,
                    label="eq. 10 (crude estimate, where μ$_1$ > 0)")
    if x == "V":
        mark_no_hopf_line(ax, xs, line["mu1"].values, axis="x", over_data=False)
    mark_failed(ax, line, xs, line[variable].values)
    has_values = bool(np.any(np.isfinite(y) & (y > 0)))
    if not has_values:  # e.g. every point without a finite limit: say so instead of an empty log axis
        ax.text(0.5, 0.5, "no finite values (see status)", transform=ax.transAxes, ha="center")
    if yscale == "auto":  # log where the values span more than a decade
        yscale = "log" if has_values and np.nanmax(y) > 10 * np.nanmin(np.where(y > 0, y, np.nan)) else "linear"
    ax.set(xscale="log", yscale=yscale if has_values else "linear", ylabel=label(ds, variable),
           xlabel=AXIS_LABELS[x] + f" at {_fixed(ds, x)}")
    ax.legend(fontsize=7, loc="best")


def eq10_estimate(ds: xr.Dataset) -> np.ndarray:
    """The crude estimate of xi_inf (eq. 10) at every point of a stop grid, (K_over_M, V); NaN where mu1 <= 0."""
    a = file_params(ds)["A"]
    return physics.xi_inf_crude(ds["chi"].values[:, None], a, ds["mu1"].values[None, :])


def _fixed(ds: xr.Dataset, x: str) -> str:
    if x == "V":
        return "K/M = {:.3g} s$^{{-2}}$ (χ = {:.3g})".format(float(ds["K_over_M"][0]), float(ds["chi"][0]))
    return "V = {:g} µm/s".format(float(ds["V"][0]) * 1e6)


def _shade(ax, xs: np.ndarray, where: np.ndarray, text: str) -> None:
    """A hatched band over the runs of ``where`` (edges half-way, in log x, to the neighbouring samples)."""
    lx = np.log(xs)
    edges = np.exp(np.concatenate([[lx[0]], 0.5 * (lx[1:] + lx[:-1]), [lx[-1]]]))
    first = True
    for i in np.flatnonzero(where):
        ax.axvspan(edges[i], edges[i + 1], facecolor="none", edgecolor="0.75", hatch="//", lw=0, zorder=0,
                   label=text if first else None)
        first = False


def trajectory_points(ds: xr.Dataset, most: int = 6) -> list[dict[str, int]]:
    """Up to ``most`` grid points whose transients to draw, spread over the grid (all of them if few)."""
    n_k, n_v = ds.sizes["K_over_M"], ds.sizes["V"]
    flat = np.unique(np.linspace(0, n_k * n_v - 1, min(most, n_k * n_v)).round().astype(int))
    return [{"K_over_M": int(i // n_v), "V": int(i % n_v)} for i in flat]


def _point_label(point: xr.Dataset) -> str:
    return "K/M = {:.3g} s$^{{-2}}$, V = {:.3g} µm/s".format(float(point["K_over_M"]), float(point["V"]) * 1e6)


def _colours(n: int):
    import matplotlib

    return matplotlib.colormaps["viridis"](np.linspace(0.0, 0.85, n))  # no yellow: the curves stay visible


def draw_xi(ax, ds: xr.Dataset, points: list[dict[str, int]], eq12: bool = True, limit: bool = True) -> None:
    """xi(tau) of the ``points`` on log axes, each with the early-stage line eq. 12 (A/chi) ln(1 + chi tau/A)
    (exact as tau -> 0) and its relaxed slip xi_inf (dotted)."""
    tau = ds["tau"].values
    a = file_params(ds)["A"]
    for colour, where in zip(_colours(len(points)), points):
        point = ds.isel(where)
        ax.plot(tau, point["xi"].values, "-", color=colour, lw=1.8, label=_point_label(point))
        if eq12:
            ax.plot(tau, physics.xi_early(tau, float(point["chi"]), a), "--", color=colour, lw=1.0)
        if limit and np.isfinite(float(point["xi_inf"])):
            ax.axhline(float(point["xi_inf"]), color=colour, ls=":", lw=1.0)
    if eq12:
        ax.plot([], [], "--", color="0.3", lw=1.0, label="eq. 12: early stage at ψ ≈ 1")
    if limit:
        ax.plot([], [], ":", color="0.3", lw=1.0, label="relaxed slip ξ$_∞$")
    ax.set(xscale="log", yscale="log", xlabel=TAU_LABEL, ylabel=label(ds, "xi"))
    ax.legend(fontsize=7, loc="lower right")


def draw_psi(ax, ds: xr.Dataset, points: list[dict[str, int]]) -> None:
    """psi(tau) of the ``points`` on log axes with its asymptotes psi = 1 (tau << 1) and psi = tau (tau >> 1)."""
    tau = ds["tau"].values
    for colour, where in zip(_colours(len(points)), points):
        point = ds.isel(where)
        ax.plot(tau, point["psi"].values, "-", color=colour, lw=1.8, label=_point_label(point))
    ax.plot(tau, np.ones_like(tau), "k--", lw=1.0, label="asymptote ψ = 1 (τ ≪ 1)")
    ax.plot(tau, tau, "k-.", lw=1.0, label="asymptote ψ = τ (τ ≫ 1)")
    psi = ds["psi"].values
    top = max(np.nanmax(psi), 1.0) * 2 if np.isfinite(psi).any() else tau[-1]
    ax.set(xscale="log", yscale="log", xlabel=TAU_LABEL, ylabel=label(ds, "psi"), ylim=(0.5, top))
    ax.legend(fontsize=7, loc="upper left")


def draw_hopf(ax, ds: xr.Dataset) -> None:
    """A Hopf file (sweep.locate_hopf): V against K/M_c from the linear theory (eq. 3) and located by simulation
    (markers coloured by the bifurcation type found), the V range without a line marked. Where the file has l1
    (docs/hopf-type.md) the theory line is solid where the bifurcation is direct (l1 < 0), dashed where inverted
    (l1 > 0), dotted where |l1| is within its error, with the Bautin points (diamonds) and the upper edge of the
    bistable band where it was measured."""
    v_um = um_per_s(ds)
    if "bifurcation_l1" in ds:
        _draw_hopf_by_type(ax, ds, v_um)
    else:
        ax.plot(ds["K_over_M_c_linear"].values, v_um, "k-", lw=1.2, label="linear theory (eq. 3)")
    shown = np.zeros(v_um.size, bool)
    shown[thinned(v_um.size)] = True  # at most ~25 markers: more would hide the theory line
    note = "" if shown.all() else f" (markers at {shown.sum()} of {v_um.size} V)"
    for code, name in enumerate(flag_names(ds, "bifurcation")):
        sel = (ds["bifurcation"].values == code) & shown
        if sel.any() and name != "none":
            ax.plot(ds["K_over_M_c"].values[sel], v_um[sel], "o", ms=4.5, mfc="none", color=REGIME_COLOURS[code],
                    label=f"located by simulation: {name}{note}")
    mark_no_hopf_line(ax, v_um, ds["mu1"].values, over_data=False)
    ax.set(xscale="log", yscale="log", xlabel="K/M on the Hopf line [s$^{-2}$]", ylabel=V_LABEL,
           ylim=(v_um.min(), v_um.max()))
    ax.text(0.03, 0.03, "stick-slip at smaller K/M,\nsteady sliding at larger", transform=ax.transAxes, fontsize=8)
    ax.legend(fontsize=7, loc="upper right")


HOPF_TYPE_STYLES = {"supercritical": ("-", "linear theory, direct (l1 < 0)"),
                    "subcritical": ("--", "linear theory, inverted (l1 > 0)"),
                    "degenerate": (":", "linear theory, degenerate (|l1| within its error)")}
"""Line style and legend of the theory line by the type from l1 (draw_hopf)."""


def _draw_hopf_by_type(ax, ds: xr.Dataset, v_um: np.ndarray) -> None:
    """The theory line in runs of one type from l1, switching type at the Bautin points (between samples, a switch
    without one at the later sample), the Bautin points and the bistable band's upper edge."""
    names = flag_names(ds, "bifurcation_l1")
    kinds = [names[c] for c in ds["bifurcation_l1"].values]
    km, vs = list(ds["K_over_M_c_linear"].values), list(v_um)
    if "bautin_V" in ds.attrs:  # the line's vertices include the Bautin points, where the type changes
        km += list(np.atleast_1d(ds.attrs["bautin_K_over_M"]))
        vs += list(np.atleast_1d(ds.attrs["bautin_V"]) * 1e6)
        kinds += ["bautin"] * (len(vs) - len(kinds))
    order = np.argsort(vs)
    km, vs, kinds = np.array(km)[order], np.array(vs)[order], np.array(kinds)[order]
    # segment i joins vertices i and i + 1; it takes the type of its left vertex, or of its right one after a Bautin
    seg = np.where(kinds[:-1] == "bautin", kinds[1:], kinds[:-1])
    labelled = set()
    for i, name in enumerate(seg):
        if name in HOPF_TYPE_STYLES:  # no segment drawn from a V without a line ("none")
            style, text = HOPF_TYPE_STYLES[name]
            ax.plot(km[i:i + 2], vs[i:i + 2], color="k", ls=style, lw=1.3,
                    label=None if name in labelled else text)
            labelled.add(name)
    if vs.size == 1 and kinds[0] in HOPF_TYPE_STYLES:
        ax.plot(km, vs, "k_", ms=8, label=HOPF_TYPE_STYLES[kinds[0]][1])
    if "bautin_V" in ds.attrs:
        v_b = np.atleast_1d(ds.attrs["bautin_V"]) * 1e6
        ax.plot(np.atleast_1d(ds.attrs["bautin_K_over_M"]), v_b, "D", ms=7, color="C3", zorder=4,
                label="Bautin point (l1 = 0): " + ", ".join(
                    f"V = {x:.4g} µm/s, γ/A = {g:.3g}" for x, g in zip(v_b, np.atleast_1d(
                        ds.attrs["bautin_gamma_over_A"]))))
    if "bistable_K_over_M_upper" in ds and np.isfinite(ds["bistable_K_over_M_upper"].values).any():
        ax.plot(ds["bistable_K_over_M_upper"].values, v_um, "^", ms=5, color="C1", zorder=4,
                label="bistable band's upper edge (simulation)")


def draw_hopf_gap(ax, ds: xr.Dataset) -> None:
    """Relative gap between the line located by simulation and the linear theory, against V, each point with the
    bracket of the sign change the search left it in (relative width <= rtol: bars +- rtol/2; the located value is
    the bracket's midpoint, centred on the root estimated from the measured growth rates: docs/physics.md 3b). A gap
    inside the bars is not resolved."""
    v_um = um_per_s(ds)
    with np.errstate(invalid="ignore", divide="ignore"):
        gap = ds["K_over_M_c"].values / ds["K_over_M_c_linear"].values - 1.0
    rtol = float(ds.attrs.get("rtol", np.nan))
    bars = rtol / 2 if np.isfinite(rtol) else None
    ax.errorbar(v_um, gap, yerr=bars, fmt="o", ms=3.5, lw=0.9, capsize=2, color="C0",
                label="simulation / linear theory - 1" + (f" (bars: located bracket ± rtol/2 = {bars:g})"
                                                          if bars else ""))
    ax.axhline(0.0, color="k", lw=0.8, label="linear theory")
    finite = np.isfinite(gap)
    if bars and finite.any():
        reach = float(np.max(np.abs(gap[finite]))) + bars
        ax.set_ylim(-1.15 * reach, 2.0 * reach)  # headroom for the legend above the bars
        if np.all(np.abs(gap[finite]) <= bars * (1 + 1e-9)):
            ax.set_title(f"the theory lies in every bracket: no gap resolved at rtol = {rtol:g}", fontsize=8)
    mark_no_hopf_line(ax, v_um, ds["mu1"].values, axis="x", over_data=False)
    ax.set(xscale="log", xlabel=V_LABEL, ylabel="relative gap of K/M$_c$ [1]")
    ax.legend(fontsize=7, loc="upper left")


def draw_regime_curve(ax, ds: xr.Dataset) -> None:
    """Regimes of a one-line driven grid along its axis (one colour per regime)."""
    x = along(ds)
    line = ds.squeeze()
    xs = _x(line, x)
    names = flag_names(ds, "regime")
    ax.scatter(xs, line["regime"].values, c=[REGIME_COLOURS[r] for r in line["regime"].values], zorder=3)
    if x == "V":
        mark_no_hopf_line(ax, xs, line["mu1"].values, axis="x", over_data=False)
    mark_failed(ax, line, xs, line["regime"].values)
    ax.set(xscale="log", yticks=np.arange(len(names)), yticklabels=names, xlabel=AXIS_LABELS[x] + f" at "
           f"{_fixed(ds, x)}", ylim=(-0.5, len(names) - 0.5))
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)
