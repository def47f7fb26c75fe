"""Chunks journaled in a helper thread (sweep.run.journal.Journal.background): every chunk handed over is on disk, whole
and verified, when the block ends (also when it ends by Ctrl-C), in the order handed over; a failed write is raised
in the caller's thread and leaves no partial file. (A run interrupted, resumed and compared bit for bit with an
uninterrupted one goes through the same path: tests/run/test_integrity.py, tests/run/test_resume.py.)"""

from __future__ import annotations

import errno
import threading
import time

import numpy as np
import pytest

import sweep.run.journal as journal_module
from sweep.errors import OutputError
from sweep.run.journal import PENDING_CHUNKS, Journal

RANGES = [(0, 3), (3, 6), (6, 9), (9, 12), (12, 15)]


def chunk(i: int) -> dict[str, np.ndarray]:
    start, stop = RANGES[i]
    return {"xi_inf": np.linspace(start, stop, stop - start) * 0.1, "status": np.arange(start, stop, dtype=np.int8),
            "seconds": np.array(0.25 * i)}


@pytest.fixture
def journal(tmp_path):
    return Journal.open(tmp_path / "out.nc", {"scene": "test", "plan_hash": "abc"}, RANGES)


@pytest.fixture
def slow_writes(monkeypatch):
    """Each chunk write takes 50 ms and records the thread and chunk order it ran in."""
    real, seen = journal_module._save_arrays, []

    def slow(f, arrays):
        time.sleep(0.05)
        seen.append((threading.current_thread().name, float(arrays["seconds"])))
        real(f, arrays)

    monkeypatch.setattr(journal_module, "_save_arrays", slow)
    return seen


def assert_whole(journal: Journal, indices) -> None:
    assert journal.done() == set(indices)
    for i in indices:
        read = journal.read(i)  # checked against its record and checksum
        for name, value in chunk(i).items():
            np.testing.assert_array_equal(read[name], value)
    assert not list(journal.path.glob("*.tmp"))


def test_every_chunk_handed_over_is_written_whole_in_order_by_a_helper_thread(journal, slow_writes, monkeypatch):
    gate, slow = threading.Event(), journal_module._save_arrays

    def gated(f, arrays):  # no write finishes before the gate opens
        assert gate.wait(timeout=60), "the gate was never opened"
        slow(f, arrays)

    monkeypatch.setattr(journal_module, "_save_arrays", gated)
    with journal.background() as keep:
        for i in range(len(RANGES)):
            if i == PENDING_CHUNKS:
                # the caller handed over PENDING_CHUNKS chunks while none was written: it did not wait for a write
                assert journal.done() == set() and not slow_writes
                gate.set()
            arrays = chunk(i)
            keep(i, arrays)
            arrays.pop("seconds")  # what the runner does right after: the chunk keeps it
    assert [s for _, s in slow_writes] == [0.25 * i for i in range(len(RANGES))]
    assert all(name.startswith("sweep-journal") for name, _ in slow_writes)
    assert_whole(journal, range(len(RANGES)))


def test_ctrl_c_waits_for_the_chunks_handed_over(journal, slow_writes):
    with pytest.raises(KeyboardInterrupt), journal.background() as keep:
        for i in range(PENDING_CHUNKS + 1):
            keep(i, chunk(i))
        raise KeyboardInterrupt
    assert_whole(journal, range(PENDING_CHUNKS + 1))


def test_a_failed_write_is_raised_in_the_callers_thread_and_leaves_no_partial_file(journal, monkeypatch):
    real = journal_module._save_arrays

    def failing(f, arrays):
        if float(arrays["seconds"]) == 0.5:  # chunk 2
            f.write(b"PK\x03\x04 partial")
            raise OSError(errno.ENOSPC, "No space left on device", f.name)
        real(f, arrays)

    monkeypatch.setattr(journal_module, "_save_arrays", failing)
    with pytest.raises(OutputError, match=r"chunk-000002\.npz \(No space left on device\); the 2 finished chunks"):
        with journal.background() as keep:
            for i in range(len(RANGES)):
                keep(i, chunk(i))
    assert_whole(journal, {0, 1})  # none written after the failure: the count in the message is what is kept
    assert {p.name for p in journal.path.iterdir()} == {"manifest.json", "chunk-000000.npz", "chunk-000001.npz"}
