"""Pictures of sweep files: ``plot_file`` draws the picture that fits the file.

* stop sweep with axes beyond (K/M, V) (A, m1, m2, D0): 2-D slices (sweep/plot/slices.py: small multiples of
  the (K/M, V) map, or the two longest axes);
* stop sweep (``xi_inf``): maps of xi_inf and of the stress relaxation over (K/M, V) with the Hopf line (linear
  theory, and located by simulation where the file has it), the stick-slip side hatched, the V range without a
  Hopf line (mu1(V) <= 0) marked and failed points crossed; curves along the axis of a one-line grid (with eq. 10);
  plus, where the file holds transients (``xi``, ``psi`` over ``tau``), a second picture of xi(tau) and psi(tau);
* driven sweep (``regime``): the regime map and the stick-slip amplitude;
* Hopf file (``K_over_M_c``, sweep.locate_hopf): K/M_c(V) by simulation and by the linear theory, and their gap.

Every picture names its parameters in its title and has the units on its axes (sweep/plot/style.py).
"""

from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

from .. import protocols
from ..errors import InputError
from ..write.read import KINDS, file_kind  # noqa: F401 (re-exported: sweep.plot.files.file_kind)
from .curves import draw_curve, draw_hopf, draw_hopf_gap, draw_psi, draw_regime_curve, draw_xi, trajectory_points
from .maps import draw_map, draw_regime_map
from .slices import extra_dims, plot_slices
from .style import caption, figure_legend, file_params, new_figure, save

__all__ = ["file_kind", "plot_file", "plot_hopf", "plot_landscape", "plot_regimes", "plot_trajectories"]

STOP_VARIABLES = ("xi_inf", "stress_relaxation")


def has_trajectories(ds: xr.Dataset) -> bool:
    """True when a stop file holds transients xi(tau), psi(tau) (observable "trajectory")."""
    return "xi" in ds and "psi" in ds and "tau" in ds.dims


def plot_file(ds: xr.Dataset, path: str | os.PathLike, variable: str | None = None) -> list[Path]:
    """The pictures that fit the file, written to ``path`` (and beside it, where its protocol draws more than one:
    Protocol.draw). ``variable``: map or draw that variable of a sweep file alone. Returns the paths written."""
    kind = file_kind(ds)
    if kind == "hopf":
        check_map_variable(ds, variable)
        return [plot_hopf(ds, path)]
    if kind == "fit":  # sweep.fit draws its own files (a later layer than this module's)
        raise InputError("a fit file is drawn by sweep.fit.plot_fit(ds, path) (or `sweep plot FILE`)")
    return protocols.get(kind).draw(ds, path, variable)


def as_K_over_M(ds: xr.Dataset) -> xr.Dataset:
    """A file over the laboratory's stiffness k [1/m] as one over K/M = k g [s-2] (g of its scene), which the
    pictures' axes and maps speak; any other file as it is."""
    if "k" not in ds.dims:
        return ds
    g = float(file_params(ds).get("g", 9.81))
    km = xr.Variable("k", ds["k"].values * g, {"units": "s-2", "long_name": "spring stiffness over slider mass K/M "
                                                 "(= k g)"})
    return ds.assign_coords(k=km).rename({"k": "K_over_M"})


def check_map_variable(ds: xr.Dataset, variable: str | None) -> None:
    """InputError unless ``variable`` is None or a (K_over_M, V) variable of the file."""
    if variable is not None and (variable not in ds.data_vars or set(ds[variable].dims) != {"K_over_M", "V"}):
        names = [n for n, v in ds.data_vars.items() if set(v.dims) == {"K_over_M", "V"}]
        raise InputError(f"--variable must be a (K_over_M, V) variable of the file, one of {names}; got {variable!r}")


