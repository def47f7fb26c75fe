"""The picture of a history file (sweep.protocols.history): one figure of up to three panels,

- friction at each segment's end (``mu_end``, or the per-segment variable asked for) over the grid's first axis
  (K/M or k; the longest axis where the first has one value), one line per segment;
- where a hold's duration is an axis of the grid (``hold = "t_hold"``), the peak on reslide above the steady
  friction, Delta mu_peak, against log10 of the hold time, one line per value of another axis, each labelled with its
  healing rate beta = d Delta mu_peak / d log10 t_h (least squares over the line);
- where the file holds friction at given times (observable ``mu_t``), mu(t) of up to six points spread over the grid.

The other axes are held at their middle value, which the panel's title names.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import InputError
from .style import caption, label, new_figure, save, thinned

__all__ = ["PER_SEGMENT", "healing_rate", "hold_axes", "plot_history"]

PER_SEGMENT = ("mu_end", "delta_mu_ss", "delta_mu_peak", "delta_mu_relax")
"""The per-segment variables the first panel can draw."""
MAX_LINES = 6
"""Lines per panel at most (segments, curves of an axis, points of mu(t))."""


def _grid_dims(ds: xr.Dataset) -> tuple[str, ...]:
    return tuple(d for d in ds["status"].dims)


def hold_axes(ds: xr.Dataset) -> dict[str, int]:
    """{axis: segment} for each grid axis that gives a hold's duration (the ``duration`` coordinate's comment names
    "segment i -> axis"; a hold is a segment with V_ratio = 0)."""
    comment = str(ds["duration"].attrs.get("comment", "")) if "duration" in ds.coords else ""
    out = {}
    for seg, name in re.findall(r"segment (\d+) -> (\w+)", comment):
        if name in ds.dims and float(ds["V_ratio"].values[int(seg)]) == 0.0:
            out[name] = int(seg)
    return out


def healing_rate(t_hold: np.ndarray, peak: np.ndarray) -> float:
    """beta = d Delta mu_peak / d log10 t_h by least squares over the finite values (NaN with fewer than two)."""
    ok = np.isfinite(peak) & (t_hold > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log10(t_hold[ok]), peak[ok], 1)[0])


def _middle(ds: xr.Dataset, keep: tuple[str, ...]) -> tuple[dict[str, int], str]:
    """Index of the middle value of every grid dim not in ``keep``, and words naming those values."""
    picks = {d: ds.sizes[d] // 2 for d in _grid_dims(ds) if d not in keep}
    words = ", ".join(_value(ds, d, i) for d, i in picks.items() if ds.sizes[d] > 1)
    return picks, words


def _value(ds: xr.Dataset, dim: str, i: int) -> str:
    unit = ds[dim].attrs.get("units", "1")
    return f"{dim} = {float(ds[dim].values[i]):.3g}" + ("" if unit == "1" else f" {unit}")


def _log(values: np.ndarray) -> bool:
    return bool(np.all(values > 0) and values.max() / values.min() > 20)


def _axis_label(ds: xr.Dataset, dim: str) -> str:
    return f"{dim} [{ds[dim].attrs.get('units', '1')}]"


def _draw_segments(ax, ds: xr.Dataset, variable: str) -> None:
    dims = _grid_dims(ds)
    x_dim = dims[0] if ds.sizes[dims[0]] > 1 else max(dims, key=lambda d: ds.sizes[d])
    picks, words = _middle(ds, (x_dim,))
    data = ds[variable].isel(picks)
    x = ds[x_dim].values
    for j in thinned(ds.sizes["segment"], MAX_LINES):
        ratio = float(ds["V_ratio"].values[j])
        what = "hold" if ratio == 0 else (f"V_ratio = {ratio:g}" if np.isfinite(ratio) else "V_ratio from an axis")
        ax.plot(x, data.isel(segment=j).values, marker="o", ms=3, label=f"segment {j} ({what})")
    if _log(x):
        ax.set_xscale("log")
    ax.set_xlabel(_axis_label(ds, x_dim))
    ax.set_ylabel(label(ds, variable))
    ax.set_title(f"{variable} at each segment's end" + (f"\n{words}" if words else ""), fontsize=9)
    ax.legend(fontsize=7)


def _draw_peaks(ax, ds: xr.Dataset, hold: str, segment: int) -> None:
    reslide = segment + 1
    dims = _grid_dims(ds)
    others = [d for d in dims if d != hold and ds.sizes[d] > 1]
    line_dim = others[0] if others else None
    picks, words = _middle(ds, (hold, line_dim) if line_dim else (hold,))
    data = ds["delta_mu_peak"].isel(picks).isel(segment=reslide)
    t = ds[hold].values
    for i in thinned(ds.sizes[line_dim], MAX_LINES) if line_dim else [None]:
        y = (data.isel({line_dim: i}) if line_dim else data).transpose(hold).values
        name = _value(ds, line_dim, i) + ", " if line_dim else ""
        ax.plot(np.log10(t), y, marker="o", ms=3, label=f"{name}β = {healing_rate(t, y):.3g} per decade")
    ax.set_xlabel(f"log10 hold time {hold} [log10 s]")
    ax.set_ylabel("Δμ_peak on reslide [1]")
    ax.set_title(f"peak after the hold of segment {segment} (reslide: segment {reslide})"
                 + (f"\n{words}" if words else ""), fontsize=9)
    ax.legend(fontsize=7)


def _draw_mu_t(ax, ds: xr.Dataset) -> None:
    dims = _grid_dims(ds)
    shape = tuple(ds.sizes[d] for d in dims)
    t = ds["t_obs"].values
    for flat in thinned(int(np.prod(shape)), MAX_LINES):
        index = dict(zip(dims, np.unravel_index(flat, shape)))
        name = ", ".join(_value(ds, d, int(i)) for d, i in index.items() if ds.sizes[d] > 1)
        ax.plot(t, ds["mu_t"].isel(index).values, label=name or "the point")
    if _log(t):
        ax.set_xscale("log")
    ax.set_xlabel("time from the history's start t_obs [s]")
    ax.set_ylabel("friction coefficient μ [1]")
    ax.set_title("μ(t)", fontsize=9)
    ax.legend(fontsize=7)


def plot_history(ds: xr.Dataset, path: str | os.PathLike, variable: str | None = None) -> Path:
    """The history file's picture (module docstring) written to ``path``; ``variable``: the per-segment variable of
    the first panel (default mu_end). Returns the path written."""
    if variable is not None and (variable not in PER_SEGMENT or variable not in ds.data_vars):
        have = [n for n in PER_SEGMENT if n in ds.data_vars]
        raise InputError(f"--variable must be a per-segment variable of the history file, one of {have}; "
                         f"got {variable!r}")
    holds = hold_axes(ds) if "delta_mu_peak" in ds.data_vars else {}
    holds = {h: s for h, s in holds.items() if s + 1 < ds.sizes["segment"]}  # a reslide follows the hold
    panels = 1 + bool(holds) + ("mu_t" in ds.data_vars)
    fig, axes = new_figure("single" if panels == 1 else "pair", panels)
    axes = np.atleast_1d(axes)
    _draw_segments(axes[0], ds, variable or "mu_end")
    k = 1
    if holds:
        hold, segment = next(iter(holds.items()))
        _draw_peaks(axes[k], ds, hold, segment)
        k += 1
    if "mu_t" in ds.data_vars:
        _draw_mu_t(axes[k], ds)
    fig.suptitle(caption(ds, "history scene: friction under a load history"), fontsize=9)
    return save(fig, path)
