"""One run per output: a lock file ``<output>.lock`` held while a run writes its journal and its file.

The lock records who holds it (pid, host, the process's start time, when the run started, its command line). It is
created whole or not at all (written under a temporary name, then hard-linked to the lock's name, which fails if
the lock exists), so that a second run never reads a half-written lock. A second run on the same output is refused
with a message naming the run that holds it. A lock whose process is gone (same host, the pid not running, or
running but started at another time: a pid reused after a reboot or a SIGKILL) is stale: removed with one line,
and the run goes on. A lock of another host cannot be checked from here: the message says to remove it by hand if
that run is gone.
"""

from __future__ import annotations

import json
import os
import socket
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import InputError
from ..log import LOGGER

__all__ = ["lock_path", "output_lock"]


def lock_path(output: str | os.PathLike) -> Path:
    """The lock file of an output file."""
    output = Path(output)
    return output.with_name(output.name + ".lock")


def _process_start(pid: int) -> str | None:
    """The start time of process ``pid`` in clock ticks since boot (Linux /proc), None where unknown: with the pid it
    identifies a process, which a pid alone does not once pids are reused."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return stat.rsplit(")", 1)[1].split()[19]  # field 22 (starttime), counted after the command name


def _running(pid: int, started: str | None) -> bool:
    """Whether the process that wrote a lock of this host still runs."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process: it exists
        pass
    now = _process_start(pid)
    return started is None or now is None or now == started


def _read(path: Path) -> dict | None:
    try:
        holder = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return holder if isinstance(holder, dict) else None


def _describe(holder: dict | None) -> str:
    if holder is None:
        return "an unknown run (the lock is unreadable)"
    return (f"pid {holder.get('pid')} on host {holder.get('host')}, started {holder.get('started')}"
            + (f": {holder['command']}" if holder.get("command") else ""))


def _stale(holder: dict | None) -> bool:
    """A lock whose run is certainly gone: written on this host by a process that no longer runs."""
    if holder is None or holder.get("host") != socket.gethostname():
        return False
    try:
        pid = int(holder["pid"])
    except (KeyError, TypeError, ValueError):
        return False
    return not _running(pid, holder.get("process_start"))


def _create(path: Path, text: str) -> bool:
    """Create ``path`` holding ``text``, whole or not at all; False if it exists already."""
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    try:
        os.link(tmp, path)
        return True
    except FileExistsError:
        return False
    except OSError:  # a file system without hard links: exclusive creation (a reader may see it empty for a moment)
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            return False
        with os.fdopen(fd, "w") as f:
            f.write(text)
        return True
    finally:
        tmp.unlink(missing_ok=True)


@contextmanager
def output_lock(output: str | os.PathLike) -> Iterator[Path]:
    """Hold the lock of ``output`` for the duration of the ``with`` block (module docstring): InputError if another
    run holds it; a stale lock is removed with one line on the ``sweep`` logger."""
    path = lock_path(output)
    path.parent.mkdir(parents=True, exist_ok=True)  # the output's folder, as its writer would create it
    me = {"pid": os.getpid(), "host": socket.gethostname(), "process_start": _process_start(os.getpid()),
          "started": time.strftime("%Y-%m-%d %H:%M:%S %z"), "command": " ".join(sys.argv)}
    text = json.dumps(me, indent=1)
    for _ in range(3):  # a stale lock removed, then taken; another run may win that race
        if _create(path, text):
            break
        holder = _read(path)
        if not _stale(holder):
            raise InputError(f"{output} is being written by another run ({_describe(holder)}; lock {path}): wait for "
                             f"it to finish, or if that run is gone, delete {path}")
        LOGGER.warning(f"removed the stale lock {path} of a run that is gone ({_describe(holder)})")
        path.unlink(missing_ok=True)
    else:
        raise InputError(f"could not take the lock {path} of {output}: other runs keep taking it")
    try:
        yield path
    finally:
        if _read(path) == me:  # still ours (never remove a lock another run took after ours was judged stale)
            path.unlink(missing_ok=True)