def plot_extra_axes(ds: xr.Dataset, path: Path, variable: str | None) -> list[Path]:
    """A stop sweep with axes beyond (K/M, V): 2-D slices of ``variable`` (default xi_inf; sweep.plot.slices) and,
    where the file holds transients, those of its middle slice along the extra axes."""
    grid = ds["xi_inf"].dims
    if variable is not None and (variable not in ds.data_vars or ds[variable].dims != grid):
        names = [n for n, v in ds.data_vars.items() if v.dims == grid]
        raise InputError(f"--variable must be a {grid} variable of the file, one of {names}; got {variable!r}")
    written = [plot_slices(ds, path, variable or "xi_inf")]
    if has_trajectories(ds):
        middle = ds.isel({d: ds.sizes[d] // 2 for d in extra_dims(ds)})
        if middle.sizes["K_over_M"] * middle.sizes["V"] > 1:
            written.append(plot_trajectories(middle, path.with_name(path.stem + "_trajectories.png")))
    return written


def plot_landscape(ds: xr.Dataset, path: str | os.PathLike, variable: str | None = None, title: str = "stop scene",
                   eq10: bool = True) -> Path:
    """A sweep file's ``variable`` (default: xi_inf and the stress relaxation side by side) as a log-log map over
    (K/M, V) (sweep.plot.maps.draw_map), or as a curve along the axis of a grid with a single K/M or a single V
    (sweep.plot.curves.draw_curve, with the paper's eq. 10 where ``eq10``). ``title``: the scene's words."""
    check_map_variable(ds, variable)
    variables = (variable,) if variable else STOP_VARIABLES
    fig, axes = new_figure("pair" if len(variables) > 1 else "map", len(variables))
    two_d = min(ds.sizes["K_over_M"], ds.sizes["V"]) > 1
    for ax, name in zip(axes if len(variables) > 1 else [axes], variables):
        if two_d:
            draw_map(fig, ax, ds, name)
        else:
            draw_curve(ax, ds, name, eq10=eq10)
    if two_d:
        figure_legend(fig, axes)
    note = "; hatched: steady sliding unstable (stick-slip side)" if two_d else ""
    fig.suptitle(caption(ds, f"{title}{note}"), fontsize=9)
    return save(fig, path)


def plot_regimes(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Driven sweep: the regime reached from perturbed steady sliding and, where the file has it, the stick-slip
    amplitude, over (K/M, V) with the Hopf lines (or along the axis of a one-line grid)."""
    amplitude = "amplitude" in ds
    fig, axes = new_figure("pair" if amplitude else "map", 2 if amplitude else 1)
    ax_regime, ax_amp = (axes[0], axes[1]) if amplitude else (axes, None)
    if min(ds.sizes["K_over_M"], ds.sizes["V"]) > 1:
        draw_regime_map(fig, ax_regime, ds)
        if amplitude:
            draw_map(fig, ax_amp, ds, "amplitude")
        figure_legend(fig, axes)
    else:
        draw_regime_curve(ax_regime, ds)
        if amplitude:
            draw_curve(ax_amp, ds, "amplitude", eq10=False)
    fig.suptitle(caption(ds, "driven scene: regime reached from perturbed steady sliding; stick-slip amplitude "
                             "(blank: steady)"), fontsize=9)
    return save(fig, path)


def plot_hopf(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Hopf file: K/M_c(V) both ways (located by simulation, linear theory eq. 3) and their relative gap."""
    fig, (ax_line, ax_gap) = new_figure("pair", 2)
    draw_hopf(ax_line, ds)
    draw_hopf_gap(ax_gap, ds)
    fig.suptitle(caption(ds, "Hopf line: located by simulation (sign change of the measured growth rate) and by the "
                             "linear theory"), fontsize=9)
    return save(fig, path)


def plot_trajectories(ds: xr.Dataset, path: str | os.PathLike, title: str = "stop scene") -> Path:
    """Stop file with transients: xi(tau) (with eq. 12 and xi_inf) and psi(tau) (with its asymptotes) on log axes
    for up to six points spread over the grid."""
    points = trajectory_points(ds)
    fig, (ax_xi, ax_psi) = new_figure("pair", 2)
    draw_xi(ax_xi, ds, points)
    draw_psi(ax_psi, ds, points)
    fig.suptitle(caption(ds, f"{title}: transients after the stop"), fontsize=9)
    return save(fig, path)
