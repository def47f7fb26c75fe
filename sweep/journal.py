"""A crash-safe journal of finished chunks beside a sweep's output, so that an interrupted run loses nothing.

HDF5 (netCDF4) files are not safe to kill mid-write, so a running sweep writes no netCDF at all: each finished chunk
goes into ``<output>.journal/chunk-NNNNNN.npz``, written to a temporary name, flushed to disk (fsync) and renamed
into place (an atomic rename on POSIX). A SIGKILL at any moment therefore leaves whole chunks only, never a torn
one. ``manifest.json`` records the run's identity: the scene's canonical TOML, the plan hash and the chunk layout
(docs/design.md). A run given the same output resumes only if that identity is the same, computes the missing chunks,
and a single writer consolidates everything into the netCDF file, after which the journal is removed.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np

from .errors import InputError

__all__ = ["Journal", "journal_path"]

MANIFEST = "manifest.json"


def journal_path(output: str | os.PathLike) -> Path:
    """The journal directory of an output file."""
    output = Path(output)
    return output.with_name(output.name + ".journal")


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _write_atomically(path: Path, write) -> None:
    """write(file object) into ``path`` via a temporary name, fsync'ed, then renamed into place."""
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as f:
        write(f)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


class Journal:
    """The finished chunks of one run (module docstring). Use :meth:`open`."""

    def __init__(self, path: Path, identity: dict[str, object]) -> None:
        self.path, self.identity = path, identity

    @classmethod
    def open(cls, output: str | os.PathLike, identity: dict[str, object], resume: bool) -> Journal:
        """Start the journal of ``output``, or with ``resume`` continue an existing one after checking that it
        belongs to the same run (``identity``: JSON-serialisable; compared key by key)."""
        path = journal_path(output)
        if (path / MANIFEST).is_file() and not resume and not any(path.glob("chunk-*.npz")):
            shutil.rmtree(path)  # a run stopped before its first chunk (e.g. Ctrl-C while compiling): nothing to lose
        if (path / MANIFEST).is_file():
            if not resume:
                raise InputError(f"{path} holds the chunks of an interrupted run: resume it (sweep run ... --resume, "
                                 f"run_sweep(..., resume=True)) or delete that directory to start afresh")
            saved = json.loads((path / MANIFEST).read_text())
            differ = sorted(k for k in set(saved) | set(identity) if saved.get(k) != identity.get(k))
            if differ:
                raise InputError(f"cannot resume from {path}: the run there differs in {', '.join(differ)} (the scene "
                                 f"or plan changed); delete that directory to start afresh")
            return cls(path, identity)
        path.mkdir(parents=True, exist_ok=True)
        _write_atomically(path / MANIFEST, lambda f: f.write(json.dumps(identity, indent=1).encode()))
        return cls(path, identity)

    def _chunk(self, index: int) -> Path:
        return self.path / f"chunk-{index:06d}.npz"

    def done(self) -> set[int]:
        """Indices of the chunks already written (whole files only: temporaries are ignored)."""
        return {int(p.stem.split("-")[1]) for p in self.path.glob("chunk-*.npz")}

    def write(self, index: int, arrays: dict[str, np.ndarray]) -> None:
        """Store chunk ``index`` (crash-safe: the file appears whole or not at all)."""
        _write_atomically(self._chunk(index), lambda f: np.savez(f, **arrays))

    def read(self, index: int) -> dict[str, np.ndarray]:
        with np.load(self._chunk(index)) as data:
            return {name: data[name] for name in data.files}

    def remove(self) -> None:
        """Delete the journal (after the consolidated file is safely in place)."""
        shutil.rmtree(self.path, ignore_errors=True)
