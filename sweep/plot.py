"""Pictures of sweep files: the relaxation landscape with the Hopf line."""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

__all__ = ["plot_file", "plot_hopf", "plot_landscape", "plot_regimes"]


def plot_hopf(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """The Hopf line K/M_c(V) located by simulation (markers coloured by bifurcation type) over the linear one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7.0, 5.0), dpi=110)
    v_um = ds["V"].values * 1e6
    ax.plot(ds["K_over_M_c_linear"].values, v_um, "k-", lw=1.2, label="linear theory (eq. 3)")
    names = ds["bifurcation"].attrs["flag_meanings"].split()
    for code, name in enumerate(names):
        sel = ds["bifurcation"].values == code
        if sel.any() and name != "none":
            ax.plot(ds["K_over_M_c"].values[sel], v_um[sel], "o", ms=4, label=f"simulation: {name}")
    none = ~np.isfinite(ds["K_over_M_c_linear"].values)
    if none.any():
        ax.axhspan(v_um[none].min(), v_um[none].max(), color="0.9", label="no Hopf line (mu1(V) <= 0)")
    ax.set(xscale="log", yscale="log", xlabel="K/M [s$^{-2}$]", ylabel="V [µm/s]",
           title=f"Hopf line, {ds.attrs.get('model', '')} model; stick-slip at smaller K/M")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def plot_file(ds: xr.Dataset, path: str | os.PathLike, variable: str | None = None) -> Path:
    """The picture that fits the file: the regime map of a driven sweep, else the stop landscape."""
    if "regime" in ds and variable is None:
        return plot_regimes(ds, path)
    return plot_landscape(ds, path, variable=variable or "xi_inf")


def plot_regimes(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Regime map of a driven sweep over (K/M, V) (categorical colours, one per regime) with the quasi-static Hopf
    line; a single K/M or V gives the regime along the other axis."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    names = ds["regime"].attrs["flag_meanings"].split()
    colours = ["#4c72b0", "#dd8452", "#55a868", "#c44e52", "#8c8c8c"][: len(names)]
    fig, ax = plt.subplots(figsize=(7.5, 5.5), dpi=110)
    km, v_um = ds["K_over_M"].values, ds["V"].values * 1e6
    from matplotlib.colors import BoundaryNorm, ListedColormap

    cmap = ListedColormap(colours)
    norm = BoundaryNorm(np.arange(len(names) + 1) - 0.5, len(names))
    if min(ds.sizes["K_over_M"], ds.sizes["V"]) > 1:
        mesh = ax.pcolormesh(km, v_um, ds["regime"].values.T, shading="nearest", cmap=cmap, norm=norm)
        bar = fig.colorbar(mesh, ax=ax, ticks=np.arange(len(names)))
        bar.ax.set_yticklabels(names)
        kc = ds["chi_c"].values * float(ds["K_over_M"][0] / ds["chi"][0])
        ax.plot(kc, v_um, "k--", lw=1.6, label="Hopf line (linear, quasi-static)")
        _simulated_line(ax, ds, v_um, "k")
        ax.set(xscale="log", yscale="log", xlim=(km.min(), km.max()), ylim=(v_um.min(), v_um.max()),
               xlabel="K/M [s$^{-2}$]", ylabel="V [µm/s]")
        ax.legend(loc="lower right", fontsize=8)
    else:
        along = "V" if ds.sizes["K_over_M"] == 1 else "K_over_M"
        line = ds.squeeze()
        x = line[along].values * (1e6 if along == "V" else 1.0)
        ax.scatter(x, line["regime"].values, c=[colours[r] for r in line["regime"].values])
        ax.set(xscale="log", yticks=np.arange(len(names)), yticklabels=names,
               xlabel="V [µm/s]" if along == "V" else "K/M [s$^{-2}$]")
    ax.set_title(_caption(ds).replace("stop scene", "driven scene") + "\nregime reached from perturbed steady sliding",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def plot_landscape(ds: xr.Dataset, path: str | os.PathLike, variable: str = "xi_inf") -> Path:
    """Picture of ``variable`` over the (K/M, V) grid, written to ``path``.

    A 2-D grid gives a log-log map with the quasi-static Hopf line (K/M)_c(V) = g chi_c / D0, the stick-slip
    side (steady sliding unstable) hatched and points with a non-ok status marked by grey crosses. A grid with
    a single K/M or a single V gives a curve along the other axis, dashed where sliding is unstable.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(7.5, 5.5), dpi=110)
    if min(ds.sizes["K_over_M"], ds.sizes["V"]) > 1:
        _draw_map(fig, ax, ds, variable)
        ax.set_title(_caption(ds) + "\nhatched: steady sliding unstable (stick-slip)", fontsize=9)
    else:
        _draw_curve(ax, ds, variable)
        ax.set_title(_caption(ds), fontsize=9)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _label(ds: xr.Dataset, variable: str) -> str:
    return f"{ds[variable].attrs.get('long_name', variable)} [{ds[variable].units}]"


