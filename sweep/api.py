"""The public entry points: run a sweep, solve one point."""

from __future__ import annotations

from collections.abc import Sequence

import xarray as xr

from .dataset import build_dataset
from .driven_sweep import run_driven
from .engine import RawResult, execute, mark_error_above_tol
from .hopf import with_simulated_line
from .model_choice import choose_stop_models
from .params import FrictionParams
from .plan import make_plan
from .scene import Scene
from .status import Status

__all__ = ["run_sweep", "solve_point"]


def run_sweep(scene: Scene, progress: bool | None = None, history: str = "") -> xr.Dataset:
    """Run ``scene`` and return its Dataset (dims K_over_M, V; see the README's output contract).

    ``progress``: None shows a bar on an interactive terminal for sweeps longer than ~2 s; True/False force it.
    ``history`` is recorded in the file's history attribute (the CLI passes its command line).
    """
    if scene.protocol == "driven":
        ds = run_driven(scene, progress=progress, history=history or "sweep.run_sweep")
    else:
        plan = make_plan(scene)
        if scene.model == "inertial":  # nothing quasi-static to compute
            raw = RawResult.empty(plan.n_points, 0)
            raw.status[~plan.finite] = Status.NO_FINITE_LIMIT
        else:
            raw = execute(scene, plan, progress=progress)
        choice = choose_stop_models(scene, plan, raw, progress=progress)
        mark_error_above_tol(scene, raw)
        raw.seconds += choice.seconds
        ds = build_dataset(scene, plan, raw, choice, history=history or "sweep.run_sweep")
    return with_simulated_line(ds, scene.params, scene.model, scene.model_tol)


def solve_point(params: FrictionParams, K_over_M: float, V: float, rtol: float = 1e-6,
                observables: Sequence[str] = ("xi_inf", "trajectory", "t50", "t90"),
                trajectory_tau: tuple[float, float, int] = (1e-3, 1e6, 61), t_obs: Sequence[float] = (),
                method: str = "auto", step: float | None = None, precision: str = "float64",
                max_steps: int = 1_000_000, model: str = "auto", model_tol: float = 1e-2) -> xr.Dataset:
    """Solve one (K/M [s-2], V [m s-1]) point through the sweep kernel; returns its 0-d Dataset
    (xi_inf, status, steps, and by default the trajectory xi(tau), psi(tau), t50, t90, each with its
    ``<name>_error`` estimate). Arguments as in :class:`sweep.Scene`."""
    scene = Scene(protocol="stop", params=params, K_over_M=[K_over_M], V=[V], rtol=rtol,
                  observables=tuple(observables), trajectory_tau=trajectory_tau, t_obs=tuple(t_obs), method=method,
                  step=step, precision=precision, max_steps=max_steps, model=model, model_tol=model_tol)
    return run_sweep(scene, progress=False, history="sweep.solve_point").isel(K_over_M=0, V=0)
