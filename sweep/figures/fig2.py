"""Fig. 2 of the paper: the slip x(t) [um] of the slider after the drive stops, 0-5 s, sample2, V = 1 um/s,
K = 1.1e5 N/m, M = 0.4 kg (K/M = 2.75e5 s^-2), with the tangent of slope V at t = 0 (the slider leaves at V)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from .. import physics
from ..plot.style import caption, new_figure
from ..scene.presets import presets
from ..scene.scene import Scene
from .common import model_summary, row, run

__all__ = ["compute", "figure", "key_numbers"]

TITLE = "Fig. 2: slip after the stop against time, with the tangent of slope V"
PARAMS = presets["sample2"]
K, M = 1.1e5, 0.4  # [N m-1], [kg] (the paper's caption)
V = 1e-6  # [m s-1]
T_END = 5.0  # [s], the paper's time axis
SLIP_AXIS_UM = 0.3  # top of the paper's slip axis [um]


def compute(num: int = 201) -> xr.Dataset:
    """The stop at K/M = 2.75e5 s^-2, V = 1 um/s: slip at ``num`` times 0..5 s, relaxed slip, t50, t90."""
    scene = Scene(protocol="stop", params=PARAMS, K_over_M=[K / M], V=[V], t_obs=tuple(np.linspace(0.0, T_END, num)),
                  observables=("xi_inf", "slip_at", "t50", "t90"))
    ds = run(scene, "fig2", "Fig. 2")
    ds.attrs.update(spring_stiffness_K=f"{K:g} N m-1", slider_mass_M=f"{M:g} kg")
    return ds


def figure(ds: xr.Dataset) -> Figure:
    """Slip [um] against t [s] with the tangent x = V t and the relaxed slip Dx_inf."""
    point = ds.isel(K_over_M=0, V=0)
    t, slip_um = point["t_obs"].values, point["slip_at"].values * 1e6
    v_um = float(point["V"]) * 1e6
    top = max(SLIP_AXIS_UM, 1.1 * float(point["slip_inf"]) * 1e6)
    fig, ax = new_figure()
    ax.plot(t, slip_um, "-", color="C0", lw=2.0, label="engine, preset sample2")
    ax.plot([0.0, top / v_um], [0.0, top], "k--", lw=1.0, label=f"tangent x = V t, slope V = {v_um:g} µm/s")
    ax.axhline(float(point["slip_inf"]) * 1e6, color="0.4", ls=":", lw=1.2,
               label=f"relaxed slip Δx$_∞$ = {float(point['slip_inf']) * 1e6:.3f} µm")
    ax.set(xlim=(0.0, T_END), ylim=(0.0, top), xlabel="time after the stop t [s]",
           ylabel="slip since the stop x [µm]")
    ax.legend(fontsize=8, loc="lower right")
    fig.suptitle(caption(ds, f"{TITLE}; K = 1.1e5 N/m, M = {M:g} kg, V = {v_um:g} µm/s"), fontsize=8)
    return fig


def key_numbers(ds: xr.Dataset) -> list[str]:
    """Relaxed slip, slip at 1 and 5 s, initial slope against V, t50/t90, stability and the inertial bound."""
    point = ds.isel(K_over_M=0, V=0)
    t, slip = point["t_obs"].values, point["slip_at"].values
    first = 1  # the first sample after t = 0
    gamma, chi = float(point["gamma"]), float(point["chi"])
    return [
        row("relaxed slip Dx_inf [um]", f"{float(point['slip_inf']) * 1e6:.4f}",
            f"the trace levels off inside the 0-{SLIP_AXIS_UM:g} um axis (value not legible in the OCR)"),
        row("slip at t = 1 s, 5 s [um]", f"{_at(t, slip, 1.0) * 1e6:.4f}, {_at(t, slip, T_END) * 1e6:.4f}"),
        row(f"mean slip velocity over 0..{t[first]:g} s [um/s]", f"{slip[first] / t[first] * 1e6:.4f}",
            f"starts at V = {V * 1e6:g} um/s (tangent of slope V)"),
        row("t50, t90 (50 %, 90 % of Dx_inf) [s]", f"{float(point['t50']):.3f}, {float(point['t90']):.3f}"),
        row("chi = K D0/(M g), chi_c = mu1(V)", f"{chi:.4g}, {float(point['chi_c']):.4g}",
            expected="steady sliding stable before the stop, chi > chi_c"),
        row("pure inertial slip V sqrt(M/K) (eq. 15) [um]",
            f"{float(physics.xi_inertial(gamma, chi)) * PARAMS.D0 * 1e6:.2g}", "<< Dx_inf (section 5)"),
        row("model", model_summary(ds)),
    ]


def _at(t: np.ndarray, values: np.ndarray, when: float) -> float:
    return float(np.interp(when, t, values))
