"""Fault injection for the integrity tests (tests/run/test_integrity.py): damage a journal on disk, or make a run's
writes fail the way a full disk, a read-only folder or a folder put in the way make them fail.

In this process: :func:`interrupt_after` (a journaled run stopped by Ctrl-C after some chunks, as a killed run
leaves it), :func:`truncate`, :func:`flip_byte`, :func:`writes_blocked_by_chmod`.

In a ``sweep`` command run as a subprocess (exit code, stderr, files on disk, as a user sees them)::

    python tests/faults.py --fault enospc-chunk:3 -- run scene.toml -o out.nc

installs the faults, then runs ``sweep.cli.main`` on the arguments after ``--`` and exits with its code:

* ``enospc-chunk:N`` / ``eacces-chunk:N``: the journal's chunk writes after the first N fail with
  OSError(ENOSPC) / PermissionError(EACCES), after writing part of their temporary file;
* ``enospc-netcdf``: the netCDF file's block writes fail with OSError(ENOSPC) after three blocks;
* ``eacces-dir:DIR``: creating a file or folder under DIR fails with PermissionError(EACCES), as in a read-only
  folder (for tests run as root, where chmod stops nothing);
* ``mkdir-output:PATH``: a folder appears at PATH just before the netCDF file is renamed there;
* ``kill-after-region:N``: the process SIGKILLs itself right after its N-th chunk reached the netCDF ``.part``, the
  journal storing a chunk only after the file has it;
* ``trace-chunks``: each chunk computed prints ``fault: computing a chunk`` on stderr (to check that something
  happened before any computation).
"""

from __future__ import annotations

import builtins
import errno
import os
import sys
from pathlib import Path

FAULTS = ("enospc-chunk", "eacces-chunk", "enospc-netcdf", "eacces-dir", "mkdir-output", "trace-chunks",
          "kill-after-region")
TRACE = "fault: computing a chunk"


# --- in this process --------------------------------------------------------------------------------------------

def interrupt_after(monkeypatch, chunks: int) -> list[int]:
    """Make the next stop runs raise KeyboardInterrupt when chunk number ``chunks`` + 1 starts (the journal then holds
    ``chunks`` chunks, as a run killed at that moment leaves it); undo with ``monkeypatch.undo()``. Returns the list
    the sizes of the chunks computed before the interrupt go into."""
    import sweep.protocols.stop.chunk as stop_chunks

    real, sizes = stop_chunks.stop_chunk, []

    def stopped(scene, plan, progress=False):
        compute = real(scene, plan, progress)

        def counted(points):
            if len(sizes) == chunks:
                raise KeyboardInterrupt
            sizes.append(points.size)
            return compute(points)
        return counted

    monkeypatch.setattr(stop_chunks, "stop_chunk", stopped)
    return sizes


def trace_chunks(monkeypatch) -> None:
    """Print :data:`TRACE` on stderr before each chunk of a stop run is computed (the ``trace-chunks`` fault of a
    command, in this process)."""
    import sweep.protocols.stop.chunk as stop_chunks

    monkeypatch.setattr(stop_chunks, "stop_chunk",
                        _wrapped(stop_chunks.stop_chunk, lambda: sys.stderr.write(TRACE + "\n")))


def truncate(path: Path, keep: float = 0.5) -> None:
    """Cut ``path`` to ``keep`` of its length (a file torn by a crash without the journal's atomic rename)."""
    data = path.read_bytes()
    path.write_bytes(data[:int(len(data) * keep)])


def flip_byte(path: Path, at: float = 0.6) -> None:
    """Flip the bits of one byte of ``path``, at ``at`` of its length (silent corruption on disk)."""
    data = bytearray(path.read_bytes())
    data[int(len(data) * at)] ^= 0xFF
    path.write_bytes(bytes(data))


def writes_blocked_by_chmod(folder: Path) -> bool:
    """chmod ``folder`` read-only and say whether that stops a new file there (not for root, where a test must inject
    EACCES instead: ``eacces-dir``)."""
    folder.chmod(0o555)
    probe = folder / ".probe"
    try:
        probe.write_text("x")
    except PermissionError:
        return True
    probe.unlink()
    return False


# --- in a sweep command -----------------------------------------------------------------------------------------

def _error(code: int, path) -> OSError:
    return OSError(code, os.strerror(code), str(path)) if code != errno.EACCES else PermissionError(
        code, os.strerror(code), str(path))


def _failing_chunk_writes(code: int, after: int) -> None:
    import sweep.run.journal as journal

    real, calls = journal._save_arrays, [0]

    def save(f, arrays):
        calls[0] += 1
        if calls[0] > after:
            f.write(b"PK\x03\x04 partial chunk")  # a torn temporary file, which the journal must remove
            raise _error(code, f.name)
        real(f, arrays)

    journal._save_arrays = save


