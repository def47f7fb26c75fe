"""Where the chunks of a sweep run: in this process (numba's own threads; past the first chunk, chunks side by side
in threads of one numba thread each: sweep/run/concurrent_chunks.py) or on a dask.distributed cluster.

Either way a chunk is the same task, :func:`sweep.run.runner.chunk_task` (sent the scene and the chunk's points, a
block of the grid, which it plans itself: no plan of the whole grid exists anywhere; the same compiled kernels), and
its results come back to the driver, the single writer of the journal and of the file, at most IN_FLIGHT_PER_WORKER
chunks a worker in flight. A point's
numbers depend on that point only and the kernels use no reassociating fastmath flags, so the results are bitwise
the same whatever the backend, the chunking and the number of workers (on one instruction set).

dask workers run one thread each with NUMBA_NUM_THREADS=1, set through ``distributed.nanny.pre-spawn-environ``
(the nanny does not set it, and numba reads it once, at import): otherwise every worker process would start as
many numba threads as the machine has cores. The driver compiles (or loads) the kernels before the fan-out, so
that the workers find them in numba's on-disk cache instead of each compiling them.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

import numpy as np

from ..errors import InputError
from ..plan.plan import Plan
from ..scene.scene import Scene
from .runner import chunk_task, in_process

__all__ = ["BACKENDS", "check_backend", "local_cluster", "open_backend"]

BACKENDS = ("threads", "dask")
IN_FLIGHT_PER_WORKER = 2
"""Chunks submitted ahead per worker: enough to keep workers busy, few enough to bound the driver's memory."""
CONNECT_TIMEOUT_S = 5.0
"""How long to try to reach an existing dask scheduler [s] before giving up with an InputError."""
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}


def _import_dask():
    try:
        import dask
        import distributed
    except ImportError:
        raise InputError("backend 'dask' needs dask.distributed: pip install '.[distributed]' in the sweep "
                         "checkout") from None
    return dask, distributed


@contextmanager
def local_cluster(workers: int = 2) -> Iterator[str]:
    """A dask LocalCluster of ``workers`` worker processes, one thread and one numba thread each, for as long as the
    context lasts; yields its scheduler address for ``run_sweep(..., backend="dask", scheduler=address)``. Start it
    once for many sweeps: ``run_sweep(..., workers=N)`` starts one per call (~1.5 s here) and shuts it down (~0.5 s).
    """
    _check_workers(workers)
    dask, distributed = _import_dask()
    env = {**dask.config.get("distributed.nanny.pre-spawn-environ", {}), **WORKER_ENV}
    saved = {key: os.environ.get(key) for key in env}
    try:
        with dask.config.set({"distributed.nanny.pre-spawn-environ": env}):
            with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                          dashboard_address=None) as cluster:
                _restore(saved)
                yield cluster.scheduler_address
    finally:
        _restore(saved)


@contextmanager
def _dask(workers: int | None, scheduler: str | None):
    """A dask Client: connected to ``scheduler``, or on a :func:`local_cluster` of ``workers`` started for it."""
    if scheduler is not None:
        _reachable(scheduler)
    _, distributed = _import_dask()
    if scheduler is not None:
        try:
            client = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError) as exc:
            why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise InputError(f"could not connect to the dask scheduler at {scheduler!r} (tried for at most "
                             f"{CONNECT_TIMEOUT_S:g} s): {why}") from None
        with client:
            check_workers_run_this_sweep(client)
            yield client
        return
    with local_cluster(workers or 2) as address, distributed.Client(address) as client:
        yield client


WORKER_PROBE = "__import__('sweep.jitcache').jitcache.source_digest()"
"""What each worker of an existing cluster is asked before any work: the digest of its sweep's sources."""


def check_workers_run_this_sweep(client) -> None:
    """InputError, before any work, where a worker of the cluster cannot import sweep or runs other sources than
    this process (other sources may give other numbers, and the journal binds a run to its sources)."""
    from ..jitcache import source_digest

    found = client.run(eval, WORKER_PROBE, on_error="return")
    if not found:
        raise InputError("the dask cluster has no workers: start some (dask worker ADDRESS) before the run")
    missing = {w: v for w, v in found.items() if isinstance(v, BaseException)}
    if missing:
        why = next(iter(missing.values()))
        raise InputError(f"{len(missing)} of {len(found)} dask workers cannot import sweep ({type(why).__name__}: "
                         f"{why}): install this sweep on them (pip install '.[distributed]' in its checkout)")
    mine = source_digest()
    other = sorted({v for v in found.values() if v != mine})
    if other:
        raise InputError(f"the dask workers run other sweep sources (digest {', '.join(other)}; here {mine}): "
                         "install the same version of sweep on them")


