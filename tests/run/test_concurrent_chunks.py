"""Chunks computed side by side (sweep/run/concurrent_chunks.py): the same bits as one chunk at a time, every finished
chunk handed back before a failure is raised, nothing left running when the consumer stops."""

from __future__ import annotations

import dataclasses
import signal
import threading
import time

import numba
import numpy as np
import pytest

import sweep
from sweep.run.concurrent_chunks import as_completed_in_threads, side_by_side


def _chunks(n: int):
    return ((i, np.arange(i * 3, i * 3 + 3)) for i in range(n))


def test_every_chunk_comes_back_once_computed_in_other_threads():
    threads: set[str] = set()

    def compute(points):
        threads.add(threading.current_thread().name)
        time.sleep(0.002 * (points[0] % 4))  # finish out of order
        return {"twice": 2 * points, "threads": np.array(numba.get_num_threads())}

    got = dict(as_completed_in_threads(compute, _chunks(12), workers=2))
    assert sorted(got) == list(range(12))
    for i, arrays in got.items():
        np.testing.assert_array_equal(arrays["twice"], 2 * np.arange(i * 3, i * 3 + 3))
        assert arrays["threads"] == 1  # each chunk's kernels on one numba thread
    assert threading.main_thread().name not in threads and len(threads) >= 1


def test_a_failing_chunk_is_raised_after_the_chunks_already_running_come_back():
    started, finished = [], []

    def compute(points):
        i = int(points[0]) // 3
        started.append(i)
        if i == 3:
            raise KeyboardInterrupt  # as a Ctrl-C in the middle of a chunk
        time.sleep(0.02)
        finished.append(i)
        return {"i": np.array(i)}

    got = []
    with pytest.raises(KeyboardInterrupt):
        for i, _ in as_completed_in_threads(compute, _chunks(20), workers=2):
            got.append(i)
    assert sorted(got) == sorted(finished)  # every chunk that finished was handed back
    assert 3 in started and 3 not in got and len(started) < 20  # and the rest were not started


def test_ctrl_c_while_waiting_hands_back_every_chunk_that_finished():
    """SIGINT to the main thread while it waits for chunks (where it spends its time): the chunks running then still
    finish and come back, then KeyboardInterrupt (the journal keeps every finished chunk)."""
    finished = []

    def compute(points):
        time.sleep(0.05)
        finished.append(int(points[0]) // 3)
        return {}

    got = []
    ctrl_c = threading.Timer(0.12, lambda: signal.pthread_kill(threading.main_thread().ident, signal.SIGINT))
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        ctrl_c.start()
        with pytest.raises(KeyboardInterrupt):
            for i, _ in as_completed_in_threads(compute, _chunks(40), workers=2):
                got.append(i)
    finally:
        ctrl_c.cancel()
        signal.signal(signal.SIGINT, previous)
    assert sorted(got) == sorted(finished) and 2 <= len(got) < 40


def test_a_consumer_that_stops_leaves_no_chunk_running():
    running = []

    def compute(points):
        running.append(1)
        time.sleep(0.02)
        running.pop()
        return {}

    gen = as_completed_in_threads(compute, _chunks(50), workers=2)
    next(gen)
    gen.close()  # as when the chunk loop raises
    assert running == []


@pytest.mark.slow
@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 numba threads (2 cores)")
@pytest.mark.parametrize("observables", [("xi_inf",), ("xi_inf", "trajectory", "t50")], ids=["relaxed", "transients"])
def test_side_by_side_gives_the_same_bits_as_one_chunk_at_a_time(observables):
    """Soft springs of the default sample (model auto: inertial points among the relaxed slips; points flagged
    error_above_tol among the transients, whose t50 keeps them on the per-point path): every variable bitwise equal
    with 1 numba thread (chunks one after another) and 2 (side by side, where the threading layer allows it)."""
    scene = dataclasses.replace(sweep.default_scene(), K_over_M=np.logspace(1, 3, 24), V=np.logspace(-6, -3, 20),
                                observables=observables)
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        alone = sweep.run_sweep(scene, progress=False, chunk_size=20)
        numba.set_num_threads(2)
        together = sweep.run_sweep(scene, progress=False, chunk_size=20)  # 24 chunks
        assert side_by_side(100) == (2 if numba.threading_layer() in ("omp", "tbb") else 1) and side_by_side(3) == 1
    finally:
        numba.set_num_threads(threads)
    mixed = alone["model"].values if observables == ("xi_inf",) else alone["status"].values
    assert np.unique(mixed).size == 2  # the points of both kinds are there
    for name in alone.data_vars:
        np.testing.assert_array_equal(alone[name].values, together[name].values, err_msg=name)


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 numba threads (2 cores)")
def test_a_run_interrupted_side_by_side_resumes_to_the_uninterrupted_file(tmp_path, monkeypatch):
    """Chunks journaled out of order (side by side), Ctrl-C in the middle of one: every chunk finished before the
    interrupt is in the journal, and --resume computes the rest into the same numbers as a run never interrupted."""
    from faults import interrupt_after

    import sweep.run.runner as runner
    from sweep.run.journal import journal_path

    scene = dataclasses.replace(sweep.default_scene(), K_over_M=np.logspace(3, 6, 24), V=np.logspace(-7, -4, 20),
                                model="quasistatic", observables=("xi_inf", "trajectory"))
    out = tmp_path / "s.nc"
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(2)
        started = interrupt_after(monkeypatch, 12)
        with pytest.raises(runner.Interrupted):
            sweep.run_sweep(scene, progress=False, output=out, chunk_size=20)
        monkeypatch.undo()
        assert len(list(journal_path(out).glob("chunk-*.npz"))) == len(started) == 12
        resumed = sweep.run_sweep(scene, progress=False, output=out, chunk_size=20, resume=True).load()
    finally:
        numba.set_num_threads(threads)
    whole = sweep.run_sweep(scene, progress=False)
    for name in whole.data_vars:
        np.testing.assert_array_equal(resumed[name].values, whole[name].values, err_msg=name)
