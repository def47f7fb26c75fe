"""Where a command may write: every file it will write checked before any work, and a failed write during the run
turned into one line that says what to do.

Every writer (``sweep run``, ``sweep hopf``, ``sweep reproduce``, ``sweep plot``; ``run_sweep(..., output=)``,
``sweep.save`` and ``reproduce`` from Python) first calls :func:`check_targets` on all the files it will write, so
that nothing is computed for a run that could not keep its results and nothing is destroyed without a question:

* a target that is a folder, or equal to one of the command's inputs (``sweep run s.toml -o s.toml``), or to another
  of its targets (``-o out.png``: the picture over the data), is refused;
* an existing target is replaced only with ``overwrite`` (``--overwrite``);
* the target's folder (or, where it does not exist yet, its nearest existing parent, where it will be created) must
  accept a new file: a probe file is created and removed, which also catches a read-only file system where
  ``os.access`` says yes (as for root);
* the folder's file system must have the free space the run needs (its estimate, sweep/run/size.py).

An ``OSError`` during the run (disk full, permission denied, a folder put in the way) becomes an
:class:`~sweep.errors.OutputError` through :func:`write_failed`: one line naming the file, the cause and the fix, and,
for a journaled run, that its finished chunks are kept for ``--resume``.
"""

from __future__ import annotations

import errno
import os
import shutil
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

from .. import protocols
from ..errors import InputError, OutputError

__all__ = ["check_targets", "free_bytes", "human_bytes", "picture_paths", "remove_quietly", "same_path",
           "write_failed"]

OVERWRITE_HINT = "add --overwrite to replace it (overwrite=True from Python), or choose another name"

FIXES = {errno.ENOSPC: "free some space on that disk", errno.EDQUOT: "free some of your disk quota",
         errno.EACCES: "make the folder writable", errno.EPERM: "make the folder writable",
         errno.EROFS: "use a writable file system", errno.EISDIR: "move the folder of that name out of the way",
         errno.ENOTDIR: "move the file that is in the way of the folder"}
"""What to do about a failed write, by errno."""


def human_bytes(n: float) -> str:
    """``n`` bytes as a short text: 512 B, 3.2 MB, 1.8 TB (powers of 1000)."""
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if abs(n) < 1000 or unit == "TB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.3g} {unit}"
        n /= 1000
    raise AssertionError("unreachable")


def same_path(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether two paths name the same file: the same file on disk (hard links, symlinks included) where both
    exist, else the same absolute path once resolved."""
    a, b = Path(a), Path(b)
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def check_targets(targets: Mapping[str, str | os.PathLike], overwrite: bool = False,
                  inputs: Mapping[str, str | os.PathLike] | None = None, need_bytes: int = 0) -> None:
    """:class:`InputError` (one line naming the file and what to do) unless every target may be written (module
    docstring). ``targets``: {what it is, e.g. "data" or "picture": path}; ``inputs``: {what it is: path} of the
    files the command reads; ``need_bytes``: the disk space the run needs in the folder of the first target."""
    seen: list[tuple[str, Path]] = []
    for what, path in targets.items():
        path = Path(path)
        if path.is_dir():
            raise InputError(f"the {what} output {path} is a folder: give a file name (e.g. {path / 'out.nc'})")
        for name, source in (inputs or {}).items():
            if source is not None and same_path(path, source):
                raise InputError(f"the {what} output {path} is the {name} the command reads: writing it would "
                                 f"destroy it; choose another output name")
        for other, earlier in seen:
            if same_path(path, earlier):
                raise InputError(f"the {what} output {path} is also the {other} output: the {what} would be written "
                                 f"over the {other}; give them different names (e.g. the data .nc, the picture --png "
                                 f"x.png)")
        seen.append((what, path))
    for _, path in seen:  # after the checks above: a collision is reported as such, not as an existing file
        if path.exists() and not overwrite:
            raise InputError(f"{path} exists: {OVERWRITE_HINT}")
    folders = dict.fromkeys(_writable_folder(path) for _, path in seen)  # each probed once, in order
    if seen and need_bytes > 0:
        check_free_space(next(iter(folders)), need_bytes, seen[0][1])


def existing_folder(path: str | os.PathLike) -> Path:
    """The folder that will receive ``path``: its parent, or the nearest existing ancestor where the parent is to be
    created."""
    existing = Path(path).parent if str(Path(path).parent) else Path(".")
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    return existing


def _writable_folder(path: Path) -> Path:
    """:func:`existing_folder` of ``path``, after checking that a file can be created there; InputError otherwise."""
    folder = path.parent if str(path.parent) else Path(".")
    existing = existing_folder(path)
    if not existing.is_dir():
        raise InputError(f"cannot create the folder {folder} of {path}: {existing} is a file")
    try:
        fd, probe = tempfile.mkstemp(dir=existing, prefix=".sweep-probe-")
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise InputError(f"cannot write in {existing} ({exc.strerror or exc}), where {path} goes: choose another "
                         "output folder or make it writable") from None
    return existing


def check_free_space(folder: Path, need_bytes: int, path: Path) -> None:
    """InputError where ``folder`` (the nearest existing folder of ``path``) has less than ``need_bytes`` free."""
    free = free_bytes(folder)
    if free < need_bytes:
        raise InputError(f"not enough free space for {path}: the run needs ~{human_bytes(need_bytes)} (estimated from "
                         f"the grid's shape: file and journal), {human_bytes(free)} free in {folder}; free some "
                         f"space or choose another output folder")


def free_bytes(folder: str | os.PathLike) -> int:
    """Free bytes for this user in the file system of ``folder``."""
    return shutil.disk_usage(folder).free


def picture_paths(path: str | os.PathLike, kind: str, trajectories: bool, points: int,
                  variable: str | None = None) -> list[Path]:
    """The pictures sweep.plot.files.plot_file writes for a file of ``kind`` (sweep.write.read.KINDS) with ``points``
    grid points (``trajectories``: it holds transients), so that a command checks them before any work: ``path``
    for a Hopf file, else what the file's protocol draws (Protocol.picture_paths)."""
    if kind not in protocols.CATALOGUE:
        return [Path(path)]
    return protocols.get(kind).picture_paths(path, trajectories, points, variable)


def write_failed(exc: BaseException, path: str | os.PathLike, journal: str | os.PathLike | None = None,
                 kept: int | None = None) -> OutputError:
    """The :class:`OutputError` of a write of ``path`` that failed with ``exc`` during a run (an OSError, or a netCDF
    library error): one line with the cause and the fix; with a ``journal``, that its ``kept`` finished chunks are
    kept for --resume."""
    code = getattr(exc, "errno", None)
    cause = getattr(exc, "strerror", None) or (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    fix = FIXES.get(code, "fix the cause")
    if journal is not None:
        chunks = "the finished chunks are" if kept is None else f"the {kept} finished chunks are"
        text = (f"could not write {path} ({cause}); {chunks} kept in {journal}: {fix}, then run the same command "
                f"with --resume (resume=True) to finish")
    else:
        text = f"could not write {path} ({cause}): {fix}, then run the command again"
    error = OutputError(text)
    error.errno = code
    return error


def remove_quietly(paths: Iterable[str | os.PathLike]) -> None:
    """Remove files left by a failed write (a temporary ``.part`` or ``.tmp``), ignoring those already gone."""
    for path in paths:
        try:
            os.unlink(path)
        except OSError:
            pass
