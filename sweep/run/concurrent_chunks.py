"""Chunks side by side in this process: one chunk per thread, each with a single numba thread.

Why not numba's threads inside each chunk alone: a chunk is a few milliseconds of compiled kernel between stretches
of serial numpy and Python (the tolerance ladder between its kernel calls, the choice of model, the error marks, the
journal's hand-over), and while one thread runs those the other numba threads wait. Two chunks side by side, each
kernel on one numba thread with the GIL released (the batch loops are ``nogil``), overlap one chunk's serial part
with the other's kernel, and a kernel on one thread needs no work-sharing between threads. Measured on the 1e6-point
default grid (2 cores, benchmarks/auto_cost.py): see docs/design.md section 8.

Results do not change: every point's numbers depend on that point only (the lanes' arithmetic does not depend on
their neighbours or on how many threads run them), so the chunks come back in another order with the same bits.

This needs a numba threading layer that may be entered from several threads at once: ``omp`` or ``tbb``, not
``workqueue`` (numba's docs: "threadsafe" layers); elsewhere the chunks run one after another, as before.
"""

from __future__ import annotations

import concurrent.futures as cf
from collections.abc import Callable, Iterator

import numba
import numpy as np

__all__ = ["THREADSAFE_LAYERS", "as_completed_in_threads", "side_by_side"]

THREADSAFE_LAYERS = ("omp", "tbb")
MIN_CHUNKS_PER_THREAD = 8
"""Fewer chunks than this a thread run one after another on all threads: side by side, the last chunks leave a
thread idle (the default scene's 5 chunks of 4096 points: 2 threads gave 1.49x one thread side by side, 1.70x one
chunk at a time; best of 15, alternated)."""
IN_FLIGHT_PER_WORKER = 2
"""Chunks submitted ahead per thread: a finished chunk's successor is already queued."""


def side_by_side(chunks_left: int) -> int:
    """How many chunks to run at once, with ``chunks_left`` to compute: numba's thread count where its threading
    layer (known once a parallel kernel has run) is safe to enter from several threads and there are at least
    MIN_CHUNKS_PER_THREAD chunks a thread, else 1."""
    threads = numba.get_num_threads()
    if threads < 2 or chunks_left < MIN_CHUNKS_PER_THREAD * threads:
        return 1
    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel kernel has run yet in this process
        return 1
    return threads if layer in THREADSAFE_LAYERS else 1


def as_completed_in_threads(compute: Callable[[np.ndarray], dict[str, np.ndarray]],
                            todo: Iterator[tuple[int, np.ndarray]], workers: int
                            ) -> Iterator[tuple[int, dict[str, np.ndarray]]]:
    """(i, compute(points)) for every (i, points) of ``todo``, computed in ``workers`` threads with one numba thread
    each, yielded as they complete (at most IN_FLIGHT_PER_WORKER x ``workers`` submitted ahead). A chunk that fails,
    or Ctrl-C while this waits for chunks, cancels the chunks not started; those running still finish and are
    yielded (nothing finished is lost), then the failure is raised. When the consumer stops (an exception of its
    own), the chunks not started are cancelled and those running waited for, so no thread is left writing once this
    returns."""

    def one(i: int, points: np.ndarray) -> tuple[int, dict[str, np.ndarray]]:
        numba.set_num_threads(1)  # thread-local: this thread's kernels run on it alone
        return i, compute(points)

    with cf.ThreadPoolExecutor(workers, thread_name_prefix="sweep-chunk") as pool:
        pending: set[cf.Future] = set()

        def submit_next() -> None:
            item = next(todo, None)
            if item is not None:
                pending.add(pool.submit(one, *item))

        failed: BaseException | None = None
        try:
            for _ in range(IN_FLIGHT_PER_WORKER * workers):
                submit_next()
            while pending:
                try:
                    done, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
                except KeyboardInterrupt as exc:  # Ctrl-C while waiting: the running chunks still come back
                    failed = failed or exc
                    for other in pending:
                        other.cancel()
                    continue
                for future in done:
                    pending.discard(future)
                    if future.cancelled():
                        continue
                    if future.exception() is not None:
                        # the chunks already running still finish and come back (nothing computed is lost), then
                        # the first failure is raised
                        failed = failed or future.exception()
                        for other in pending:
                            other.cancel()
                        continue
                    yield future.result()
                    if failed is None:
                        submit_next()
        finally:
            for future in pending:
                future.cancel()
        if failed is not None:
            raise failed
