"""The public entry points: run a sweep, solve one point."""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from . import protocols
from .analysis.hopf import with_simulated_line
from .errors import InputError, OutputError
from .jitcache import source_digest
from .plan.layout import block_shape
from .plan.plan import make_plan, scene_plan_hash
from .plan.sample import plan_sample
from .run.backends import check_backend, open_backend
from .run.compile_notice import announce_if_cold
from .run.journal import Journal, journal_path
from .run.lock import output_lock
from .run.runner import chunk_ranges, run_chunks
from .run.size import check_fits, estimate_size
from .scene.params import FrictionParams
from .scene.plausibility import PlausibilityWarning, warn_implausible, warn_implausible_params, warn_not_ok
from .scene.scene import Scene
from .write.netcdf import NetCDFRegions, open_dataset
from .write.regions import GridArrays, Regions, RunTotals, lattice_steps
from .write.targets import check_targets, write_failed

__all__ = ["PreparedRun", "check_run_arguments", "prepare_run", "run_sweep", "solve_point"]


def run_sweep(scene: Scene, progress: bool | None = None, history: str = "", output: str | os.PathLike | None = None,
              resume: bool = False, chunk_size: int | None = None, backend: str = "threads",
              workers: int | None = None, scheduler: str | None = None, overwrite: bool = False) -> xr.Dataset:
    """Run ``scene`` and return its Dataset (dims K_over_M, V; see the README's output contract).

    ``progress``: None shows a bar on an interactive terminal for sweeps longer than ~2 s; True/False force it.
    ``history`` is recorded in the file's history attribute (the CLI passes its command line).
    ``output``: also write the Dataset there (netCDF4). An existing file is replaced only with ``overwrite=True``;
    an unwritable folder, too little free space or too little memory for the grid are refused before any work
    (sweep/write/targets.py, sweep/run/size.py). The run journals every finished chunk beside the output
    (``<output>.journal``, sweep/run/journal.py) so that a killed or interrupted run loses nothing: run again with
    ``resume=True`` to compute only the missing chunks (refused if the scene or plan differs; every chunk is checked
    first, a damaged one moved aside and computed again). Without ``resume`` an existing journal is refused, or
    deleted with ``overwrite=True``. A lock (``<output>.lock``) keeps a second run off the same output.
    ``chunk_size``: points per chunk (an integer >= 1; default plan.CHUNK_POINTS of the protocol); part of what a
    resume checks.
    ``backend``: "threads" (this process, numba's threads) or "dask" (dask.distributed: a LocalCluster of
    ``workers`` one-thread processes started for the run, default 2, or the existing cluster at ``scheduler``,
    e.g. "tcp://host:8786"); the results are bitwise the same (sweep/run/backends.py).
    With an output, the variables sampled in time (trajectory, slip_at) go from the journal into the file chunk
    by chunk, never held whole, and the returned Dataset reads them from the file when they are used.
    Errors: :class:`~sweep.errors.InputError` for anything refused before the work, :class:`~sweep.errors.OutputError`
    for a write that failed during it (the journal is then kept for ``resume=True``).
    """
    with prepare_run(scene, output, resume=resume, overwrite=overwrite, chunk_size=chunk_size, backend=backend,
                     workers=workers, scheduler=scheduler) as run:
        if backend == "dask":
            warm_up_kernels(scene, fan_out=True)  # before the fan-out: the workers load them from the cache
        return run.finish(progress, history or "sweep.run_sweep")


def check_run_arguments(output: str | os.PathLike | None = None, resume: bool = False, overwrite: bool = False,
                        chunk_size: int | None = None, backend: str = "threads", workers: int | None = None,
                        scheduler: str | None = None) -> None:
    """InputError naming the argument and its allowed values, for the arguments of :func:`run_sweep` besides the
    scene (the command line's own checks, made here for Python callers too)."""
    if chunk_size is not None and (isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer))
                                   or chunk_size < 1):
        plain = chunk_size.item() if isinstance(chunk_size, np.generic) else chunk_size  # "0", not "np.int64(0)"
        raise InputError(f"chunk_size must be an integer >= 1 (points per chunk), or None for the protocol's "
                         f"default; got {plain!r}")
    for name, value in (("resume", resume), ("overwrite", overwrite)):
        if not isinstance(value, (bool, np.bool_)):
            raise InputError(f"{name} must be True or False, got {value!r}")
    if output is not None and not isinstance(output, (str, os.PathLike)):
        raise InputError(f"output must be a file path (str or pathlib.Path), got {type(output).__name__}")
    if resume and output is None:
        raise InputError("resume=True continues the journal of an output file: give output= as well")
    check_backend(backend, workers, scheduler)


