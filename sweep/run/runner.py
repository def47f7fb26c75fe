"""Running a scene chunk by chunk: one progress bar for the whole sweep, each finished chunk journaled when the
run writes a file (sweep/run/journal.py, in a helper thread while the next chunks compute: a SIGKILL loses at most the
chunks in flight, computing or finished and not yet handed over, and the journal.PENDING_CHUNKS not yet written;
Ctrl-C only those still computing: side by side, the running ones finish and are journaled first), then the chunks
consolidated into flat per-point arrays.

A chunk is a fixed set of points (engine.chunk_points: the same layout for a given number of points and chunk
size) and every point's numbers depend on that point only, so the consolidated arrays are the same whatever the
chunking, the order in which chunks finish, or how many runs it took.
"""

from __future__ import annotations

import contextlib
import functools
import time
from collections.abc import Callable, Iterable, Iterator

import numpy as np
import xarray as xr

from ..plan.plan import Plan
from ..protocols.stop.engine import SAMPLED, RawResult, chunk_points, mark_error_above_tol, n_samples, run_points
from ..protocols.stop.model_choice import ModelChoice, choose_stop_models
from ..scene.scene import Scene
from ..status import Status
from .concurrent_chunks import as_completed_in_threads, side_by_side
from .journal import Journal
from .progress import Progress

__all__ = ["Interrupted", "chunk_ranges", "chunk_task", "execute", "in_process", "run_chunks", "sampled_blocks",
           "stop_chunk", "stop_outputs", "warm_up"]


class Interrupted(RuntimeError):
    """A journaled run was interrupted (Ctrl-C); the message says where the finished chunks are and how to resume."""


def chunk_ranges(n: int, chunk_size: int | None) -> list[tuple[int, int]]:
    """The chunk layout of ``n`` points (engine.chunk_points): (first point, last point + 1) of each chunk, which the
    journal records and checks every chunk against."""
    return [(int(points.min()), int(points.max()) + 1) for points in chunk_points(n, chunk_size)]


def chunk_task(scene: Scene, plan: Plan, points: np.ndarray, shared: bool = False,
               progress: bool | None = False) -> dict[str, np.ndarray]:
    """Compute one chunk (any backend): per-point arrays plus ``seconds``, the time it took. ``plan``: the chunk's
    share of the scene's plan (Plan.take, made once by the driver for the whole scene: what a dask worker is sent),
    ``points`` its points in the grid; with ``shared``, the whole plan itself, ``points`` the chunk's points in it
    (the threads backend: no copy of the chunk's share, ~0.1 ms a chunk of 4096 points). ``progress``: a bar of the
    chunk's inertial points (stop scene; see :func:`in_process`)."""
    from ..protocols.driven.chunk import driven_chunk

    t0 = time.perf_counter()
    compute = driven_chunk(scene, plan) if plan.protocol == "driven" else stop_chunk(scene, plan, progress)
    arrays = compute(_rows(points, shared))
    arrays["seconds"] = np.array(time.perf_counter() - t0)
    return arrays


def kernel_task(scene: Scene, plan: Plan, points: np.ndarray, shared: bool = False,
                progress: bool | None = False) -> dict[str, np.ndarray]:
    """The stop kernels alone on one chunk (no choice of model, no error marks): :func:`execute`'s task (arguments
    as :func:`chunk_task`'s; no inertial points, so no bar)."""
    t0 = time.perf_counter()
    raw = run_points(scene, plan, _rows(points, shared))
    arrays = {name: value for name, value in vars(raw).items() if isinstance(value, np.ndarray)}
    arrays["seconds"] = np.array(time.perf_counter() - t0)
    return arrays


def _rows(points: np.ndarray, shared: bool) -> np.ndarray:
    """The chunk's rows in its plan: its points themselves in the whole plan (``shared``), as a writable copy (the
    chunk layout's arrays are read-only, and numba compiles a kernel again for a read-only array: ~20 s more on a
    cold cache), else 0..n-1 in the chunk's share."""
    return np.array(points, dtype=np.int64) if shared else np.arange(points.size)