def _draw_map(fig, ax, ds: xr.Dataset, variable: str) -> None:
    km, v_um = ds["K_over_M"].values, ds["V"].values * 1e6
    z = ds[variable].values.T  # rows: V, columns: K/M
    finite = z[np.isfinite(z) & (z > 0)]
    norm = LogNorm(finite.min(), finite.max()) if finite.size and finite.max() > finite.min() else None
    mesh = ax.pcolormesh(km, v_um, np.ma.masked_invalid(z), shading="nearest", cmap="viridis", norm=norm)
    fig.colorbar(mesh, ax=ax, label=_label(ds, variable))
    unstable = ds["stable"].values.T == 0
    if unstable.any():
        ax.contourf(km, v_um, unstable.astype(float), levels=[0.5, 1.5], colors="none", hatches=["//"])
    kc = ds["chi_c"].values * float(ds["K_over_M"][0] / ds["chi"][0])  # chi -> K/M is the factor g/D0
    ax.plot(kc, v_um, "w-", lw=2.2)
    ax.plot(kc, v_um, "r--", lw=1.6, label="Hopf line (linear, quasi-static)")
    _simulated_line(ax, ds, v_um, "r")
    failed = ds["status"].values.T != 0
    if failed.any():
        kk, vv = np.meshgrid(km, v_um)
        ax.plot(kk[failed], vv[failed], "x", color="0.5", ms=3, label="status != ok")
    ax.set(xscale="log", yscale="log", xlim=(km.min(), km.max()), ylim=(v_um.min(), v_um.max()),
           xlabel="K/M [s$^{-2}$]", ylabel="V [µm/s]")


def _simulated_line(ax, ds: xr.Dataset, v_um: np.ndarray, colour: str) -> None:
    """The Hopf line located by simulation (sweep.hopf.with_simulated_line), where the file has it."""
    if "K_over_M_c_simulated" in ds.coords:
        ax.plot(ds["K_over_M_c_simulated"].values, v_um, "o", ms=3, mfc="none", mec=colour,
                label="Hopf line (located by simulation)")


def _draw_curve(ax, ds: xr.Dataset, variable: str) -> None:
    along = "V" if ds.sizes["K_over_M"] == 1 else "K_over_M"
    line = ds.squeeze()
    x = line[along].values * (1e6 if along == "V" else 1.0)
    y = np.where(line["status"].values == 0, line[variable].values, np.nan)
    stable = line["stable"].values == 1
    ax.plot(x, np.where(stable, y, np.nan), "-", color="C0", label="steady sliding stable")
    ax.plot(x, np.where(stable, np.nan, y), "--", color="C0", label="unstable (stick-slip side)")
    fixed = "V = {:g} µm/s".format(float(ds["V"][0]) * 1e6) if along == "K_over_M" else \
        "K/M = {:g} s$^{{-2}}$".format(float(ds["K_over_M"][0]))
    has_values = bool(np.any(np.isfinite(y) & (y > 0)))
    if not has_values:  # e.g. every point without a finite limit: say so instead of an empty log axis
        ax.text(0.5, 0.5, "no finite values (see status)", transform=ax.transAxes, ha="center")
    ax.set(xscale="log", yscale="log" if has_values else "linear", ylabel=_label(ds, variable),
           xlabel=("V [µm/s]" if along == "V" else "K/M [s$^{-2}$]") + f" at {fixed}")


def _caption(ds: xr.Dataset) -> str:
    params = tomllib.loads(ds.attrs["scene"]).get("params", {}) if "scene" in ds.attrs else {}
    shown = ", ".join(f"{k}={params[k]:g}" for k in ("A", "m1", "m2", "D0") if k in params)
    return f"stop scene, quasi-static model; {shown}"
