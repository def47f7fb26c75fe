"""The writer interface: where the finished chunks of a run go. The chunk loop (sweep/run/runner.py) hands every
chunk to its writers and knows nothing else of them.

A writer is started with the run's chunk layout, takes one finished chunk at a time (:meth:`Writer.put`, from the
thread that runs the loop; it may do its work in a thread of its own) and is closed when the loop ends (every chunk
put is then stored, or the first failure raised). A writer that keeps chunks across runs (the journal,
sweep/run/journal.py) says which it holds (:meth:`Writer.done`) and reads them back (:meth:`Writer.read`) for the
other writers of a resumed run. Implementations: :class:`FlatArrays` (per-point arrays in memory, the Dataset's
input), sweep.write.netcdf.NetCDFWriter (the file), sweep.run.journal.Journal (crash-safe chunk files).
"""

from __future__ import annotations

import threading
from abc import ABC, abstractmethod
from collections import deque
from collections.abc import Callable, Iterable
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

__all__ = ["PENDING_CHUNKS", "Behind", "FlatArrays", "Writer"]

PENDING_CHUNKS = 2
"""Most chunks handed to a writer's helper thread (:class:`Behind`) and not yet stored: the computing waits beyond
that (a slow disk must not fill the memory with chunks)."""


class Writer(ABC):
    """Where finished chunks go (module docstring)."""

    def start(self, layout: tuple[np.ndarray, ...]) -> None:
        """Start taking chunks of ``layout`` (chunk i's points, in the order its arrays come)."""
        self.layout = layout

    @abstractmethod
    def put(self, index: int, arrays: dict[str, np.ndarray]) -> None:
        """Take finished chunk ``index`` (its per-point arrays over ``layout[index]``, plus ``seconds``); the arrays
        are not changed afterwards, the dict may be."""

    def close(self) -> None:  # noqa: B027 (a writer that stores at once has nothing to wait for)
        """Wait until every chunk put is stored; raise the first failure."""

    def abort(self, error: BaseException) -> None:  # noqa: B027 (likewise)
        """Stop after ``error`` (raised by the loop or by another writer): keep what was stored, raise nothing."""

    def resume_hint(self, n_chunks: int) -> str | None:
        """After an interruption: where the chunks stored are and how to continue (None: nothing kept)."""
        return None

    def done(self) -> set[int]:
        """The chunks this writer already holds from an earlier run."""
        return set()

    def read(self, index: int) -> dict[str, np.ndarray]:
        """The arrays of a chunk it holds (:meth:`done`)."""
        raise KeyError(index)


class FlatArrays(Writer):
    """Every chunk's arrays consolidated into arrays over all ``n`` points (flat over the grid), as soon as it is put:
    no second copy of the chunks. ``skip``: names left out (those a journal keeps and the file takes block by block).
    ``seconds`` sums the chunks' own times."""

    def __init__(self, n: int, skip: Iterable[str] = ()) -> None:
        self.n, self.skip = n, frozenset(skip)
        self.flat: dict[str, np.ndarray] = {}
        self.seconds = 0.0

    def put(self, index: int, arrays: dict[str, np.ndarray]) -> None:
        points = self.layout[index]
        self.seconds += float(arrays.get("seconds", 0.0))
        for name, value in arrays.items():
            if name == "seconds" or name in self.skip or not isinstance(value, np.ndarray):
                continue
            if name not in self.flat:
                fill = np.nan if value.dtype.kind == "f" else 0
                self.flat[name] = np.full((self.n,) + value.shape[1:], fill, dtype=value.dtype)
            self.flat[name][points] = value


class Behind:
    """Work done in one helper thread, in the order submitted, while the caller goes on: at most ``pending`` calls
    waiting (:meth:`submit` blocks beyond that). The first failure is raised by the next :meth:`submit` or by
    :meth:`close`, and nothing submitted after it runs."""

    def __init__(self, name: str, pending: int = PENDING_CHUNKS) -> None:
        self.pending: deque[Future] = deque()
        self.limit = pending
        self.failed = threading.Event()
        self.executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix=name)

    def submit(self, fn: Callable[..., object], *args: object) -> None:
        while self.pending and (self.pending[0].done() or len(self.pending) >= self.limit):
            self.pending.popleft().result()  # a failed call raises here
        self.pending.append(self.executor.submit(self._call, fn, *args))

    def _call(self, fn: Callable[..., object], *args: object) -> None:
        if self.failed.is_set():  # after a failure nothing more is done
            return
        try:
            fn(*args)
        except BaseException:
            self.failed.set()
            raise

    def close(self, raise_errors: bool = True) -> None:
        """Wait for every call submitted; raise the first failure (unless not ``raise_errors``)."""
        self.executor.shutdown(wait=True)
        while self.pending:
            future = self.pending.popleft()
            if raise_errors:
                future.result()
