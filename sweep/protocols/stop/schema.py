"""The output schema of the stop protocol: the relaxation landscape's variables (xi_inf, the slip and stress relaxation,
stability, the model used, status, steps, their error estimates), the values sampled in time where asked for, and the
plan in the attributes."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import xarray as xr

from ... import physics
from ...accuracy import ESTIMATE_RTOL, TIGHTER
from ...assemble.dataset import DIMS, global_attrs, variable, with_errors
from ...plan.plan import Plan, line_uses_inertia, scene_plan_hash
from ...scene.scene import Scene
from ...status import MODEL_FLAG, flag_attrs
from .engine import SAMPLED, RawResult
from .model_choice import ModelChoice

if TYPE_CHECKING:
    from ...write.regions import RunTotals

__all__ = ["sampled_variables", "stop_attributes", "stop_variables"]


def stop_variables(scene: Scene, plan: Plan, raw: RawResult, choice: ModelChoice) -> dict[str, xr.Variable]:
    """The data variables of a stop sweep over the grid of ``scene`` (a run's chunk: its block of the grid) from the
    kernel's flat outputs in the grid's C order."""
    shape = scene.shape
    dims = scene.dims
    V, A, D0, g = (scene.broadcast(n) for n in ("V", "A", "D0", "g"))
    grid = lambda a: a.reshape(shape + a.shape[1:])  # noqa: E731
    xi_inf = grid(raw.xi_inf)
    chi = plan.chi.reshape(shape)
    gamma = physics.inertia_number(V, D0, g)
    gamma_used = gamma * line_uses_inertia(gamma / A, scene.model, scene.model_tol)
    stable = physics.stable_sliding(chi, plan.mu1.reshape(shape), A, gamma_used).astype(np.int8)
    xi_in = np.asarray(physics.xi_inertial(gamma, chi))
    data = {
        "xi_inf": variable(dims, xi_inf, "1", "relaxed slip after the stop in units of D0, Dx_inf/D0"),
        "slip_inf": variable(dims, D0 * xi_inf, "m", "relaxed slip after the stop Dx_inf"),
        "stress_relaxation": variable(dims, chi * xi_inf, "1", "reduced stress relaxation K Dx_inf/(M g) = chi xi_inf"),
        "stable": variable(dims, stable, "1", "steady sliding at V is linearly stable (model of chi_c)",
                       flag_values=np.array([0, 1], np.int8), flag_meanings="unstable stable"),
        **_model_variables(scene, choice, grid, dims),
        "status": variable(dims, grid(raw.status), "1", "numerical status of the point", **flag_attrs()),
        "steps": variable(dims, grid(raw.steps), "1", "steps taken by the point (fine run of the first pass)"),
        "xi_inertial": variable(dims, xi_in, "1", "slip of a pure inertial stop (constant friction) in units of D0, "
                            "sqrt(gamma/chi) (eqs. 14-15)"),
        "creep_over_inertia": variable(dims, xi_inf / xi_in, "1",
                                   "relaxed creep slip over the pure inertial slip, xi_inf/xi_inertial (>> 1: creep "
                                   "dominates, D0/V >> sqrt(M/K); ~1 or below: inertia matters)"),
    }
    errors = {"xi_inf": grid(raw.xi_inf_err), "slip_inf": D0 * grid(raw.xi_inf_err),
              "stress_relaxation": chi * grid(raw.xi_inf_err)}
    seconds_per_tau = D0 / V
    for name, col, pct in (("t50", 0, 50), ("t90", 1, 90)):
        if name in scene.observables:
            data[name] = variable(dims, grid(raw.tau_at_fraction[:, col]) * seconds_per_tau, "s",
                              f"time after the stop to reach {pct} % of the relaxed slip")
            errors[name] = grid(raw.tau_at_fraction_err[:, col]) * seconds_per_tau
    data.update(with_errors(data, errors))
    data.update(sampled_variables(scene, plan.tau_samples.size, dims, *(grid(getattr(raw, name)) for name in SAMPLED),
                                  D0=D0))
    return data


def stop_attributes(scene: Scene, totals: RunTotals, history: str) -> dict[str, object]:
    """The global attributes of a stop sweep's file from its run's totals (sweep/write/regions.py): the plan as
    described over every chunk, the model counts."""
    attrs = global_attrs(scene, "Relaxation landscape of the Baumberger-Gauthier spring-block model (stop scene)",
                         "points on unstable steady sliding (stable = 0) are computed and flagged by stable, not by "
                         "status", history, totals.seconds)
    attrs["plan_hash"] = scene_plan_hash(scene)
    attrs.update({f"plan_{k}": v for k, v in totals.plan_example.describe(totals.plan).items()})
    models = totals.counts.get("model", {})
    attrs["plan_model"] = _describe_models(scene, models.get(1, 0), sum(models.values()))
    return attrs


def sampled_variables(scene: Scene, n_traj: int, dims: tuple[str, ...], xi_at: np.ndarray, u_at: np.ndarray,
                      xi_at_err: np.ndarray, u_at_err: np.ndarray, D0: np.ndarray | float | None = None
                      ) -> dict[str, xr.Variable]:
    """The variables sampled in time, with their errors, from the kernel's per-point samples (engine.SAMPLED:
    arrays (..., n samples), the ``n_traj`` trajectory times first, then the slip_at times) over the leading
    ``dims`` (the grid, or the points of one chunk). ``D0`` [m]: each point's memory length, broadcastable to the
    leading dims (default: the scene's D0, one number; needed per point where the scene sweeps D0)."""
    D0 = scene.params.D0 if D0 is None else np.expand_dims(D0, -1) if np.ndim(D0) else D0
    data, errors = {}, {}
    if "trajectory" in scene.observables:
        traj_dims = dims + ("tau",)
        data["xi"] = variable(traj_dims, xi_at[..., :n_traj], "1", "slip since the stop in units of D0, xi(tau)")
        data["psi"] = variable(traj_dims, np.exp(u_at[..., :n_traj]), "1", "reduced contact age psi(tau) = V phi/D0")
        errors["xi"] = xi_at_err[..., :n_traj]
        errors["psi"] = data["psi"].values * np.expm1(u_at_err[..., :n_traj])
    if "slip_at" in scene.observables:
        data["slip_at"] = variable(dims + ("t_obs",), D0 * xi_at[..., n_traj:], "m",
                                   "slip since the stop at time t_obs")
        errors["slip_at"] = D0 * xi_at_err[..., n_traj:]
    return {**data, **with_errors(data, errors)}


def _model_variables(scene: Scene, choice: ModelChoice, grid, dims=DIMS) -> dict[str, xr.Variable]:
    """The per-point model flag and, with model="auto", the quasi-static model's estimated error."""
    out = {"model": variable(dims, grid(choice.inertial.astype(np.int8)), "1", "model used for the point",
                             **MODEL_FLAG)}
    if choice.model_error is not None:
        out["model_error"] = variable(
            dims, grid(choice.model_error), "1", "relative error of xi_inf with the quasi-static model",
            comment=f"first-order inertial correction (estimated at rtol {ESTIMATE_RTOL:g}) where the quasi-static "
                    f"model is used (model = 0: 1.5 x model_error <= model_tol = {scene.model_tol:g}); measured "
                    f"between the two models where inertia was solved for; NaN where there is no finite xi_inf")
    return out


def _describe_models(scene: Scene, n_in: int, n_points: int) -> str:
    inertial = (f"inertial at {n_in} point(s): rodas3 (L-stable Rosenbrock, analytic Jacobian) in contact-age time "
                f"on (xi, ln(xi' psi)), handed over to the quasi-static form once inertia is below 0.1 rtol, error "
                f"estimate |x(rtol/{TIGHTER:g}) - x(rtol/{TIGHTER**2:g})| (local tolerances)")
    if scene.model == "auto":
        return (f"auto (model_tol {scene.model_tol:g}): quasi-static at {n_points - n_in} point(s), "
                f"{inertial}")
    return f"{scene.model} (forced)" + (f"; {inertial}" if scene.model == "inertial" else "")