def in_process(scene: Scene, plan: Plan, todo: Iterable[tuple[int, np.ndarray]], task=chunk_task,
               progress: bool | None = False):
    """The threads backend (sweep/run/concurrent_chunks.py): with one numba thread, or a threading layer that is not
    safe to enter from two threads at once, the chunks one after another in this thread (numba's threads inside
    each); else the first chunk so, then the others side by side, one chunk per numba thread (where there are enough
    of them: concurrent_chunks.MIN_CHUNKS_PER_THREAD). Every chunk reads the one plan (``shared``). A lone chunk
    (a small grid is one: plan.ONE_CHUNK_POINTS) gets ``progress`` for its inertial points, which the run's bar,
    counting chunks, would not show until the end."""
    todo = list(todo)
    for n, (i, points) in enumerate(todo):
        yield i, task(scene, plan, points, shared=True, progress=progress if len(todo) == 1 else False)
        workers = side_by_side(len(todo) - n - 1)
        if workers > 1:
            rest = iter(todo[n + 1:])
            yield from as_completed_in_threads(lambda pts: task(scene, plan, pts, shared=True), rest, workers)
            return


def run_chunks(scene: Scene, plan: Plan, chunk_size: int | None, journal: Journal | None,
               progress: bool | None, imap=None) -> tuple[dict[str, np.ndarray], float]:
    """The one chunk loop: every chunk of ``scene`` not yet in ``journal``, computed through ``imap``
    (sweep/run/backends.py; default :func:`in_process`), then all chunks consolidated: (arrays over the plan's points,
    normally the scene's, seconds spent computing them, summed over chunks and over the runs that computed them).
    With a journal the arrays sampled in time (engine.SAMPLED) stay there, never held whole: :func:`sampled_blocks`
    reads them back chunk by chunk."""
    imap = imap or in_process
    n = plan.n_points
    chunks = chunk_points(n, chunk_size or plan.chunk_size)
    done = journal.done() if journal is not None else set()
    flat: dict[str, np.ndarray] = {}
    seconds = [0.0]

    def consolidate(points: np.ndarray, arrays: dict[str, np.ndarray]) -> None:
        seconds[0] += float(arrays.pop("seconds"))
        for name, value in arrays.items():
            if journal is not None and name in SAMPLED:
                continue
            if name not in flat:
                fill = np.nan if value.dtype.kind == "f" else 0
                flat[name] = np.full((n,) + value.shape[1:], fill, dtype=value.dtype)
            flat[name][points] = value

    todo = ((i, points) for i, points in enumerate(chunks) if i not in done)
    # journaled in a helper thread while the next chunks compute; every chunk handed over is on disk when it ends
    writes = journal.background() if journal is not None else contextlib.nullcontext(lambda i, arrays: None)
    with Progress(n, enabled=progress) as bar:
        bar.update(sum(chunks[i].size for i in done))
        try:
            with writes as keep:
                for i, arrays in imap(scene, plan, todo, progress=progress):
                    keep(i, arrays)
                    consolidate(chunks[i], arrays)  # into the flat arrays at once: no second copy of the chunks
                    bar.update(chunks[i].size)
        except KeyboardInterrupt:
            if journal is None:
                raise
            raise Interrupted(f"interrupted: {len(journal.done())} of {len(chunks)} chunks are saved in "
                              f"{journal.path}; run the same command with --resume (run_sweep(..., resume=True)) "
                              f"to compute only the rest") from None
    for i in sorted(done):  # chunks of an earlier run, from the journal
        consolidate(chunks[i], journal.read(i))
    return flat, seconds[0]


