"""Dataset assembly: flat kernel outputs -> a self-describing CF-1.11 xarray.Dataset (docs/design.md 5).

Reduced quantities (xi, tau, chi) and dimensional ones (slip in m, times in s) never share a name.
"""

from __future__ import annotations

import datetime as _dt
import functools
import sys
from importlib import metadata

import numpy as np
import xarray as xr

from .. import physics
from ..accuracy import ESTIMATE_RTOL, TIGHTER
from ..plan.plan import Plan, line_uses_inertia
from ..protocols.stop.engine import SAMPLED, RawResult
from ..protocols.stop.model_choice import ModelChoice
from ..scene.scene import AXIS_UNITS, Scene
from ..status import MODEL_FLAG, Status, flag_attrs
from .construct import assemble

__all__ = ["build_dataset", "build_driven_dataset", "sampled_variables", "REFERENCES"]

REFERENCES = (
    "T. Baumberger and L. Gauthier, Creeplike relaxation at the interface between rough solids under shear, "
    "J. Phys. I France 6 (1996) 1021-1030, doi:10.1051/jp1:1996113"
)
DIMS = ("K_over_M", "V")


@functools.cache
def versions() -> str:
    """The versions of sweep and its numerical stack, for the file's ``source`` (looked up once per process: the
    package metadata lookups cost ~2.5 ms, an eighth of a 20,000-point sweep's serial time on two threads)."""

    def v(pkg: str) -> str:
        try:
            return metadata.version(pkg)
        except metadata.PackageNotFoundError:
            return "unknown"

    from .._version import __version__

    return (f"sweep {__version__}, numba {v('numba')}, numpy {v('numpy')}, xarray {v('xarray')}, "
            f"python {sys.version.split()[0]}")


def _var(dims, data, units: str, long_name: str, **attrs) -> xr.Variable:
    return xr.Variable(dims, data, {"units": units, "long_name": long_name, **attrs})


AXIS_NAMES = {"K_over_M": "spring stiffness over slider mass K/M", "V": "driving velocity before the stop",
              "A": "direct-effect coefficient A (eq. 1)", "m1": "slope m1 of mu_d at V0 (eq. 6)",
              "m2": "curvature m2 of mu_d (eq. 6)", "D0": "memory length D0"}
"""long_name of each grid axis (Scene.dims)."""


def _on(scene: Scene, names: tuple[str, ...], fn) -> tuple[tuple[str, ...], np.ndarray]:
    """(dims, values) of fn(**parameters) over the grid dims among ``names`` (a quantity of the parameters
    ``names``; parameters that are not axes enter as numbers): in 2-D, chi over K_over_M and mu1 over V."""
    dims = scene.on_dims(names)
    value = fn(**{n: scene.broadcast(n, dims) for n in names})
    return dims, np.broadcast_to(value, tuple(scene.axis(d).size for d in dims)).copy()