@dataclass
class PreparedRun:
    """A run whose checks are made, its backend up and its journal (if any) open and checked: what
    :func:`prepare_run` yields. :meth:`finish` computes it."""

    scene: Scene
    chunk_size: int
    output: Path | None
    overwrite: bool
    journal: Journal | None
    imap: Callable[..., Iterator[tuple[int, dict[str, np.ndarray]]]]
    """The backend's map over chunks (sweep/run/backends.py: open_backend)."""
    compute_s: float = 0.0
    """Wall seconds of :meth:`finish`'s chunk loop (the computing, the file written as it goes)."""
    totals: RunTotals | None = None
    """What the run counted over its whole grid (flags, plans, seconds), once :meth:`finish` has run."""

    def finish(self, progress: bool | None = None, history: str = "",
               picture: Callable[[xr.Dataset], None] | None = None) -> xr.Dataset:
        """Compute the chunks not yet in the journal, each written into the file as it comes (a helper thread,
        sweep/write/regions.py) while the next ones compute; then the file's attributes, the file closed and renamed
        into place, the journal removed. Returns the Dataset: in memory where the grid fits LATTICE_BYTES (or
        without an output), else the file opened lazily (see :func:`run_sweep`).

        ``picture(ds)`` (the command line's drawing) is called once, with the Dataset in memory: the whole grid, or
        a regular lattice of it where the grid is larger (every n-th point along each dim, attribute ``lattice``).
        The file is whole or absent when this returns or raises."""
        scene, size, journal = self.scene, self.chunk_size, self.journal
        protocol = protocols.get(scene.protocol)
        coords = protocol.coords(scene)
        if scene.simulated_hopf_line:  # asked for: the driven kernel is compiled only then
            coords = dict(with_simulated_line(xr.Dataset(coords=coords), scene.params, scene.model, scene.model_tol,
                                              scene.state_law).coords.variables)
        steps = (None if self.output is None else
                 lattice_steps(scene.shape, protocol.file_bytes_per_point(scene)))
        memory = GridArrays(steps)
        sinks = [memory] if self.output is None else [memory, NetCDFRegions(self.output, block_shape(scene.shape,
                                                                                                      size))]
        regions = Regions(scene, sinks, coords)
        t0 = time.perf_counter()
        try:
            run_chunks(scene, None, size, [regions] if journal is None else [journal, regions], progress, self.imap)
            self.compute_s = time.perf_counter() - t0
            if self.output is not None and self.output.exists() and not self.overwrite:  # someone wrote it meanwhile
                raise OutputError(f"{self.output} appeared during the run; the finished chunks are kept in "
                                  f"{journal.path}: run the same command with --resume --overwrite (resume=True, "
                                  "overwrite=True) to replace it, or move it away and --resume")
            self.totals = regions.totals
            attrs = protocol.attributes(scene, regions.totals, history)
            regions.finish(attrs)
        except OSError as exc:
            regions.abort(exc)
            if journal is None or isinstance(exc, OutputError):  # (an OutputError says what is kept already)
                raise
            raise write_failed(exc, self.output, journal.path, len(journal.done())) from None
        except BaseException as exc:
            regions.abort(exc)
            raise
        if journal is not None:
            journal.remove()
        ds = memory.dataset(attrs)
        if picture is not None:
            picture(ds)
        return ds if memory.whole else open_dataset(self.output, load=False)


@contextmanager
def prepare_run(scene: Scene, output: str | os.PathLike | None = None, resume: bool = False,
                overwrite: bool = False, chunk_size: int | None = None, backend: str = "threads",
                workers: int | None = None, scheduler: str | None = None) -> Iterator[PreparedRun]:
    """Everything :func:`run_sweep` does before computing, in the order that loses nothing and leaves nothing behind
    when something is refused: the arguments, the implausible axes (warned) and the memory the grid needs (from its
    shape, before any plan is made); the output (writable, not an input, replaced only with ``overwrite``, enough
    free space); the plan; the output's lock; the backend (a bad scheduler fails here, in seconds, before any
    journal exists); then the journal, created or, with ``resume``, checked chunk by chunk. The lock is held, and a
    dask cluster started here kept, until the ``with`` block ends. Arguments as in :func:`run_sweep`."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a sweep.Scene (sweep.Scene(protocol=..., params=..., K_over_M=..., V=...), "
                        f"sweep.load_scene(path) or sweep.default_scene()), got {type(scene).__name__}")
    check_run_arguments(output, resume, overwrite, chunk_size, backend, workers, scheduler)
    warn_implausible(scene.K_over_M, scene.V)  # likely unit mistakes, before any work
    warn_implausible_params(scene.params, scene.axes)
    announce_if_cold(scene)  # logs (logger "sweep") that the kernels compile now, on a machine without numba's cache
    size = estimate_size(scene, journaled=output is not None)
    check_fits(scene, size)
    if output is not None:
        output = Path(output)
        check_targets({"data": output}, overwrite=overwrite,
                      need_bytes=max(0, size.disk - _bytes_in(journal_path(output))) if resume else size.disk)
    chunk_size = int(chunk_size or protocols.get(scene.protocol).chunk_size(scene))
    with ExitStack() as stack:
        if output is not None:
            stack.enter_context(output_lock(output))
        imap = stack.enter_context(open_backend(backend, workers, scheduler))  # connect first: fails in seconds
        journal = None
        if output is not None:
            # the sources' digest: a journal of another version of sweep (or of edited sources) may hold chunks whose
            # numbers this version would not give, which the plan's hash alone does not see
            identity = {"scene": scene.to_toml(), "plan_hash": scene_plan_hash(scene), "chunk_size": chunk_size,
                        "n_points": scene.n_points, "sweep_source": source_digest()}
            journal = Journal.open(output, identity, chunk_ranges(scene.shape, chunk_size), resume, overwrite)
        yield PreparedRun(scene, chunk_size, output, overwrite, journal, imap)


def _bytes_in(folder: Path) -> int:
    """Bytes of the files in ``folder`` (0 if there is none)."""
    return sum(p.stat().st_size for p in folder.iterdir() if p.is_file()) if folder.is_dir() else 0


WARM_UP_POINTS = 10_000
"""The warm-up plans a subsample of at most this many points of a larger grid (sweep/plan/sample.py) to find the
kernels its points use."""


def warm_up_kernels(scene: Scene, fan_out: bool = False) -> None:
    """Compile (or load from numba's disk cache) the kernels the scene uses, on one point each of a subsample of its
    grid (its protocol's Protocol.warm_up; ``fan_out``: before a dask fan-out, also those only some points may
    need), and the driven kernel of the simulated Hopf line only where the scene asks for that line."""
    sample, _ = plan_sample(scene, WARM_UP_POINTS)
    protocols.get(scene.protocol).warm_up(sample, make_plan(sample), fan_out)
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
