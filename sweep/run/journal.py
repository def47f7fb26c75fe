"""A crash-safe journal of finished chunks beside a sweep's output, so that an interrupted run loses nothing, and that
can only hold its own run.

HDF5 (netCDF4) files are not safe to kill mid-write, so a running sweep writes no netCDF at all: each finished chunk
goes into ``<output>.journal/chunk-NNNNNN.npz``, written to a temporary name, flushed to disk (fsync) and renamed
into place (an atomic rename on POSIX). A SIGKILL at any moment therefore leaves whole chunks only, never a torn
one. A single writer consolidates the chunks into the netCDF file at the end, after which the journal is removed.

What binds a journal to its run:

* ``manifest.json``, written atomically before any chunk, records the run's identity: the journal format, the scene's
  canonical TOML, the plan hash, the digest of sweep's own sources (another version, or edited sources, may give
  other numbers for the same plan) and the chunk layout (points, chunk size, number of chunks). A run resumes a
  journal only if that identity is the same.
* every chunk carries a record (the member ``JOURNAL_RECORD`` of its .npz): the run's id (a digest of the identity),
  the plan hash, its index, the range of points it covers and a checksum of its arrays. A chunk is checked against
  that record and the run's layout whenever it is read; one that does not match (truncated, bit-flipped, under
  another index, of another run) is never consolidated.
* on resume every file of the journal is checked before any computation: a chunk that does not match, a chunk
  index outside the layout and a stray file are moved aside into ``<output>.rejected/`` (never deleted), each with
  a one-line :class:`~sweep.errors.JournalWarning`, and the missing chunks are computed again. A journal without a
  readable manifest cannot be attributed to any run: resuming it moves it aside whole and starts afresh.
* a run without ``resume`` never consumes a journal: it refuses with one line saying how to resume it or to start
  over (``overwrite``: the old journal is deleted). The exception is a journal holding nothing but its manifest (a
  run stopped before its first chunk, e.g. Ctrl-C while compiling): nothing to lose, so it is started afresh.

A running sweep hands its chunks to :meth:`Journal.background`, which writes them in order in one helper thread while
the next chunks compute (the checksum, the file write and the fsyncs need no kernel), at most
:data:`PENDING_CHUNKS` waiting; each write is the same atomic write as :meth:`Journal.write`, so a crash leaves whole
chunks only, as before. Leaving the ``with`` block waits for every chunk handed over, also when the run is
interrupted, so the journal then holds every chunk computed.

Write failures (disk full, permission) become :class:`~sweep.errors.OutputError` lines that say the finished
chunks are kept (sweep/write/targets.py); the temporary file of the failed write is removed.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
import shutil
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from ..errors import InputError, JournalWarning, OutputError
from ..write.targets import remove_quietly, write_failed
from ..write.writer import PENDING_CHUNKS, Behind, Writer

__all__ = ["FORMAT", "JOURNAL_RECORD", "Journal", "journal_path", "rejected_path"]

FORMAT = 3
"""3: chunks carry a record binding them to their run and a checksum (2: consecutive ranges; 1: spread points)."""
MANIFEST = "manifest.json"
JOURNAL_RECORD = "__journal__"
"""The member of a chunk's .npz that holds its record (JSON text)."""
CHUNK = re.compile(r"chunk-(\d{6,})\.npz")
TEMPORARY = re.compile(r"(chunk-\d{6,}\.npz|manifest\.json)\.tmp")
"""Leftovers of a write interrupted before its rename: never whole, so removed."""


def journal_path(output: str | os.PathLike) -> Path:
    """The journal directory of an output file."""
    output = Path(output)
    return output.with_name(output.name + ".journal")


def rejected_path(output: str | os.PathLike) -> Path:
    """The folder where files refused from the journal of ``output`` are moved (kept for inspection)."""
    output = Path(output)
    return output.with_name(output.name + ".rejected")