def _coords(scene: Scene) -> dict[str, xr.Variable]:
    p = scene.params
    line_model = lambda V, m1, m2, A, D0: line_uses_inertia(  # noqa: E731
        physics.inertia_number(V, D0, p.g) / A, scene.model, scene.model_tol)
    mu1 = lambda V, m1, m2: physics.mu1(V, m1, m2, p.V0)  # noqa: E731
    coords = {d: _var(d, scene.axis(d), AXIS_UNITS[d], AXIS_NAMES[d]) for d in scene.dims}
    coords.update({
        "chi": _var(*_on(scene, ("K_over_M", "D0"), lambda K_over_M, D0: physics.reduced_stiffness(K_over_M, D0,
                                                                                                     p.g)),
                    "1", "reduced stiffness chi = K D0/(M g)"),
        "mu1": _var(*_on(scene, ("V", "m1", "m2"), mu1), "1", "velocity-weakening slope mu1(V) = m1 - 2 m2 ln(V/V0)"),
        "chi_c": _var(*_on(scene, ("V", "m1", "m2", "A", "D0"), lambda V, m1, m2, A, D0: physics.chi_c_inertial(
                          mu1(V, m1, m2), A, physics.inertia_number(V, D0, p.g) * line_model(V, m1, m2, A, D0))),
                      "1", "reduced stiffness on the Hopf line of the model used at this V, mu1 (1 + gamma/A) with "
                      "inertia (NaN: no Hopf line, mu1 <= 0)", comment=_line_model_comment(scene)),
        "chi_c_quasistatic": _var(*_on(scene, ("V", "m1", "m2"), lambda V, m1, m2: physics.chi_c_quasistatic(
                                      mu1(V, m1, m2))), "1",
                                  "reduced stiffness on the Hopf line of the quasi-static model mu1 (paper eq. 3; NaN: "
                                  "no Hopf line)"),
        "gamma": _var(*_on(scene, ("V", "D0"), lambda V, D0: physics.inertia_number(V, D0, p.g)), "1",
                      "inertia number gamma = V^2/(g D0)"),
    })
    if "trajectory" in scene.observables:
        coords["tau"] = _var("tau", scene.tau_samples, "1", "reduced time after the stop tau = V t/D0")
    if "slip_at" in scene.observables:
        coords["t_obs"] = _var("t_obs", np.asarray(scene.t_obs), "s", "time after the stop")
    return coords


def _line_model_comment(scene: Scene) -> str:
    if scene.model == "auto":
        return (f"inertial model where gamma/A > model_tol = {scene.model_tol:g} (inertia shifts the line by gamma/A "
                f"relative), quasi-static elsewhere")
    return f"{scene.model} model"


def _model_variables(scene: Scene, choice: ModelChoice, grid, dims=DIMS) -> dict[str, xr.Variable]:
    """The per-point model flag and, with model="auto", the quasi-static model's estimated error."""
    out = {"model": _var(dims, grid(choice.inertial.astype(np.int8)), "1", "model used for the point", **MODEL_FLAG)}
    if choice.model_error is not None:
        out["model_error"] = _var(
            dims, grid(choice.model_error), "1", "relative error of xi_inf with the quasi-static model",
            comment=f"first-order inertial correction (estimated at rtol {ESTIMATE_RTOL:g}) where the quasi-static "
                    f"model is used (model = 0: 1.5 x model_error <= model_tol = {scene.model_tol:g}); measured "
                    f"between the two models where inertia was solved for; NaN where there is no finite xi_inf")
    return out


