"""The picture of a fit: data with the fitted model and the residuals, the profile likelihoods, the misfit map."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

__all__ = ["plot_fit", "trend_lines"]

MAX_SETS = 8
"""Data sets drawn in the data panel (the first ones)."""


def _data_panel(ax, res_ax, ds: xr.Dataset) -> None:
    record = '"kind": "records"' in ds.attrs.get("fit_settings", "")  # mu(t) of laboratory records: linear axes
    scale = 1.0 if record else 1e6
    names = list(dict.fromkeys(ds["datum_set"].values.tolist()))[:MAX_SETS]
    trends = dict(zip(ds["record_name"].values.tolist(), trend_lines(ds))) if "record_name" in ds else {}
    for name in names:
        sel = ds["datum_set"].values == name
        t = ds["datum_t"].values[sel]
        x = t if np.all(np.isfinite(t)) else ds["datum_K_over_M"].values[sel]
        order = np.argsort(x)
        line, = ax.plot(x[order], scale * ds["observed"].values[sel][order], "o", ms=3 if not record else 1,
                        alpha=0.6)
        ax.plot(x[order], scale * ds["fitted"].values[sel][order], "-", color=line.get_color(),
                label=f"{name}: {trends[name]}" if trends.get(name) else name)
        res_ax.plot(x[order], ds["residual"].values[sel][order], "o", ms=2 if not record else 1,
                    color=line.get_color())
    ax.set_xscale("linear" if record else "log")
    ax.set_ylabel("friction mu" if record else "slip [um]")
    ax.set_title("data (points) and fit (lines)")
    ax.legend(fontsize=7)
    res_ax.set_xscale("linear" if record else "log")
    res_ax.axhline(0.0, color="k", lw=0.8)
    res_ax.set_xlabel("t [s] (the record's clock)" if record else "t [s] (relaxed slips: K/M [s-2])")
    res_ax.set_ylabel("residual / noise")


def trend_lines(ds: xr.Dataset) -> list[str]:
    """Per record of a record fit (the Dataset's ``record`` dimension): its detrend at the best fit in words,
    'trend 2.0e-05 /s in time (fitted)', or '' where it has none (sweep.fit.result: detrend_slope_*)."""
    out = []
    for i, kind in enumerate(ds["record_detrend"].values.tolist()):
        if kind == "none":
            out.append("")
            continue
        c = float(ds[f"detrend_slope_{kind}"][i])
        out.append(f"trend {c:.3g} /{'s' if kind == 'time' else 'm'} in {kind} (fitted)")
    return out


def _profile_panel(ax, ds: xr.Dataset, name: str) -> None:
    for i in range(min(ds.sizes["sample"], MAX_SETS)):
        v, d = ds[f"{name}_profile"].values[i], ds[f"{name}_profile_misfit"].values[i]
        ok = np.isfinite(v)
        ax.plot(v[ok], d[ok], "o-", ms=3)
    crit = np.atleast_1d(ds[f"{name}_profile_misfit"].attrs["threshold_95"])[0]
    ax.axhline(crit, color="k", ls="--", lw=0.8, label="95 %")
    ax.set_xlabel(f"{name} [{ds[name].attrs['units']}]")
    ax.set_ylabel("misfit increase")
    ax.set_title(f"profile of {name}")


def _landscape_panel(fig, ax, ds: xr.Dataset) -> None:
    if "misfit_landscape" not in ds:  # a fit without a global stage (search "local", sweep.fit)
        ax.set_title("no global stage (search local: least squares from the start)")
        ax.set_axis_off()
        return
    land = ds["misfit_landscape"].isel(sample=0)
    dims = land.dims
    if len(dims) == 1:
        ax.plot(land[dims[0]], land.values)
        ax.set_yscale("log")
        ax.set_xlabel(dims[0])
        return
    if not np.isfinite(land.values).any():  # no grid point solved every datum (a failed fit: fit_status)
        ax.set_title("global stage (first sample): no grid point solved every datum")
        return
    best = np.unravel_index(np.nanargmin(land.values), land.shape)  # the other axes at the best grid point
    sl = land.isel({d: int(best[k]) for k, d in enumerate(dims) if k >= 2})
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.log10(sl.values.T)
    mesh = ax.pcolormesh(sl[dims[0]].values, sl[dims[1]].values, z, shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="log10 misfit")
    name0, name1 = (d.removeprefix("grid_") for d in dims[:2])
    ax.plot(ds[name0].values[0], ds[name1].values[0], "r*", ms=10, label="best fit")
    ax.set_xlabel(name0)
    ax.set_ylabel(name1)
    ax.set_title("global stage (first sample)")
    if bool(ds[dims[0]].attrs.get("units") == "m") or np.all(sl[dims[0]].values > 0) and \
            sl[dims[0]].values.max() / sl[dims[0]].values.min() > 20:
        ax.set_xscale("log")


def plot_fit(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write the fit's PNG: data and fit with residuals, one profile per free parameter, the misfit map."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = ds["parameter"].values.tolist()
    has_profiles = f"{names[0]}_profile" in ds
    ncol = max(2, len(names) if has_profiles else 1)
    fig = plt.figure(figsize=(4.2 * ncol, 10), constrained_layout=True)
    grid = fig.add_gridspec(3, ncol, height_ratios=[2.2, 1.0, 2.2])
    ax = fig.add_subplot(grid[0, : ncol - 1])
    _data_panel(ax, fig.add_subplot(grid[1, : ncol - 1], sharex=ax), ds)
    _landscape_panel(fig, fig.add_subplot(grid[0:2, ncol - 1]), ds)
    if has_profiles:
        for j, name in enumerate(names):
            _profile_panel(fig.add_subplot(grid[2, j]), ds, name)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
