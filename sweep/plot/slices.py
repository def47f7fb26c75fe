"""Pictures of stop sweeps with more axes than (K/M, V) (Scene.axes: A, m1, m2, D0): 2-D slices.

* Where the (K/M, V) plane is a grid (more than one K/M and more than one V): small multiples of the map of that
  plane (sweep.plot.maps.draw_map, Hopf lines and all), one panel per value of the first extra axis (rows) and of
  the second (columns), at most MAX_PER_AXIS values of each, evenly spread (first, middle, last); further extra
  axes are held at their middle value. Each panel names its values.
* Otherwise (one K/M or one V, e.g. a grid over (A, m1) at one (K/M, V)): the variable over the two longest axes
  of the file as one map (a curve if only one axis has more than one value), the other axes at their middle value.
"""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.colors import LogNorm

from .maps import draw_map
from .style import DPI, caption, figure_legend, label, save

__all__ = ["MAX_PER_AXIS", "extra_dims", "plot_slices"]

MAX_PER_AXIS = 3
"""Values of an extra axis shown as panels."""
GRID = ("K_over_M", "V")


def extra_dims(ds: xr.Dataset, variable: str = "xi_inf") -> tuple[str, ...]:
    """The grid dims of ``variable`` beyond (K_over_M, V) (the scene's extra axes: the paper's or the laboratory's)."""
    from ..scene.scene import EXTRA_AXES, LAB_AXES

    return tuple(d for d in ds[variable].dims if d in EXTRA_AXES + LAB_AXES)


def _picks(n: int) -> np.ndarray:
    return np.unique(np.linspace(0, n - 1, min(n, MAX_PER_AXIS)).round().astype(int))


def _value(ds: xr.Dataset, dim: str, i: int) -> str:
    unit = ds[dim].attrs.get("units", "1")
    return f"{dim} = {float(ds[dim].values[i]):.4g}" + ("" if unit == "1" else f" {unit}")


def _log_axis(values: np.ndarray) -> bool:
    return bool(np.all(values > 0) and values.max() / values.min() > 20)


def plot_slices(ds: xr.Dataset, path: str | os.PathLike, variable: str = "xi_inf") -> Path:
    """``variable`` of a stop sweep with extra axes as 2-D slices (module docstring); returns the path written."""
    extra = extra_dims(ds, variable)
    if min(ds.sizes["K_over_M"], ds.sizes["V"]) > 1:
        return _small_multiples(ds, path, variable, extra)
    return _over_longest_axes(ds, path, variable)


def _small_multiples(ds: xr.Dataset, path, variable: str, extra: tuple[str, ...]) -> Path:
    rows_dim, cols_dim = extra[0], (extra[1] if len(extra) > 1 else None)
    held = {d: ds.sizes[d] // 2 for d in extra[2:]}
    rows = _picks(ds.sizes[rows_dim])
    cols = _picks(ds.sizes[cols_dim]) if cols_dim else np.array([-1])
    fig, axes = plt.subplots(rows.size, cols.size, figsize=(4.6 * cols.size, 3.6 * rows.size + 0.8), dpi=DPI,
                             layout="constrained", squeeze=False)
    for r, i in enumerate(rows):
        for c, j in enumerate(cols):
            sel = {rows_dim: int(i), **({cols_dim: int(j)} if cols_dim else {}), **held}
            ax = axes[r, c]
            draw_map(fig, ax, ds.isel(sel), variable)
            ax.set_title(", ".join(_value(ds, d, k) for d, k in sel.items()), fontsize=8)
    figure_legend(fig, axes[0, 0])
    fixed = "; ".join(_value(ds, d, k) for d, k in held.items())
    fig.suptitle(caption(ds, f"stop scene over {', '.join(('K_over_M', 'V') + extra)}: {variable} maps at "
                             f"{rows_dim}{' x ' + cols_dim if cols_dim else ''} values (panels)"
                             + (f"; {fixed}" if fixed else "")
                             + "; hatched: steady sliding unstable"), fontsize=9)
    return save(fig, path)


def _over_longest_axes(ds: xr.Dataset, path, variable: str) -> Path:
    dims = ds[variable].dims
    longest = sorted((d for d in dims if ds.sizes[d] > 1), key=lambda d: -ds.sizes[d])[:2]
    shown = [d for d in dims if d in longest]  # in the file's order
    held = {d: ds.sizes[d] // 2 for d in dims if d not in shown}
    sl = ds[variable].isel(held)
    fig, ax = plt.subplots(figsize=(7.6, 5.6), dpi=DPI, layout="constrained")
    if len(shown) == 2:
        x, y = ds[shown[0]].values, ds[shown[1]].values
        z = sl.transpose(*shown).values.T
        good = np.isfinite(z) & (z > 0)
        norm = LogNorm(z[good].min(), z[good].max()) if good.any() and z[good].max() > z[good].min() else None
        mesh = ax.pcolormesh(x, y, np.ma.masked_where(~good, z), shading="nearest", norm=norm)
        fig.colorbar(mesh, ax=ax, label=label(ds, variable))
        ax.set_ylabel(label(ds, shown[1]))
        if _log_axis(y):
            ax.set_yscale("log")
    elif len(shown) == 1:
        x = ds[shown[0]].values
        ax.plot(x, sl.values, "o-", ms=3)
        ax.set_ylabel(label(ds, variable))
        if np.all(sl.values > 0):
            ax.set_yscale("log")
    else:
        x = np.array([])
        ax.text(0.5, 0.5, f"{variable} = {float(sl.values):.6g}", ha="center", transform=ax.transAxes)
    if shown:
        ax.set_xlabel(label(ds, shown[0]))
        if _log_axis(x):
            ax.set_xscale("log")
    fixed = "; ".join(_value(ds, d, k) for d, k in held.items())
    fig.suptitle(caption(ds, f"stop scene: {variable} over {' x '.join(shown) or 'one point'}"
                             + (f"; {fixed}" if fixed else "")), fontsize=9)
    return save(fig, path)