def build_dataset(scene: Scene, plan: Plan, raw: RawResult, choice: ModelChoice, history: str = "",
                  sampled: bool = True) -> xr.Dataset:
    """Assemble the Dataset of a stop sweep from the kernel's flat outputs. ``sampled=False`` leaves out the
    variables sampled in time (:func:`sampled_variables`: the trajectory and slip_at), which a journaled run
    writes into its file chunk by chunk instead of holding them whole (sweep/write/netcdf.py)."""
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
        "xi_inf": _var(dims, xi_inf, "1", "relaxed slip after the stop in units of D0, Dx_inf/D0"),
        "slip_inf": _var(dims, D0 * xi_inf, "m", "relaxed slip after the stop Dx_inf"),
        "stress_relaxation": _var(dims, chi * xi_inf, "1", "reduced stress relaxation K Dx_inf/(M g) = chi xi_inf"),
        "stable": _var(dims, stable, "1", "steady sliding at V is linearly stable (model of chi_c)",
                       flag_values=np.array([0, 1], np.int8), flag_meanings="unstable stable"),
        **_model_variables(scene, choice, grid, dims),
        "status": _var(dims, grid(raw.status), "1", "numerical status of the point", **flag_attrs()),
        "steps": _var(dims, grid(raw.steps), "1", "steps taken by the point (fine run of the first pass)"),
        "xi_inertial": _var(dims, xi_in, "1", "slip of a pure inertial stop (constant friction) in units of D0, "
                            "sqrt(gamma/chi) (eqs. 14-15)"),
        "creep_over_inertia": _var(dims, xi_inf / xi_in, "1",
                                   "relaxed creep slip over the pure inertial slip, xi_inf/xi_inertial (>> 1: creep "
                                   "dominates, D0/V >> sqrt(M/K); ~1 or below: inertia matters)"),
    }
    errors = {"xi_inf": grid(raw.xi_inf_err), "slip_inf": D0 * grid(raw.xi_inf_err),
              "stress_relaxation": chi * grid(raw.xi_inf_err)}
    seconds_per_tau = D0 / V
    for name, col, pct in (("t50", 0, 50), ("t90", 1, 90)):
        if name in scene.observables:
            data[name] = _var(dims, grid(raw.tau_at_fraction[:, col]) * seconds_per_tau, "s",
                              f"time after the stop to reach {pct} % of the relaxed slip")
            errors[name] = grid(raw.tau_at_fraction_err[:, col]) * seconds_per_tau
    data.update(_with_errors(data, errors))
    if sampled:
        data.update(sampled_variables(scene, plan.tau_samples.size, dims, *(grid(getattr(raw, name))
                                                                            for name in SAMPLED), D0=D0))
    attrs = _attrs(scene, "Relaxation landscape of the Baumberger-Gauthier spring-block model (stop scene)",
                   "points on unstable steady sliding (stable = 0) are computed and flagged by stable, not by status",
                   history, raw.seconds)
    attrs["plan_hash"] = plan.hash()
    attrs.update({f"plan_{k}": v for k, v in plan.describe().items()})
    attrs["plan_model"] = _describe_models(scene, choice)
    return assemble(data, _coords(scene), attrs)


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
        data["xi"] = _var(traj_dims, xi_at[..., :n_traj], "1", "slip since the stop in units of D0, xi(tau)")
        data["psi"] = _var(traj_dims, np.exp(u_at[..., :n_traj]), "1", "reduced contact age psi(tau) = V phi/D0")
        errors["xi"] = xi_at_err[..., :n_traj]
        errors["psi"] = data["psi"].values * np.expm1(u_at_err[..., :n_traj])
    if "slip_at" in scene.observables:
        data["slip_at"] = _var(dims + ("t_obs",), D0 * xi_at[..., n_traj:], "m", "slip since the stop at time t_obs")
        errors["slip_at"] = D0 * xi_at_err[..., n_traj:]
    return {**data, **_with_errors(data, errors)}


def _with_errors(data: dict[str, xr.Variable], errors: dict[str, np.ndarray]) -> dict[str, xr.Variable]:
    """The ``<name>_error`` variables of ``errors`` (each linked from its variable in ``data``)."""
    out = {}
    for name, err in errors.items():
        var = data[name]
        var.attrs["ancillary_variables"] = f"{name}_error"
        out[f"{name}_error"] = _var(var.dims, err, var.attrs["units"],
                                    f"estimated absolute numerical error of {name} (Richardson pair + tail bound)")
    return out


def _describe_models(scene: Scene, choice: ModelChoice) -> str:
    n_in = int(np.count_nonzero(choice.inertial))
    inertial = (f"inertial at {n_in} point(s): rodas3 (L-stable Rosenbrock, analytic Jacobian) in contact-age time "
                f"on (xi, ln(xi' psi)), handed over to the quasi-static form once inertia is below 0.1 rtol, error "
                f"estimate |x(rtol/{TIGHTER:g}) - x(rtol/{TIGHTER**2:g})| (local tolerances)")
    if scene.model == "auto":
        return (f"auto (model_tol {scene.model_tol:g}): quasi-static at {choice.inertial.size - n_in} point(s), "
                f"{inertial}")
    return f"{scene.model} (forced)" + (f"; {inertial}" if scene.model == "inertial" else "")