def _reachable(scheduler: str) -> None:
    """InputError at once where nothing listens at a tcp:// scheduler address (dask.distributed retries a refused
    connection until its timeout: 5 s for an answer that the first attempt had), or where the host does not answer
    within CONNECT_TIMEOUT_S. Other schemes (tls://, ucx://...) are left to dask."""
    import socket
    from urllib.parse import urlsplit

    try:
        parts = urlsplit(scheduler if "://" in scheduler else f"tcp://{scheduler}")
        host, port = parts.hostname, parts.port
    except ValueError:
        raise InputError(f"scheduler must be an address such as tcp://host:8786, got {scheduler!r}") from None
    if parts.scheme != "tcp":
        return
    if not host or port is None:
        raise InputError(f"scheduler must be an address such as tcp://host:8786, got {scheduler!r}")
    try:
        socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        why = exc.strerror or str(exc) or type(exc).__name__
        raise InputError(f"could not connect to the dask scheduler at {scheduler!r} (tried for at most "
                         f"{CONNECT_TIMEOUT_S:g} s): {why}") from None


def _restore(saved: dict[str, str | None]) -> None:
    """Undo the nanny's update of this process's environment (a LocalCluster's nannies run in the driver and set
    the pre-spawn variables in os.environ for good: numba re-reads NUMBA_NUM_THREADS when it compiles and refuses a
    value that differs from its running thread pool)."""
    for key, value in saved.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value


def _on_dask(client, scene: Scene, plan: Plan, todo: Iterable[tuple[int, np.ndarray]]):
    """Submit the chunks (a bounded number in flight) and yield them as they complete; dask retries a chunk whose
    worker died."""
    from distributed import as_completed

    scene_f = client.scatter(scene, broadcast=True)
    todo = iter(todo)
    limit = IN_FLIGHT_PER_WORKER * max(1, len(client.scheduler_info()["workers"]))
    pending = as_completed()
    index = {}

    def submit_next() -> bool:
        item = next(todo, None)
        if item is None:
            return False
        i, points = item
        # a chunk of a scene is planned by its worker from the scene (plan None); a caller's own plan travels as
        # the chunk's share of it
        future = client.submit(chunk_task, scene_f, None if plan is None else plan.take(points), points,
                               key=f"sweep-chunk-{i}-{id(todo)}", retries=3)
        index[future.key] = i
        pending.add(future)
        return True

    for _ in range(limit):
        if not submit_next():
            break
    for future in pending:
        yield index.pop(future.key), future.result()
        future.release()
        submit_next()


def check_backend(backend: str, workers: int | None, scheduler: str | None) -> None:
    """InputError naming the argument if the backend arguments are not allowed (before any work)."""
    if backend not in BACKENDS:
        raise InputError(f"backend must be one of {list(BACKENDS)}, got {backend!r}")
    if backend == "threads":
        if workers is not None or scheduler is not None:
            raise InputError("workers and scheduler are for backend 'dask' (the threads backend uses numba's threads: "
                             "NUMBA_NUM_THREADS)")
        return
    if workers is not None:
        _check_workers(workers)
    if workers is not None and scheduler is not None:
        raise InputError("give workers (a local cluster started for this run) or scheduler (an existing one), not both")


def _check_workers(workers: int) -> None:
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"workers must be an integer >= 1, got {workers!r}")


@contextmanager
def open_backend(backend: str = "threads", workers: int | None = None, scheduler: str | None = None) -> Iterator:
    """A function imap(scene, plan, todo, progress=False) -> iterator of (chunk index, arrays) as chunks complete,
    for the duration of the context (a dask cluster started here is shut down on exit; ``progress``: see
    runner.in_process, not shown from dask workers)."""
    check_backend(backend, workers, scheduler)
    if backend == "threads":
        yield in_process
        return
    with _dask(workers, scheduler) as client:
        yield lambda scene, plan, todo, progress=False: _on_dask(client, scene, plan, todo)