def checksum(arrays: dict[str, np.ndarray]) -> str:
    """Digest of named arrays: names, dtypes, shapes and bytes."""
    h = hashlib.blake2b(digest_size=16)
    for name in sorted(arrays):
        value = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{value.dtype.str}|{value.shape}|".encode())
        h.update(value.tobytes())
    return h.hexdigest()


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _save_arrays(f, arrays: dict[str, np.ndarray]) -> None:
    """Write the arrays of a chunk as .npz into the open file ``f`` (a hook of its own, where tests inject faults)."""
    np.savez(f, **arrays)


def _write_atomically(path: Path, write) -> None:
    """write(file object) into ``path`` via a temporary name, fsync'ed, then renamed into place; the temporary file is
    removed if anything fails."""
    tmp = path.with_name(path.name + ".tmp")
    try:
        with open(tmp, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        remove_quietly([tmp])
        raise
    _fsync_dir(path.parent)


def _warn(message: str) -> None:
    warnings.warn(message, JournalWarning, stacklevel=3)


def _move_aside(path: Path, folder: Path) -> Path:
    """Move ``path`` (a file or a folder) into ``folder`` under a name not taken yet; returns its new path."""
    folder.mkdir(parents=True, exist_ok=True)
    target, n = folder / path.name, 0
    while target.exists():
        n += 1
        target = folder / f"{path.name}.{n}"
    shutil.move(str(path), str(target))
    return target


class Journal(Writer):
    """The finished chunks of one run (module docstring), a writer of the chunk loop (sweep/write/writer.py) that
    keeps what it holds across runs. Use :meth:`open`.

    ``ranges[i]`` = (first point, last point + 1) of chunk i: the run's chunk layout (sweep.run.runner.chunk_ranges)."""

    def __init__(self, output: Path, identity: dict[str, object], ranges: list[tuple[int, int]]) -> None:
        self.output, self.path, self.identity, self.ranges = output, journal_path(output), identity, ranges
        self.run_id = hashlib.blake2b(json.dumps(identity, sort_keys=True).encode(), digest_size=16).hexdigest()
        self._done: set[int] = set()

    @classmethod
    def open(cls, output: str | os.PathLike, identity: dict[str, object], ranges: list[tuple[int, int]],
             resume: bool = False, overwrite: bool = False) -> Journal:
        """Start the journal of ``output``, or with ``resume`` continue an existing one of the same run after checking
        every file in it (module docstring). ``identity``: JSON-serialisable, compared key by key; ``overwrite``
        (without ``resume``): delete an existing journal instead of refusing. Raises :class:`InputError` (one line)
        for a journal that this call may not use."""
        journal = cls(Path(output), {**identity, "format": FORMAT, "n_chunks": len(ranges)}, ranges)
        path = journal.path
        if path.exists() and not path.is_dir():
            raise InputError(f"{path}, where the journal of {output} goes, is a file: move it away")
        if path.is_dir() and not resume:
            journal._refuse_or_discard(overwrite)
        if path.is_dir():  # resume
            if journal._check_manifest():
                journal._check_files()
                return journal
        path.mkdir(parents=True, exist_ok=True)
        try:
            _write_atomically(path / MANIFEST, lambda f: f.write(json.dumps(journal.identity, indent=1).encode()))
        except OSError as exc:
            raise write_failed(exc, path / MANIFEST) from None
        return journal

    def _refuse_or_discard(self, overwrite: bool) -> None:
        """A run without resume: delete the journal found (``overwrite``, or nothing in it but a manifest), else
        refuse."""
        files = [p for p in self.path.iterdir() if not TEMPORARY.fullmatch(p.name)]
        if overwrite or [p.name for p in files] in ([], [MANIFEST]):
            shutil.rmtree(self.path)
            return
        if self._read_manifest()[0] is None:
            raise InputError(f"{self.path} holds {len(files)} file(s) but no readable {MANIFEST}, so they cannot be "
                             f"checked: start over with --overwrite (overwrite=True), which deletes them, or --resume "
                             f"(resume=True), which moves them to {rejected_path(self.output)} first")
        chunks = sum(bool(CHUNK.fullmatch(p.name)) for p in files)
        raise InputError(f"{self.path} holds {chunks} chunk(s) of an earlier run that did not finish: continue it with "
                         f"--resume (resume=True), or start over with --overwrite (overwrite=True), which deletes them")

    def _read_manifest(self) -> tuple[dict | None, str | None]:
        """(the saved identity, None), or (None, why it cannot be read)."""
        manifest = self.path / MANIFEST
        try:
            saved = json.loads(manifest.read_text())
        except FileNotFoundError:
            return None, "is missing"
        except (OSError, ValueError) as exc:
            empty = manifest.is_file() and manifest.stat().st_size == 0
            return None, "is empty" if empty else f"is unreadable ({type(exc).__name__})"
        return (saved, None) if isinstance(saved, dict) else (None, "is not a JSON object")

    def _check_manifest(self) -> bool:
        """Resuming: True if the manifest is this run's; a journal without a readable manifest is moved aside whole
        (False: start afresh); InputError for the manifest of another run."""
        saved, why = self._read_manifest()
        if saved is None:
            moved = _move_aside(self.path, rejected_path(self.output))
            _warn(f"{self.path / MANIFEST} {why}: nothing in {self.path} can be attributed to this run; moved it to "
                  f"{moved}, computing every chunk afresh")
            return False
        differ = sorted(k for k in set(saved) | set(self.identity) if saved.get(k) != self.identity.get(k))
        if differ:
            raise InputError(f"cannot resume from {self.path}: the run there differs in {', '.join(differ)} (the "
                             f"scene, plan, chunking or version of sweep changed); start over with --overwrite "
                             f"(overwrite=True), which deletes that journal")
        return True

    def _check_files(self) -> None:
        """Resuming: check every file of the journal before any computation (module docstring)."""
        for path in sorted(self.path.iterdir()):
            if path.name == MANIFEST:
                continue
            if TEMPORARY.fullmatch(path.name):
                path.unlink(missing_ok=True)  # a write killed before its rename: never whole
                continue
            match = CHUNK.fullmatch(path.name)
            if match is None:
                self._reject(path, "is not a file of a sweep journal")
                continue
            index = int(match.group(1))
            if index >= len(self.ranges):
                self._reject(path, f"is not a chunk of this run (it has chunks 0..{len(self.ranges) - 1})")
                continue
            why = self._verify(path, index)[1]
            if why is None:
                self._done.add(index)
            else:
                self._reject(path, why, f"chunk {index} will be computed again")

    def _reject(self, path: Path, why: str, then: str = "") -> None:
        """Move a file refused from the journal aside, with one line that names it and says why."""
        moved = _move_aside(path, rejected_path(self.output))
        _warn(f"{path} {why}: moved to {moved}" + (f"; {then}" if then else ""))

    def _verify(self, path: Path, index: int) -> tuple[dict[str, np.ndarray] | None, str | None]:
        """(arrays, None) of a chunk file that is chunk ``index`` of this run, whole; else (None, why not)."""
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {name: data[name] for name in data.files}
        except Exception as exc:  # noqa: BLE001 (truncated or flipped: BadZipFile, EOFError, zlib.error, ValueError...)
            return None, f"is unreadable ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
        try:
            record = json.loads(str(arrays.pop(JOURNAL_RECORD)))
        except (KeyError, ValueError):
            return None, "has no journal record (not written by this version of sweep)"
        start, stop = self.ranges[index]
        if record.get("run") != self.run_id:
            same_plan = record.get("plan_hash") == self.identity.get("plan_hash")
            return None, ("belongs to another run" + ("" if same_plan else f" (plan hash {record.get('plan_hash')}, "
                                                      f"this run's {self.identity.get('plan_hash')})"))
        if record.get("index") != index:
            return None, f"holds chunk {record.get('index')}, not chunk {index}"
        if record.get("range") != [start, stop]:
            return None, f"covers points {record.get('range')}, not those of chunk {index} ({[start, stop]})"
        if record.get("checksum") != checksum(arrays) or any(np.ndim(v) and len(v) != stop - start
                                                             for v in arrays.values()):
            return None, "does not match its checksum (damaged)"
        return arrays, None

    def _chunk(self, index: int) -> Path:
        return self.path / f"chunk-{index:06d}.npz"

    def done(self) -> set[int]:
        """Indices of the chunks checked or written by this run."""
        return set(self._done)

    def write(self, index: int, arrays: dict[str, np.ndarray]) -> None:
        """Store chunk ``index`` with its record (crash-safe: the file appears whole or not at all); a failed write
        is an :class:`OutputError` that says the finished chunks are kept."""
        start, stop = self.ranges[index]
        record = {"run": self.run_id, "plan_hash": self.identity.get("plan_hash"), "index": index,
                  "range": [start, stop], "checksum": checksum(arrays)}
        payload = {**arrays, JOURNAL_RECORD: np.array(json.dumps(record))}
        try:
            _write_atomically(self._chunk(index), lambda f: _save_arrays(f, payload))
        except OSError as exc:
            raise write_failed(exc, self._chunk(index), self.path, len(self._done)) from None
        self._done.add(index)

    def start(self, layout: tuple[np.ndarray, ...]) -> None:  # chunks written in a helper thread (background)
        self.layout = layout
        self._writing = contextlib.ExitStack()
        self._keep = self._writing.enter_context(self.background())

    def put(self, index: int, arrays: dict[str, np.ndarray]) -> None:
        self._keep(index, {name: value for name, value in arrays.items() if isinstance(value, np.ndarray)})

    def close(self) -> None:
        self._writing.close()

    def abort(self, error: BaseException) -> None:
        self._writing.__exit__(type(error), error, error.__traceback__)

    def resume_hint(self, n_chunks: int) -> str | None:
        return (f"interrupted: {len(self.done())} of {n_chunks} chunks are saved in {self.path}; run the same command "
                f"with --resume (run_sweep(..., resume=True)) to compute only the rest")

    @contextlib.contextmanager
    def background(self) -> Iterator[Callable[[int, dict[str, np.ndarray]], None]]:
        """``with journal.background() as keep: keep(index, arrays)``: :meth:`write` in one helper thread
        (sweep.write.writer.Behind), chunks written in the order handed over (module docstring). A failed write is
        raised (its :class:`OutputError`) by the next ``keep`` or when the block ends, and no chunk is written after
        it; the block's end waits for every chunk handed over. ``arrays`` may not change after the call, the dict
        itself may (the caller's ``seconds`` is popped while the chunk is written: the chunk keeps it)."""
        behind = Behind("sweep-journal", PENDING_CHUNKS)
        try:
            yield lambda index, arrays: behind.submit(self.write, index, dict(arrays))
        except BaseException:
            behind.close(raise_errors=False)  # the chunks computed are kept; the block's own error is the one raised
            raise
        behind.close()

    def read(self, index: int) -> dict[str, np.ndarray]:
        """The arrays of chunk ``index``, checked against its record; a chunk that changed on disk since it was
        checked is moved aside and is an :class:`OutputError` (never consolidated)."""
        arrays, why = self._verify(self._chunk(index), index)
        if why is not None:
            self._done.discard(index)
            moved = _move_aside(self._chunk(index), rejected_path(self.output))
            raise OutputError(f"{self._chunk(index)} {why} (it changed on disk during the run): moved to {moved}; run "
                              f"the same command with --resume (resume=True) to compute it again")
        return arrays

    def remove(self) -> None:
        """Delete the journal (after the consolidated file is safely in place)."""
        shutil.rmtree(self.path, ignore_errors=True)