def _attrs(scene: Scene, title: str, comment: str, history: str, seconds: float) -> dict[str, object]:
    """Global attributes shared by every protocol's Dataset."""
    return {
        "Conventions": "CF-1.11",
        "title": title,
        "institution": "sweep users",
        "source": versions(),
        "history": f"{_dt.datetime.now(_dt.UTC).isoformat(timespec='seconds')}: {history or 'sweep'}",
        "references": REFERENCES,
        "comment": f"status codes: {', '.join(f'{s.value}={s.name.lower()}' for s in Status)}; {comment}",
        "scene": scene.to_toml(),
        "elapsed_seconds": float(seconds),
    }


def build_driven_dataset(scene: Scene, out: dict[str, np.ndarray], seconds: float, description: dict[str, str],
                         history: str = "") -> xr.Dataset:
    """Assemble the Dataset of a driven sweep from flat outputs of :func:`sweep.integrate.models.driven.simulate_batch`
    (keys regime, status, growth_rate, period, amplitude, cycles, steps, peak_w)."""
    from ..accuracy import RUNAWAY_XI_DOT
    from ..integrate.driven import Regime

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
        "regime": _var(DIMS, grid(out["regime"]), "1", "regime reached from the perturbed steady sliding",
                       **regime_attrs),
        "status": _var(DIMS, grid(out["status"]), "1", "numerical status of the point", **flag_attrs()),
        "stable": _var(DIMS, physics.stable_sliding(chi, mu1, p.A, gamma).astype(np.int8), "1",
                       "steady sliding at V is linearly stable (model used by the point)",
                       flag_values=np.array([0, 1], np.int8), flag_meanings="unstable stable"),
        "model": _var(DIMS, inertial.astype(np.int8), "1", "model used for the point", **MODEL_FLAG),
        "growth_rate_linear": _var(DIMS, root.real, "1",
                                   "reduced growth rate of small oscillations, linear theory Re sigma (per unit tau)"),
        "period_linear": _var(DIMS, period_linear, "1",
                              "reduced period of small oscillations, linear theory 2 pi/Im sigma (tau units)"),
        "steps": _var(DIMS, grid(out["steps"]), "1", "accepted and rejected steps of the point"),
        "cycles": _var(DIMS, grid(out["cycles"]), "1", "oscillation cycles simulated"),
        "peak_slip_velocity": _var(DIMS, np.exp(grid(out["peak_w"])) * scene.V[None, :], "m s-1",
                                   "largest slip velocity met"),
    }
    if "growth_rate" in scene.observables:
        data["growth_rate"] = _var(DIMS, grid(out["growth_rate"]), "1",
                                   "reduced growth rate measured from the simulated envelope (per unit tau)")
    if "period" in scene.observables:
        data["period"] = _var(DIMS, grid(out["period"]), "1", "measured oscillation period (tau units)")
    if "amplitude" in scene.observables:
        data["amplitude"] = _var(DIMS, grid(out["amplitude"]), "1",
                                 "half the peak-to-peak spring stretch tau - xi on the attractor (0: steady sliding)")
    if scene.model == "auto":
        data["model_error"] = _var(DIMS, np.broadcast_to(gamma_v / p.A, shape).copy(), "1",
                                   "relative shift of the Hopf line (and of chi where the linear growth rate changes "
                                   "sign) if the quasi-static model is used: gamma/A",
                                   comment=f"quasi-static where gamma/A <= model_tol = {scene.model_tol:g} (and the "
                                           "run did not break down: regime runaway is run again with inertia)")
    coords = _coords(scene)
    coords["V"].attrs["long_name"] = "driving velocity"
    coords["Omega_c"] = _var("V", physics.Omega_c(scene.V, mu1[0], p.A, p.D0),
                             "s-1", "critical pulsation on the Hopf line (V/D0) sqrt(mu1/A) (NaN: no line)")
    attrs = _attrs(scene, "Stability of steady sliding and stick-slip of the Baumberger-Gauthier spring-block model "
                   "(driven scene)", "regime runaway is status quasistatic_breakdown", history, seconds)
    attrs["runaway_slip_velocity_over_V"] = RUNAWAY_XI_DOT
    attrs.update({f"plan_{k}": v for k, v in description.items()})
    return assemble(data, coords, attrs)
