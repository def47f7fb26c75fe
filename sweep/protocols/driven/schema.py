"""The output schema of the driven protocol: the regime reached from perturbed steady sliding, its linear theory, the
measured growth rate, period and amplitude where asked for, the model used, status and steps."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ... import physics
from ...accuracy import RUNAWAY_XI_DOT
from ...assemble.dataset import DIMS, global_attrs, grid_coords, variable
from ...integrate.driven import Regime
from ...scene.scene import Scene
from ...status import MODEL_FLAG, flag_attrs

__all__ = ["driven_attributes", "driven_coords", "driven_variables"]


def driven_variables(scene: Scene, out: dict[str, np.ndarray]) -> dict[str, xr.Variable]:
    """The data variables of a driven sweep over the grid of ``scene`` (a run's chunk: its block of the grid) from
    flat outputs of :func:`sweep.integrate.models.driven.simulate_batch` in the grid's C order (keys regime, status,
    growth_rate, period, amplitude, cycles, steps, peak_w, inertial)."""
    shape = scene.shape
    p = scene.params
    grid = lambda a: a.reshape(shape)  # noqa: E731
    chi = physics.reduced_stiffness(scene.K_over_M, p.D0, p.g)[:, None] * np.ones(shape)
    mu1 = physics.mu1(scene.V, p.m1, p.m2, p.V0)[None, :] * np.ones(shape)
    gamma_v = physics.inertia_number(scene.V, p.D0, p.g)
    inertial = grid(out["inertial"])
    gamma = gamma_v[None, :] * inertial  # per point: the model it used
    root = physics.characteristic_roots(chi, mu1, p.A, gamma)[..., 0]  # the leading root (sorted)
    with np.errstate(divide="ignore"):
        period_linear = np.where(root.imag != 0.0, 2.0 * np.pi / np.abs(root.imag), np.nan)
    regime_attrs = {"flag_values": np.array([r.value for r in Regime], np.int8),
                    "flag_meanings": " ".join(r.name.lower() for r in Regime)}
    data = {
        "regime": variable(DIMS, grid(out["regime"]), "1", "regime reached from the perturbed steady sliding",
                       **regime_attrs),
        "status": variable(DIMS, grid(out["status"]), "1", "numerical status of the point", **flag_attrs()),
        "stable": variable(DIMS, physics.stable_sliding(chi, mu1, p.A, gamma).astype(np.int8), "1",
                       "steady sliding at V is linearly stable (model used by the point)",
                       flag_values=np.array([0, 1], np.int8), flag_meanings="unstable stable"),
        "model": variable(DIMS, inertial.astype(np.int8), "1", "model used for the point", **MODEL_FLAG),
        "growth_rate_linear": variable(DIMS, root.real, "1",
                                   "reduced growth rate of small oscillations, linear theory Re sigma (per unit tau)"),
        "period_linear": variable(DIMS, period_linear, "1",
                              "reduced period of small oscillations, linear theory 2 pi/Im sigma (tau units)"),
        "steps": variable(DIMS, grid(out["steps"]), "1", "accepted and rejected steps of the point"),
        "cycles": variable(DIMS, grid(out["cycles"]), "1", "oscillation cycles simulated"),
        "peak_slip_velocity": variable(DIMS, np.exp(grid(out["peak_w"])) * scene.V[None, :], "m s-1",
                                   "largest slip velocity met"),
    }
    if "growth_rate" in scene.observables:
        data["growth_rate"] = variable(DIMS, grid(out["growth_rate"]), "1",
                                   "reduced growth rate measured from the simulated envelope (per unit tau)")
    if "period" in scene.observables:
        data["period"] = variable(DIMS, grid(out["period"]), "1", "measured oscillation period (tau units)")
    if "amplitude" in scene.observables:
        data["amplitude"] = variable(DIMS, grid(out["amplitude"]), "1",
                                 "half the peak-to-peak spring stretch tau - xi on the attractor (0: steady sliding)")
    if scene.model == "auto":
        data["model_error"] = variable(DIMS, np.broadcast_to(gamma_v / p.A, shape).copy(), "1",
                                   "relative shift of the Hopf line (and of chi where the linear growth rate changes "
                                   "sign) if the quasi-static model is used: gamma/A",
                                   comment=f"quasi-static where gamma/A <= model_tol = {scene.model_tol:g} (and the "
                                           "run did not break down: regime runaway is run again with inertia)")
    return data


def driven_coords(scene: Scene) -> dict[str, xr.Variable]:
    """The coordinates of a driven sweep: the grid's, with the critical pulsation along V."""
    p = scene.params
    coords = grid_coords(scene)
    coords["V"].attrs["long_name"] = "driving velocity"
    coords["Omega_c"] = variable("V", physics.Omega_c(scene.V, physics.mu1(scene.V, p.m1, p.m2, p.V0), p.A, p.D0),
                                 "s-1", "critical pulsation on the Hopf line (V/D0) sqrt(mu1/A) (NaN: no line)")
    return coords


def driven_attributes(scene: Scene, seconds: float, description: dict[str, str], history: str = ""
                      ) -> dict[str, object]:
    """The global attributes of a driven sweep's file (``description``: its plan's)."""
    attrs = global_attrs(scene, "Stability of steady sliding and stick-slip of the Baumberger-Gauthier spring-block "
                         "model (driven scene)", "regime runaway is status quasistatic_breakdown", history, seconds)
    attrs["runaway_slip_velocity_over_V"] = RUNAWAY_XI_DOT
    attrs.update({f"plan_{k}": v for k, v in description.items()})
    return attrs