def execute(scene: Scene, plan: Plan, indices: np.ndarray | None = None, progress: bool | None = None,
            chunk_size: int | None = None) -> RawResult:
    """The stop kernels alone (no choice of model) over the plan's points ``indices`` (default: all), through the
    one chunk loop in this process; flat outputs in the order of ``indices``, error_above_tol marked."""
    part = plan if indices is None else plan.take(np.asarray(indices))
    flat, seconds = run_chunks(scene, part, chunk_size, None, progress,
                               imap=functools.partial(in_process, task=kernel_task))
    out = RawResult(**flat, seconds=seconds)
    mark_error_above_tol(scene, out)
    return out


def warm_up(scene: Scene, plan: Plan) -> float:
    """Compile the kernels (or load them from numba's on-disk cache) on one point per method of the plan;
    returns the seconds taken."""
    t0 = time.perf_counter()
    firsts = np.array([int(np.argmax(plan.point_method == m)) for m in range(len(plan.point_methods))])
    if scene.model == "auto" and plan.lanes:  # the run's own lanes: those that carry the first-order correction
        run_points(scene, plan.take(firsts), np.arange(firsts.size), correction=np.full(firsts.size, np.nan))
    else:
        execute(scene, plan, firsts, progress=False)
    return time.perf_counter() - t0


def stop_chunk(scene: Scene, plan: Plan, progress: bool | None = False
               ) -> Callable[[np.ndarray], dict[str, np.ndarray]]:
    """compute(points) of the stop protocol: the quasi-static kernels (unless the model is forced inertial), the
    choice of model, the inertial points (with a bar if ``progress``), the error_above_tol marks."""
    n_t = n_samples(scene, plan)

    def compute(points: np.ndarray) -> dict[str, np.ndarray]:
        # the first-order correction, where the lanes carry it (model="auto" only needs it)
        carried = np.full(points.size, np.nan) if scene.model == "auto" else None
        if scene.model == "inertial":
            raw = RawResult.empty(points.size, n_t, 0)
            raw.status[~plan.finite[points]] = Status.NO_FINITE_LIMIT
        else:
            raw = run_points(scene, plan, points, correction=carried)
            mark_error_above_tol(scene, raw)
        choice = choose_stop_models(scene, plan, raw, points, progress=progress, correction=carried)
        mark_error_above_tol(scene, raw)
        arrays = {name: value for name, value in vars(raw).items() if isinstance(value, np.ndarray)}
        arrays["inertial"] = choice.inertial
        if choice.model_error is not None:
            arrays["model_error"] = choice.model_error
        return arrays

    return compute


def sampled_blocks(scene: Scene, n_traj: int, chunk_size: int | None, journal: Journal
                   ) -> Iterator[tuple[int, dict[str, xr.Variable]]]:
    """The variables sampled in time (dataset.sampled_variables; ``n_traj`` trajectory times) of the journaled
    chunks, one chunk at a time in the order of the grid: (first flat point, variables over the chunk's points), for
    io.save(..., blocks=)."""
    from ..assemble.dataset import sampled_variables

    for i, points in enumerate(chunk_points(scene.n_points, chunk_size)):
        order = np.argsort(points)  # a chunk is a consecutive range of points, shuffled (engine.chunk_points)
        arrays = journal.read(i)
        yield int(points[order[0]]), sampled_variables(scene, n_traj, ("point",),
                                                       *(arrays[name][order] for name in SAMPLED),
                                                       D0=scene.at_points("D0", points[order]))


def stop_outputs(flat: dict[str, np.ndarray], seconds: float) -> tuple[RawResult, ModelChoice]:
    """The consolidated arrays of :func:`stop_chunk` as the kernel outputs and the model choice (the arrays sampled
    in time empty where they stayed in the journal)."""
    n = flat["xi_inf"].size
    fields = {name: flat[name] if name in flat else np.empty((n, 0)) for name in RawResult.__dataclass_fields__
              if name in flat or name in SAMPLED}
    raw = RawResult(**fields, seconds=seconds)
    return raw, ModelChoice(flat["inertial"], flat.get("model_error"))