def _failing_netcdf(after: int = 3) -> None:
    """The netCDF file's block writes fail with ENOSPC after ``after`` blocks (its .part then holds a partial file)."""
    from sweep.write.netcdf import NetCDFRegions

    real, calls = NetCDFRegions.put, [0]

    def put(self, block):
        calls[0] += 1
        if calls[0] > after:
            raise _error(errno.ENOSPC, self.part)
        return real(self, block)

    NetCDFRegions.put = put


def _read_only(folder: Path) -> None:
    """Creating anything under ``folder`` raises PermissionError(EACCES), reading works."""
    folder = folder.resolve()
    inside = lambda path: Path(os.path.abspath(os.fspath(path))).is_relative_to(folder)  # noqa: E731
    real_open, real_os_open, real_mkdir = builtins.open, os.open, os.mkdir

    def guarded_open(file, mode="r", *args, **kwargs):
        if isinstance(file, (str, os.PathLike)) and any(c in mode for c in "wax+") and inside(file):
            raise _error(errno.EACCES, file)
        return real_open(file, mode, *args, **kwargs)

    def guarded_os_open(path, flags, *args, **kwargs):
        if flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT) and inside(path):
            raise _error(errno.EACCES, path)
        return real_os_open(path, flags, *args, **kwargs)

    def guarded_mkdir(path, *args, **kwargs):
        if inside(path):
            raise _error(errno.EACCES, path)
        return real_mkdir(path, *args, **kwargs)

    builtins.open, os.open, os.mkdir = guarded_open, guarded_os_open, guarded_mkdir


def _folder_in_the_way(path: Path) -> None:
    """A folder appears where the file goes while the run computes (its rename into place then fails)."""
    from sweep.write.netcdf import NetCDFRegions

    real = NetCDFRegions.close

    def close(self, attrs):
        Path(path).mkdir(parents=True, exist_ok=True)
        return real(self, attrs)

    NetCDFRegions.close = close


def _killed_after_region(count: int) -> None:
    """The process SIGKILLs itself right after its ``count``-th chunk reached the netCDF ``.part``; the journal
    stores a chunk only once the file has it, so that chunk is in the file and not in the journal."""
    import signal
    import time

    from sweep.run.journal import Journal
    from sweep.write.regions import Regions

    real_store, real_write, stored = Regions._store, Journal.write, set()

    def store(self, index, arrays):
        real_store(self, index, arrays)
        if len(stored) + 1 == count:
            self.sinks[-1].nc.sync()  # the region on disk, its chunk not in the journal
            os.kill(os.getpid(), signal.SIGKILL)
        stored.add(index)

    def write(self, index, arrays):
        t0 = time.monotonic()
        while index not in stored and time.monotonic() - t0 < 30:
            time.sleep(0.005)
        return real_write(self, index, arrays)

    Regions._store, Journal.write = store, write


def _wrapped(stop_chunk, action):
    """``stop_chunk`` (sweep.run.runner) calling ``action()`` before each chunk it computes."""
    def wrapped(scene, plan, progress=False):
        compute = stop_chunk(scene, plan, progress)

        def run(points):
            action()
            return compute(points)
        return run

    return wrapped


def _before_each_chunk(action) -> None:
    import sweep.protocols.stop.chunk as stop_chunks

    stop_chunks.stop_chunk = _wrapped(stop_chunks.stop_chunk, action)


def install(spec: str) -> None:
    """Install one fault ``name[:argument]`` (module docstring)."""
    name, _, arg = spec.partition(":")
    if name not in FAULTS:
        raise SystemExit(f"faults.py: unknown fault {name!r}; one of {FAULTS}")
    if name in ("enospc-chunk", "eacces-chunk"):
        _failing_chunk_writes(errno.ENOSPC if name == "enospc-chunk" else errno.EACCES, int(arg))
    elif name == "enospc-netcdf":
        _failing_netcdf()
    elif name == "eacces-dir":
        _read_only(Path(arg))
    elif name == "mkdir-output":
        _folder_in_the_way(Path(arg))
    elif name == "kill-after-region":
        _killed_after_region(int(arg))
    else:
        # one write a line: chunks computed side by side print from two threads at once
        _before_each_chunk(lambda: (sys.stderr.write(TRACE + "\n"), sys.stderr.flush()))


def command(faults: list[str], args: list[str]) -> list[str]:
    """The command line that runs ``sweep args`` with ``faults`` installed."""
    return [sys.executable, str(Path(__file__).resolve()), *[f"--fault={f}" for f in faults], "--", *args]


def main(argv: list[str]) -> int:
    split = argv.index("--")
    for spec in argv[:split]:
        install(spec.removeprefix("--fault="))
    from sweep.cli import main as sweep_main

    return sweep_main(argv[split + 1:])


if __name__ == "__main__":
    code = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # as sweep's entry point after Ctrl-C; here for every code, the faults may have patched open()
