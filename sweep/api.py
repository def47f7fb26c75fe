"""The public entry points: run a sweep, solve one point."""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence

import numpy as np
import xarray as xr

from .backends import check_backend, open_backend
from .compile_notice import announce_if_cold, inertial_stop_compiled_aside
from .dataset import build_dataset, build_driven_dataset
from .engine import n_samples
from .hopf import with_simulated_line
from .io import open_dataset, save
from .journal import Journal
from .model_choice import warm_up_models
from .params import FrictionParams
from .plan import make_plan
from .plausibility import PlausibilityWarning, warn_implausible, warn_not_ok
from .runner import JOURNAL_FORMAT, chunk_task, run_chunks, sampled_blocks, stop_outputs, warm_up
from .scene import Scene

__all__ = ["run_sweep", "solve_point"]


def run_sweep(scene: Scene, progress: bool | None = None, history: str = "", output: str | os.PathLike | None = None,
              resume: bool = False, chunk_size: int | None = None, backend: str = "threads",
              workers: int | None = None, scheduler: str | None = None) -> xr.Dataset:
    """Run ``scene`` and return its Dataset (dims K_over_M, V; see the README's output contract).

    ``progress``: None shows a bar on an interactive terminal for sweeps longer than ~2 s; True/False force it.
    ``history`` is recorded in the file's history attribute (the CLI passes its command line).
    ``output``: also write the Dataset there (netCDF4). The run then journals every finished chunk beside it
    (``<output>.journal``, sweep/journal.py) so that a killed or interrupted run loses nothing: run again with
    ``resume=True`` to compute only the missing chunks (refused if the scene or plan differs). ``chunk_size``:
    points per chunk (default plan.CHUNK_POINTS of the protocol); part of
    what a resume checks.
    ``backend``: "threads" (this process, numba's threads) or "dask" (dask.distributed: a LocalCluster of
    ``workers`` one-thread processes started for the run, default 2, or the existing cluster at ``scheduler``,
    e.g. "tcp://host:8786"); the results are bitwise the same (sweep/backends.py).
    With an output, the variables sampled in time (trajectory, slip_at) go from the journal into the file chunk
    by chunk, never held whole, and the returned Dataset reads them from the file when they are used.
    """
    history = history or "sweep.run_sweep"
    warn_implausible(scene.K_over_M, scene.V)  # likely unit mistakes, before any work
    announce_if_cold(scene)  # logs (logger "sweep") that the kernels compile now, on a machine without numba's cache
    plan = make_plan(scene)
    size = chunk_size or plan.chunk_size
    check_backend(backend, workers, scheduler)
    journal = None
    if output is not None:
        identity = {"format": JOURNAL_FORMAT, "scene": scene.to_toml(),
                    "plan_hash": plan.hash(), "chunk_size": size, "n_points": scene.n_points}
        journal = Journal.open(output, identity, resume)
    with open_backend(backend, workers, scheduler) as imap:  # connect first: a bad scheduler fails in seconds
        if backend == "dask":
            warm_up_kernels(scene, plan)  # once, before the fan-out: the workers load them from numba's cache
        flat, seconds = run_chunks(scene, plan, size, journal, progress, imap)
    # with a journal the arrays sampled in time stayed there: written into the file chunk by chunk, never held whole
    blocks = None
    if journal is not None and plan.protocol == "stop" and n_samples(scene, plan) > 0:
        blocks = sampled_blocks(scene, plan.tau_samples.size, size, journal)  # (holds no reference to the plan)
    if plan.protocol == "driven":
        ds = build_driven_dataset(scene, flat, seconds, plan.describe(), history=history)
    else:
        ds = build_dataset(scene, plan, *stop_outputs(flat, seconds), history=history, sampled=blocks is None)
    # the Dataset holds what it needs; the plan's and the unused outputs' per-point arrays (~100 bytes per point)
    # go before the netCDF write, whose copies are the peak of a large run's memory
    del plan, flat
    if scene.simulated_hopf_line:  # asked for: the driven kernel is compiled only then
        ds = with_simulated_line(ds, scene.params, scene.model, scene.model_tol, scene.state_law)
    if journal is None:
        return ds
    save(ds, output, blocks=blocks)
    journal.remove()
    return ds if blocks is None else open_dataset(output, load=False)


def warm_up_kernels(scene: Scene, plan) -> None:
    """Compile (or load from numba's disk cache) every kernel the scene uses, on one point each: the stop scene's
    chunks (the inertial stop kernels only where the model policy can use them) or the driven scene's, and the
    driven kernel of the simulated Hopf line only where the scene asks for that line."""
    if plan.protocol == "stop":
        with inertial_stop_compiled_aside(scene):  # a cold cache: two kernel families compile on two cores
            warm_up(scene, plan)
        if scene.model != "quasistatic":
            warm_up_models()
    else:  # one point per variant of the driven kernel the plan uses (quasi-static, inertial)
        inertial = plan.inertial & (plan.G > 0.0)
        firsts = np.unique([int(np.argmax(inertial == used)) for used in (False, True) if (inertial == used).any()])
        chunk_task(scene, plan.take(firsts), firsts)
    if scene.simulated_hopf_line:
        with warnings.catch_warnings():  # the scene's axes were checked; this is one of its velocities
            warnings.simplefilter("ignore", PlausibilityWarning)
            with_simulated_line(xr.Dataset(coords={"V": scene.V[:1]}), scene.params, scene.model, scene.model_tol,
                                scene.state_law)


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
    point = run_sweep(scene, progress=False, history="sweep.solve_point").isel(K_over_M=0, V=0)
    warn_not_ok(point, f"solve_point(K_over_M={float(K_over_M):g}, V={float(V):g})")  # never a silent NaN
    return point
