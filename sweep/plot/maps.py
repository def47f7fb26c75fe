"""Maps over the (K/M, V) plane: the relaxation landscape of a stop sweep and the regime map of a driven one, each
with the Hopf line (linear theory, and located by simulation where the file has it). The maps label what they draw;
the caller puts the legend below the panels (sweep.plot.style.figure_legend)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm

from .. import physics
from ..log import LOGGER
from ..scene.scene import EXTRA_AXES
from .blocks import block_edges, block_means, block_size, reduction_note
from .style import (
    KM_LABEL,
    V_LABEL,
    file_params,
    km_per_chi,
    label,
    mark_failed,
    mark_no_hopf_line,
    thinned,
    um_per_s,
)

__all__ = ["draw_map", "draw_regime_map", "hopf_line_dense", "REGIME_COLOURS"]

REGIME_COLOURS = ["#0072b2", "#e69f00", "#009e73", "#cc79a7", "#999999"]
"""Okabe-Ito colours (distinct for colour-blind readers), one per regime code."""
CMAPS = {"xi_inf": "viridis", "stress_relaxation": "cividis", "amplitude": "magma"}


def draw_map(fig, ax, ds: xr.Dataset, variable: str) -> None:
    """``variable`` over (K/M, V), log colour scale, with the Hopf lines, the stick-slip side (steady sliding
    unstable, ``stable`` = 0) hatched, the V range without a Hopf line marked and failed points crossed. A grid with
    more than plot_blocks.MAX_CELLS points along an axis is drawn in blocks of points, which the map's title says
    (sweep/plot/blocks.py)."""
    km, v_um = ds["K_over_M"].values, um_per_s(ds)
    z = ds[variable].values.T  # rows: V, columns: K/M
    finite = z[np.isfinite(z) & (z > 0)]
    # the colour scale spans every point's value, also where the map is drawn in blocks (sweep/plot/blocks.py)
    norm = LogNorm(finite.min(), finite.max()) if finite.size and finite.max() > finite.min() else None
    style = dict(cmap=CMAPS.get(variable, "viridis"), norm=norm)
    s_km, s_v = block_size(km.size), block_size(v_um.size)
    note = reduction_note((km.size, v_um.size), (s_km, s_v))
    if note is None:
        mesh = ax.pcolormesh(km, v_um, np.ma.masked_where(~(np.isfinite(z) & (z > 0)), z), shading="nearest",
                             **style)
    else:
        shown = block_means(z, s_v, s_km)
        mesh = ax.pcolormesh(block_edges(km, s_km), block_edges(v_um, s_v), np.ma.masked_invalid(shown),
                             shading="flat", **style)
        ax.set_title(note, fontsize=7)
        LOGGER.info("map of %s: %s", variable, note)
    fig.colorbar(mesh, ax=ax, label=label(ds, variable))
    _hatch_unstable(ax, ds)
    _hopf_lines(ax, ds, v_um)
    mark_no_hopf_line(ax, v_um, ds["mu1"].values)
    kk, vv = np.meshgrid(km, v_um, indexing="ij")
    mark_failed(ax, ds, kk, vv)
    _frame(ax, km, v_um)


def draw_regime_map(fig, ax, ds: xr.Dataset) -> None:
    """The regime reached by each driven point (categorical colours, one per regime), with the Hopf lines."""
    names = ds["regime"].attrs["flag_meanings"].split()
    km, v_um = ds["K_over_M"].values, um_per_s(ds)
    cmap = ListedColormap(REGIME_COLOURS[: len(names)])
    norm = BoundaryNorm(np.arange(len(names) + 1) - 0.5, len(names))
    mesh = ax.pcolormesh(km, v_um, ds["regime"].values.T, shading="nearest", cmap=cmap, norm=norm)
    bar = fig.colorbar(mesh, ax=ax, ticks=np.arange(len(names)), label="regime")
    bar.ax.set_yticklabels(names)
    _hopf_lines(ax, ds, v_um)
    mark_no_hopf_line(ax, v_um, ds["mu1"].values)
    kk, vv = np.meshgrid(km, v_um, indexing="ij")
    mark_failed(ax, ds, kk, vv)
    _frame(ax, km, v_um)


def hopf_line_dense(ds: xr.Dataset, num: int = 400) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Hopf line dense in V over the file's V range: (V [µm/s], K/M_c of eq. 3 quasi-static [s-2], K/M_c of
    the model the file used [s-2]); NaN where mu1(V) <= 0. The model's line is eq. 3 times the file's own ratio
    chi_c / chi_c_quasistatic (1 + gamma/A where inertia moves it), interpolated in ln V. The parameters are the
    file's, except those of a slice of a sweep over them (a scalar coordinate A, m1, m2 or D0: sweep.plot.slices)."""
    p = {**file_params(ds), **{n: float(ds[n]) for n in EXTRA_AXES if n in ds.coords and ds[n].ndim == 0}}
    v_file = ds["V"].values
    v = np.geomspace(v_file.min(), v_file.max(), num)
    kc = physics.hopf_K_over_M(v, p["A"], p["m1"], p["m2"], p["D0"], p.get("V0", 1e-6), p.get("g", 9.81))
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = ds["chi_c"].values / ds["chi_c_quasistatic"].values
    ratio = np.where(np.isfinite(ratio), ratio, 1.0)
    return v * 1e6, kc, kc * np.interp(np.log(v), np.log(v_file), ratio)


