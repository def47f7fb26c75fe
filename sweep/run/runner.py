"""Running a scene chunk by chunk: one progress bar for the whole sweep, each finished chunk handed to the run's
writers (sweep/write/writer.py): the journal when the run writes a file (sweep/run/journal.py, in a helper thread while
the next chunks compute: a SIGKILL loses at most the chunks in flight, computing or finished and not yet handed over,
and the journal.PENDING_CHUNKS not yet written; Ctrl-C only those still computing: side by side, the running ones
finish and are journaled first), and the per-point arrays of the result.

A chunk is a fixed set of points (:func:`chunk_points`: the same layout for a given number of points and chunk
size) and every point's numbers depend on that point only, so the consolidated arrays are the same whatever the
chunking, the order in which chunks finish, or how many runs it took.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Iterable, Sequence

import numpy as np

from .. import protocols
from ..plan.plan import Plan
from ..scene.scene import Scene
from ..write.writer import Writer
from .concurrent_chunks import as_completed_in_threads, side_by_side
from .progress import Progress

__all__ = ["ORDER_SEED", "Interrupted", "chunk_points", "chunk_ranges", "chunk_task", "in_process", "rows",
           "run_chunks"]

ORDER_SEED = 20261121
"""Seed of the fixed pseudo-random order of the points within a chunk (:func:`chunk_points`)."""


class Interrupted(RuntimeError):
    """A journaled run was interrupted (Ctrl-C); the message says where the finished chunks are and how to resume."""


@functools.lru_cache(maxsize=8)
def chunk_points(n: int, chunk_size: int) -> tuple[np.ndarray, ...]:
    """The points 0..n-1 split into consecutive chunks of at most ``chunk_size``, each in a fixed pseudo-random order:
    the costly points cluster on the grid, and every thread's share of a chunk then mixes cheap and costly ones. A
    chunk covers a contiguous range of the flat grid index, so that its trajectories can be written into the file as
    one block (sweep/write/netcdf.py) and never held whole. Cached (read-only arrays): a run asks twice, for its
    journal's ranges and for its chunks, and the permutations cost ~0.3 ms of the default scene's ~35 ms run."""
    rng = np.random.default_rng(ORDER_SEED)
    bounds = np.array_split(np.arange(n), max(1, math.ceil(n / chunk_size)))
    chunks = tuple(rng.permutation(block) for block in bounds)
    for chunk in chunks:
        chunk.flags.writeable = False
    return chunks


def chunk_ranges(n: int, chunk_size: int) -> list[tuple[int, int]]:
    """The chunk layout of ``n`` points (:func:`chunk_points`): (first point, last point + 1) of each chunk, which the
    journal records and checks every chunk against."""
    return [(int(points.min()), int(points.max()) + 1) for points in chunk_points(n, chunk_size)]


def chunk_task(scene: Scene, plan: Plan, points: np.ndarray, shared: bool = False,
               progress: bool | None = False) -> dict[str, np.ndarray]:
    """Compute one chunk (any backend) with the scene's protocol: per-point arrays plus ``seconds``, the time it took.
    ``plan``: the chunk's share of the scene's plan (Plan.take, made once by the driver for the whole scene: what a
    dask worker is sent), ``points`` its points in the grid; with ``shared``, the whole plan itself, ``points`` the
    chunk's points in it (the threads backend: no copy of the chunk's share, ~0.1 ms a chunk of 4096 points).
    ``progress``: a bar of the chunk's own slow points, where the protocol has them (see :func:`in_process`)."""
    t0 = time.perf_counter()
    compute = protocols.get(scene.protocol).chunk(scene, plan, progress)
    arrays = compute(rows(points, shared))
    arrays["seconds"] = np.array(time.perf_counter() - t0)
    return arrays


def rows(points: np.ndarray, shared: bool) -> np.ndarray:
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


def run_chunks(scene: Scene, plan: Plan, chunk_size: int | None, writers: Sequence[Writer],
               progress: bool | None, imap=None) -> None:
    """The one chunk loop: every chunk of ``scene`` that no writer holds yet (sweep/write/writer.py: the journal of
    an earlier run), computed through ``imap`` (sweep/run/backends.py; default :func:`in_process`) and handed to
    every writer as it finishes; then the chunks held from the earlier run, read back and handed to the others."""
    imap = imap or in_process
    n = plan.n_points
    chunks = chunk_points(n, chunk_size or plan.chunk_size)
    held: dict[int, Writer] = {}
    for writer in writers:
        writer.start(chunks)
        for i in writer.done():
            held.setdefault(i, writer)
    todo = ((i, points) for i, points in enumerate(chunks) if i not in held)
    with Progress(n, enabled=progress) as bar:
        bar.update(sum(chunks[i].size for i in held))
        try:
            for i, arrays in imap(scene, plan, todo, progress=progress):
                for writer in writers:
                    writer.put(i, arrays)
                bar.update(chunks[i].size)
            for i in sorted(held):  # chunks of an earlier run
                arrays = held[i].read(i)
                for writer in writers:
                    if writer is not held[i]:
                        writer.put(i, arrays)
        except BaseException as exc:
            for writer in writers:
                writer.abort(exc)
            hints = [h for w in writers if (h := w.resume_hint(len(chunks))) is not None]
            if isinstance(exc, KeyboardInterrupt) and hints:
                raise Interrupted(hints[0]) from None
            raise
        for writer in writers:
            writer.close()
