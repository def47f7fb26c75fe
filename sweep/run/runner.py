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
import time
from collections.abc import Iterable, Sequence

import numpy as np

from .. import protocols
from ..plan.layout import block_slices, chunk_bounds
from ..plan.plan import Plan, make_plan
from ..scene.scene import Scene
from ..write.regions import BLOCK, build_block
from ..write.writer import Writer
from .concurrent_chunks import as_completed_in_threads, side_by_side
from .progress import Progress

__all__ = ["ORDER_SEED", "ChunkLayout", "Interrupted", "chunk_points", "chunk_ranges", "chunk_task", "in_process",
           "rows", "run_chunks"]

ORDER_SEED = 20261121
"""Seed of the fixed pseudo-random order of the points within a chunk (:func:`chunk_points`)."""


class Interrupted(RuntimeError):
    """A journaled run was interrupted (Ctrl-C); the message says where the finished chunks are and how to resume."""


class ChunkLayout(Sequence):
    """The chunks of a grid: ``layout[i]`` the flat points of chunk i, the block i of sweep/plan/layout.py (a
    consecutive range of the flat index that is also a rectangle of the grid) in a fixed pseudo-random order of its
    own (seeded by ORDER_SEED and i): the costly points cluster on the grid, and every thread's share of a chunk then
    mixes cheap and costly ones. Made on demand, so a layout holds its chunks' bounds only (16 bytes a chunk, not 8 a
    point). Read-only arrays."""

    def __init__(self, shape: tuple[int, ...], chunk_size: int) -> None:
        self.bounds = chunk_bounds(shape, chunk_size)

    def __len__(self) -> int:
        return len(self.bounds)

    def __getitem__(self, i):  # an index (the points) or a slice (a list of them)
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        lo, hi = self.bounds[i]
        points = lo + np.random.default_rng([ORDER_SEED, i]).permutation(hi - lo)
        points.flags.writeable = False
        return points

    def size(self, i: int) -> int:
        lo, hi = self.bounds[i]
        return hi - lo


@functools.lru_cache(maxsize=8)
def chunk_points(shape: int | tuple[int, ...], chunk_size: int) -> ChunkLayout:
    """The chunk layout of a grid of ``shape`` (or of ``n`` points in a row) with at most ``chunk_size`` points a
    chunk (:class:`ChunkLayout`)."""
    return ChunkLayout((shape,) if isinstance(shape, (int, np.integer)) else tuple(shape), chunk_size)


def chunk_ranges(shape: int | tuple[int, ...], chunk_size: int) -> list[tuple[int, int]]:
    """The chunk layout of a grid (:func:`chunk_points`): (first point, last point + 1) of each chunk, which the
    journal records and checks every chunk against."""
    return chunk_points(shape, chunk_size).bounds


def chunk_task(scene: Scene, plan: Plan | None, points: np.ndarray, shared: bool = False,
               progress: bool | None = False) -> dict[str, np.ndarray]:
    """Compute one chunk (any backend) with the scene's protocol: per-point arrays plus ``seconds``, the time it took.
    ``plan`` None (a run of a scene): the chunk is a block of the scene's grid (``points``, its flat indices in the
    grid: a consecutive range, shuffled), planned here from its sub-grid (Scene.sub_grid), so no plan of the whole
    grid is ever made or shipped to a worker; its variables are built here too (sweep.write.regions.BLOCK). Else
    ``plan`` is a plan made by the caller (sweep.protocols.stop.chunk
    .execute): its share for this chunk (Plan.take), ``points`` the chunk's points; with ``shared``, the plan itself,
    ``points`` the chunk's rows in it (no copy of the chunk's share). ``progress``: a bar of the chunk's own slow
    points, where the protocol has them (see :func:`in_process`)."""
    t0 = time.perf_counter()
    protocol = protocols.get(scene.protocol)
    if plan is None:
        lo = int(points.min())
        sub = scene.sub_grid(block_slices(scene.shape, lo, lo + points.size))
        block_plan = make_plan(sub)
        arrays = protocol.chunk(sub, block_plan, progress)(points - lo)
        arrays[BLOCK] = build_block(scene, points, arrays, block_plan, sub)  # here, side by side: not in the writer
    else:
        arrays = protocol.chunk(scene, plan, progress)(rows(points, shared))
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
    todo = todo if isinstance(todo, Sequence) else list(todo)
    for n in range(len(todo)):
        i, points = todo[n]
        yield i, task(scene, plan, points, shared=True, progress=progress if len(todo) == 1 else False)
        workers = side_by_side(len(todo) - n - 1)
        if workers > 1:
            rest = (todo[j] for j in range(n + 1, len(todo)))
            yield from as_completed_in_threads(lambda pts: task(scene, plan, pts, shared=True), rest, workers)
            return


def run_chunks(scene: Scene, plan: Plan | None, chunk_size: int | None, writers: Sequence[Writer],
               progress: bool | None, imap=None) -> None:
    """The one chunk loop: every chunk of ``scene`` that no writer holds yet (sweep/write/writer.py: the journal of
    an earlier run), computed through ``imap`` (sweep/run/backends.py; default :func:`in_process`) and handed to
    every writer as it finishes; then the chunks held from the earlier run, read back and handed to the others.
    ``plan`` None: the chunks are the blocks of the scene's grid, each planned where it is computed
    (:func:`chunk_task`); else the points of ``plan`` in rows."""
    imap = imap or in_process
    if plan is None:
        n, chunks = scene.n_points, chunk_points(scene.shape, chunk_size)
    else:
        n, chunks = plan.n_points, chunk_points(plan.n_points, chunk_size or plan.chunk_size)
    held: dict[int, Writer] = {}
    for writer in writers:
        writer.start(chunks)
        for i in writer.done():
            held.setdefault(i, writer)
    todo = _Todo(chunks, [i for i in range(len(chunks)) if i not in held])
    with Progress(n, enabled=progress) as bar:
        bar.update(sum(chunks.size(i) for i in held))
        try:
            for i, arrays in imap(scene, plan, todo, progress=progress):
                for writer in writers:
                    writer.put(i, arrays)
                bar.update(chunks.size(i))
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


class _Todo(Sequence):
    """(i, points) of the chunks ``indices`` of ``layout``, each made when asked for."""

    def __init__(self, layout: ChunkLayout, indices: list[int]) -> None:
        self.layout, self.indices = layout, indices

    def __len__(self) -> int:
        return len(self.indices)

    def __getitem__(self, n):
        if isinstance(n, slice):
            return [self[j] for j in range(*n.indices(len(self)))]
        return self.indices[n], self.layout[self.indices[n]]
