"""The public entry points: run a sweep, solve one point."""

from __future__ import annotations

import os
from collections.abc import Sequence

import xarray as xr

from .dataset import build_dataset, build_driven_dataset
from .driven_sweep import CHUNK as DRIVEN_CHUNK
from .driven_sweep import describe, driven_chunk
from .engine import CHUNK_POINTS
from .hopf import with_simulated_line
from .io import save
from .journal import Journal
from .params import FrictionParams
from .plan import make_plan
from .runner import JOURNAL_FORMAT, run_chunks, stop_chunk, stop_outputs
from .scene import Scene

__all__ = ["run_sweep", "solve_point"]


def run_sweep(scene: Scene, progress: bool | None = None, history: str = "", output: str | os.PathLike | None = None,
              resume: bool = False, chunk_size: int | None = None) -> xr.Dataset:
    """Run ``scene`` and return its Dataset (dims K_over_M, V; see the README's output contract).

    ``progress``: None shows a bar on an interactive terminal for sweeps longer than ~2 s; True/False force it.
    ``history`` is recorded in the file's history attribute (the CLI passes its command line).
    ``output``: also write the Dataset there (netCDF4). The run then journals every finished chunk beside it
    (``<output>.journal``, sweep/journal.py) so that a killed or interrupted run loses nothing: run again with
    ``resume=True`` to compute only the missing chunks (refused if the scene or plan differs). ``chunk_size``:
    points per chunk (default engine.CHUNK_POINTS for stop, driven_sweep.CHUNK for driven scenes); part of
    what a resume checks.
    """
    history = history or "sweep.run_sweep"
    if scene.protocol == "driven":
        compute, plan_hash, size = driven_chunk(scene), "", chunk_size or DRIVEN_CHUNK
    else:
        plan = make_plan(scene)
        compute, plan_hash, size = stop_chunk(scene, plan), plan.hash(), chunk_size or CHUNK_POINTS
    journal = None
    if output is not None:
        identity = {"format": JOURNAL_FORMAT, "scene": scene.to_toml(), "plan_hash": plan_hash, "chunk_size": size,
                    "n_points": scene.n_points}
        journal = Journal.open(output, identity, resume)
    flat, seconds = run_chunks(scene.n_points, compute, size, journal, progress)
    if scene.protocol == "driven":
        ds = build_driven_dataset(scene, flat, seconds, describe(scene), history=history)
    else:
        raw, choice = stop_outputs(flat, seconds)
        ds = build_dataset(scene, plan, raw, choice, history=history)
    ds = with_simulated_line(ds, scene.params, scene.model, scene.model_tol)
    if journal is not None:
        save(ds, output)
        journal.remove()
    return ds


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