def _hatch_unstable(ax, ds: xr.Dataset) -> None:
    """Hatch the stick-slip side (steady sliding unstable: K/M below the Hopf line of the model used), bounded by
    the line itself, dense in V, not by the cells of the grid (which, with few velocities, would hatch stable
    points)."""
    km = ds["K_over_M"].values
    v_um, _, kc = hopf_line_dense(ds)
    edge = np.clip(np.where(np.isfinite(kc), kc, km.min()), km.min(), km.max())
    inside = edge > km.min()
    if inside.any():
        ax.fill_betweenx(v_um, km.min(), edge, where=inside, facecolor="none", edgecolor="k", hatch="//", lw=0,
                         zorder=2, label="steady sliding unstable (stick-slip side)")


def _hopf_lines(ax, ds: xr.Dataset, v_um: np.ndarray) -> None:
    """The quasi-static Hopf line eq. 3 from the file's parameters (dense in V, so that it runs into the edge of
    the V range without a line), the file's own line where inertia moves it (chi_c = mu1 (1 + gamma/A)), and the
    line located by simulation (sweep.analysis.hopf.with_simulated_line) where the file has it; markers thinned to at
    most
    ~25 on a dense V axis, so that they do not merge into a band hiding the theory."""
    v_dense, kc, _ = hopf_line_dense(ds)
    ax.plot(kc, v_dense, "w-", lw=2.6, zorder=3)  # a halo: the line stays visible on any colour
    ax.plot(kc, v_dense, "r--", lw=1.6, zorder=3, label="Hopf line, linear theory (eq. 3, quasi-static)")
    used, quasistatic = ds["chi_c"].values, ds["chi_c_quasistatic"].values
    shifted = np.isfinite(used) & (np.abs(used - quasistatic) > 1e-3 * np.abs(quasistatic))
    show = thinned(v_um.size)
    if shifted.any():  # inertia moves the line by gamma/A relative where the model used has it
        ax.plot(used * km_per_chi(ds), v_um, ":", color="r", marker="+", lw=1.2, zorder=3, markevery=list(show),
                label="Hopf line with inertia, χ$_c$ = μ$_1$ (1 + γ/A)")
    if "K_over_M_c_simulated" in ds.coords:
        note = "" if show.size == v_um.size else f" (markers at {show.size} of {v_um.size} V)"
        ax.plot(ds["K_over_M_c_simulated"].values[show], v_um[show], "o", ms=3.5, mfc="none", mec="r", zorder=3,
                label="Hopf line located by simulation" + note)


def _frame(ax, km: np.ndarray, v_um: np.ndarray) -> None:
    ax.set(xscale="log", yscale="log", xlim=(km.min(), km.max()), ylim=(v_um.min(), v_um.max()),
           xlabel=KM_LABEL, ylabel=V_LABEL)
