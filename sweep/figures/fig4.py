"""Fig. 4 of the paper, sample2 at K/M = 2.8e5 s^-2: (a) the reduced slip xi(tau) at V = 1 and 10 um/s on log axes
with the early-stage line eq. 12, (A/chi) ln(1 + chi tau/A) (creep at constant contact age, psi ~ 1); (b) the
reduced contact age psi(tau) at V = 1 um/s with its asymptotes psi = 1 (tau << 1) and psi = tau (tau >> 1)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from .. import physics
from ..plot.curves import draw_psi, draw_xi
from ..plot.style import caption, new_figure
from ..scene.presets import presets
from ..scene.scene import Scene
from .common import model_summary, row, run

__all__ = ["compute_a", "compute_b", "figure_a", "figure_b", "key_numbers_a", "key_numbers_b"]

TITLE_A = "Fig. 4a: reduced slip after the stop at K/M = 2.8e5 s^-2, V = 1 and 10 µm/s"
TITLE_B = "Fig. 4b: reduced contact age after the stop at K/M = 2.8e5 s^-2, V = 1 µm/s"
PARAMS = presets["sample2"]
K_OVER_M = 2.8e5  # [s-2]
V_A = (1e-6, 1e-5)  # [m s-1]
TAU = (1e-3, 1e3)  # computed and drawn; the paper's axes span 0.01..100
PAPER_TAU = "tau axis 0.01..100"


def compute_a(num: int = 121) -> xr.Dataset:
    """xi(tau), psi(tau) at ``num`` log-spaced tau, V = 1 and 10 um/s."""
    return _transients("fig4a", "Fig. 4a", V_A, num)


def compute_b(num: int = 121) -> xr.Dataset:
    """xi(tau), psi(tau) at ``num`` log-spaced tau, V = 1 um/s (the data of Figs. 2 and 4a)."""
    return _transients("fig4b", "Fig. 4b", V_A[:1], num)


def _transients(name: str, figure: str, v, num: int) -> xr.Dataset:
    scene = Scene(protocol="stop", params=PARAMS, K_over_M=[K_OVER_M], V=v, observables=("xi_inf", "trajectory"),
                  trajectory_tau=(*TAU, num))
    return run(scene, name, figure)


def _points(ds: xr.Dataset) -> list[dict[str, int]]:
    return [{"K_over_M": 0, "V": j} for j in range(ds.sizes["V"])]


def figure_a(ds: xr.Dataset) -> Figure:
    fig, ax = new_figure()
    draw_xi(ax, ds, _points(ds))
    fig.suptitle(caption(ds, TITLE_A), fontsize=8)
    return fig


def figure_b(ds: xr.Dataset) -> Figure:
    fig, ax = new_figure()
    draw_psi(ax, ds, _points(ds))
    fig.suptitle(caption(ds, TITLE_B), fontsize=8)
    return fig


def early_gap(ds: xr.Dataset) -> xr.DataArray:
    """Relative gap xi(tau)/eq. 12 - 1 of each point (K_over_M, V, tau): -> 0 as tau -> 0 (eq. 12 is the
    tangent)."""
    early = physics.xi_early(ds["tau"], ds["chi"], PARAMS.A)
    return ds["xi"] / early - 1.0


def key_numbers_a(ds: xr.Dataset) -> list[str]:
    """Per V: xi at both ends of the tau axis, xi_inf, the slip done by tau = 1, the gap to eq. 12; the inertial
    bound of section 5 at 10 um/s."""
    tau = ds["tau"].values
    gap = early_gap(ds)
    lines = []
    for j in range(ds.sizes["V"]):
        point, v_um = ds.isel(K_over_M=0, V=j), float(ds["V"][j]) * 1e6
        xi = point["xi"].values
        lines += [
            row(f"V = {v_um:g} um/s: xi at tau = {tau[0]:g}, {tau[-1]:g}", f"{xi[0]:.4g}, {xi[-1]:.4g}",
                f"{PAPER_TAU}, xi axis 0.01..1 (log)"),
            row(f"V = {v_um:g} um/s: xi_inf (Dx_inf [um])",
                f"{float(point['xi_inf']):.4f} ({float(point['slip_inf']) * 1e6:.3f})"),
            row(f"V = {v_um:g} um/s: xi(tau = 1)/xi_inf",
                f"{float(np.interp(0.0, np.log(tau), xi)) / float(point['xi_inf']):.3f}",
                "most of the slip in the first stage (tau < 1)"),
            row(f"V = {v_um:g} um/s: xi/eq. 12 - 1 at tau = {tau[0]:g}, 0.1, 1",
                ", ".join(f"{float(gap.isel(K_over_M=0, V=j).interp(tau=t)):.2g}" for t in (tau[0], 0.1, 1.0)),
                "dashed line: the initial stage"),
        ]
    fast = ds.isel(K_over_M=0, V=-1)
    slip_in = float(physics.xi_inertial(fast["gamma"], fast["chi"])) * PARAMS.D0 * 1e6
    lines += [row(f"pure inertial slip at V = {float(fast['V']) * 1e6:g} um/s (eq. 15) [um]", f"{slip_in:.2g}",
                  "~2e-2 um (K/M ~ 3e5 s^-2, V = 10 um/s), << Dx_inf"),
              row("model", model_summary(ds))]
    return lines


def key_numbers_b(ds: xr.Dataset) -> list[str]:
    """psi at the ends of the tau axis against its asymptotes psi = 1 and psi = tau."""
    point = ds.isel(K_over_M=0, V=0)
    tau, psi = point["tau"].values, point["psi"].values
    at = lambda t: float(np.exp(np.interp(np.log(t), np.log(tau), np.log(psi))))  # noqa: E731
    return [
        row(f"psi at tau = {tau[0]:g}, 0.01", f"{psi[0]:.5f}, {at(0.01):.4f}", f"{PAPER_TAU}; asymptote psi = 1"),
        row(f"psi/tau at tau = 100, {tau[-1]:g}", f"{at(100.0) / 100.0:.4f}, {psi[-1] / tau[-1]:.4f}",
            "asymptote psi = tau"),
        row("psi at tau = 1", f"{at(1.0):.3f}", "where the asymptotes cross"),
        row("model", model_summary(ds)),
    ]
