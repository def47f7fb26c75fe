"""Many independent optimisations in lockstep, their forward runs merged into one engine call per round.

scipy.optimize.least_squares asks for one function value at a time. To fit many curves (and many profile points)
at the price of a few engine calls, each optimisation runs in a thread of its own; whenever it needs the forward
model it posts its points and waits. When every running optimisation is waiting, the coordinator (the calling
thread) merges all posted points into one batch, runs the engine once, and hands each its rows back. A point's
numbers do not depend on the other points of a batch (sweep/integrate/batch.py), so each optimisation takes
exactly the path it would take alone: many curves in one call give the same estimates as one call per curve.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import fields
from typing import Any

import numpy as np

from .forward import ForwardPoints, ForwardResult, forward

__all__ = ["Lockstep", "run_merged"]

MAX_THREADS = 256
"""Optimisations running at once (more wait for a free thread; each round merges the running ones)."""


def _pad(t: np.ndarray, n_t: int) -> np.ndarray:
    if t.shape[1] == n_t:
        return t
    if t.shape[1] == 0:
        return np.zeros((t.shape[0], n_t))
    return np.concatenate((t, np.repeat(t[:, -1:], n_t - t.shape[1], axis=1)), axis=1)


def _distinct_rows(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(index of the first of each distinct row of the 2-D float array ``a``, the number of each row's distinct row):
    rows compared by their bytes, one memcmp-sorted key a row (np.unique(axis=0) compares a row of 200 sample times
    field by field: ~20 ms a round, 1.2 s of a 20-curve fit's 7 s). Rows equal in value but not in bits (0.0 and
    -0.0) stay apart: they are solved twice, with the same numbers."""
    rows = np.ascontiguousarray(a).reshape(a.shape[0], -1)
    if rows.shape[1] == 0:  # no columns: every row is the same
        return np.zeros(min(1, rows.shape[0]), np.intp), np.zeros(rows.shape[0], np.intp)
    keys = rows.view(np.dtype((np.void, rows.dtype.itemsize * max(1, rows.shape[1])))).reshape(-1)
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return first, inverse.reshape(-1)


def unique_points(points: ForwardPoints) -> tuple[ForwardPoints, np.ndarray]:
    """(the distinct points of ``points``, the index of each point among them): equal inputs give equal outputs,
    since a point's numbers do not depend on its batch. Curves of one campaign often share (K/M, V), times and
    bounds, so their global grids are the same parameter sets (100 such curves: the global stage solves one grid,
    not 100); profile and perturbed sets repeat too."""
    n = points.n
    t = np.asarray(points.t, dtype=float).reshape(n, -1)
    _, t_row = _distinct_rows(t)  # rows of times, then the 6 parameters: keys of 7 numbers
    keys = np.column_stack([np.broadcast_to(np.asarray(getattr(points, f), dtype=float), (n,))
                            for f in ForwardPoints._fields[:-1]] + [t_row.astype(float)])
    first, inverse = _distinct_rows(keys)
    kept = ForwardPoints(*(np.broadcast_to(np.asarray(getattr(points, f), dtype=float), (n,))[first]
                           for f in ForwardPoints._fields[:-1]), t=t[first])
    return kept, inverse.reshape(n)


def run_merged(requests: Sequence[ForwardPoints], rtol: float, V0: float, g: float) -> list[ForwardResult]:
    """Run every request's points in one engine call, each distinct point once (:func:`unique_points`); each
    request gets its own rows back (times padded with their last value to a common width, then cut back)."""
    sizes = [r.n for r in requests]
    n_t = max(np.shape(r.t)[1] for r in requests)
    merged = ForwardPoints(*(np.concatenate([np.atleast_1d(getattr(r, f)) for r in requests])
                             for f in ForwardPoints._fields[:-1]),
                           t=np.concatenate([_pad(np.asarray(r.t, dtype=float), n_t) for r in requests]))
    distinct, where = unique_points(merged)
    once = forward(distinct, rtol=rtol, V0=V0, g=g)
    res = ForwardResult(*(getattr(once, f.name)[where] for f in fields(ForwardResult)))
    out, start = [], 0
    for req, n in zip(requests, sizes):
        cols = np.shape(req.t)[1]
        sl = slice(start, start + n)
        out.append(ForwardResult(x=res.x[sl, :cols], x_err=res.x_err[sl, :cols], dx_inf=res.dx_inf[sl],
                                 dx_inf_err=res.dx_inf_err[sl], status=res.status[sl], stable=res.stable[sl]))
        start += n
    return out


class Lockstep:
    """Run tasks ``fn(item, evaluate)`` in threads; ``evaluate(points)`` blocks until the round's merged engine call
    returns that task's :class:`ForwardResult`. ``rounds`` counts the engine calls; ``on_round`` (if given) is
    called after each with (round number, points in it)."""

    def __init__(self, rtol: float, V0: float, g: float, on_round: Callable[[int, int], None] | None = None):
        self.rtol, self.V0, self.g, self.on_round = rtol, V0, g, on_round
        self.rounds = 0
        self._cond = threading.Condition()
        self._posted: dict[int, ForwardPoints] = {}
        self._answers: dict[int, ForwardResult] = {}
        self._waiting: dict[int, threading.Event] = {}
        self._running = 0

    def _evaluate(self, points: ForwardPoints) -> ForwardResult:
        token, answered = threading.get_ident(), threading.Event()
        with self._cond:
            self._posted[token] = points
            self._waiting[token] = answered
            self._cond.notify_all()  # only the coordinator waits on the condition
        # each task waits on its own event: a shared condition woke every waiting task at every post and answer
        # (256 tasks: ~65,000 wake-ups a round)
        answered.wait()
        with self._cond:
            return self._answers.pop(token)

    def map(self, fn: Callable[[Any, Callable[[ForwardPoints], ForwardResult]], Any], items: Sequence[Any]) -> list:
        """Results of fn(item, evaluate) for every item, in order (the first exception of a task is raised)."""
        items = list(items)
        results: list[Any] = [None] * len(items)
        errors: list[BaseException] = []
        queue = list(range(len(items)))[::-1]

        def worker() -> None:
            while True:
                with self._cond:
                    if not queue or errors:
                        return
                    i = queue.pop()
                    self._running += 1
                try:
                    results[i] = fn(items[i], self._evaluate)
                except BaseException as exc:  # noqa: BLE001 (handed to the caller)
                    errors.append(exc)
                finally:
                    with self._cond:
                        self._running -= 1
                        self._cond.notify_all()

        threads = [threading.Thread(target=worker, daemon=True) for _ in range(min(MAX_THREADS, len(items)))]
        for th in threads:
            th.start()
        while True:
            with self._cond:
                while not (self._posted and len(self._posted) == self._running) and \
                        not (self._running == 0 and (not queue or errors)):
                    self._cond.wait()
                if not self._posted:
                    break
                tokens, requests = zip(*self._posted.items())
                self._posted.clear()
            answers = run_merged(requests, self.rtol, self.V0, self.g)
            self.rounds += 1
            if self.on_round is not None:
                self.on_round(self.rounds, sum(r.n for r in requests))
            with self._cond:
                self._answers.update(zip(tokens, answers))
                for token in tokens:
                    self._waiting.pop(token).set()
        for th in threads:
            th.join()
        if errors:
            raise errors[0]
        return results
