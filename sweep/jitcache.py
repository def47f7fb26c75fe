"""Stable identities for numba dispatchers, so that kernels built by factories load from numba's disk cache.

numba keys a cached closure by a pickle of its closure cells; a cell holding another dispatcher pickles that
dispatcher's instance UUID, a fresh random one in every process. Kernels built by factories (one per float type
and tableau: integrate/lanes.py, models/stop.py, models/stop_stiff.py) therefore missed the cache in every new
process and recompiled (~8 s per process, and the cache index grew by one entry each time). :func:`pin` gives a
dispatcher (or intrinsic) a UUID derived from its module, qualified name and variant instead, so the pickle, and
the cache key, are the same in every process (the fastmath options are dicts, not sets, for the same reason:
models/stop.py FAST).

The UUID also carries a digest of the package's sources (:func:`source_digest`). numba keeps a cached kernel as long
as the file that defines it is unchanged, and a closure's key holds only the identities of the dispatchers it calls;
a kernel built by a factory and compiled into another module's loop (the lanes' relax_runs into
integrate/batch.py's lanes_batch) would otherwise load from the cache with the code of an older version of its
factory's module whenever that module changed and batch.py did not. Seen once, in a development tree, after edits
of the lanes' state-array layout: a sweep failed with a corrupted heap, and did not with an empty cache (a stale
lanes_batch writing past the new, smaller state array is the likely cause). With the digest every edit of the
package gives its factory-built kernels new keys.

numba's cache files are also serialised between processes here (:func:`serialise_cache_files`, applied on import):
numba saves a compiled overload by reading the function's index, picking the first free data-file number and
writing the index back, with no lock. Two processes that save different overloads of one function at once (a
factory's variants, compiled side by side: the cold first run's helper process, sweeps started together on a
cold cache) can both pick data file 1: the index then names one overload's key and the file holds the other's code,
which a later process loads as if it were the first (seen once: a fresh-clone test run aborted in LLVM while
loading the driven kernel from its cache, and passed from the same cache files afterwards).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import sys
from pathlib import Path

from numba.core import event
from numba.core.dispatcher import Dispatcher
from numba.core.extending import _Intrinsic

__all__ = ["compiling", "pin", "pin_module", "serialise_cache_files", "source_digest"]


class _CompileDepth(event.Listener):
    """Counts the numba compilations in progress in this process (nested ones included)."""

    depth = 0

    def on_start(self, ev: event.Event) -> None:
        self.depth += 1

    def on_end(self, ev: event.Event) -> None:
        self.depth -= 1


_COMPILE_DEPTH = _CompileDepth()
event.register("numba:compile", _COMPILE_DEPTH)


def compiling() -> bool:
    """Whether numba is compiling a function in this process now. A KeyboardInterrupt raised then can land in a
    callback of LLVM's code generation, where it is printed and lost, and the compilation fails later with an
    unrelated RuntimeError ("no compiled object yet"); the command line ends the process at once instead
    (sweep/cli.py)."""
    return _COMPILE_DEPTH.depth > 0


@functools.cache
def source_digest(root: Path = Path(__file__).parent) -> str:
    """16 hex digits of a SHA-256 over the names and contents of every .py file under ``root`` (default: the sweep
    package), in sorted order (a few ms, once per process)."""
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:16]


def pin(dispatcher: Dispatcher | _Intrinsic, *variant: object) -> Dispatcher | _Intrinsic:
    """Set a stable UUID "sweep:<source digest>:<module>.<qualname>[:variant...]" on a dispatcher or intrinsic (no-op
    if it has one)."""
    func = dispatcher.py_func if isinstance(dispatcher, Dispatcher) else dispatcher._defn
    name = ":".join(["sweep", source_digest(), f"{func.__module__}.{func.__qualname__}", *map(str, variant)])
    try:
        dispatcher._set_uuid(name)
    except AssertionError:  # already identified (e.g. pickled before): keep it
        pass
    return dispatcher


def pin_module(name: str) -> None:
    """:func:`pin` every dispatcher and intrinsic defined at the top level of the module ``name`` (call it at the
    module's end as ``pin_module(__name__)``)."""
    for value in vars(sys.modules[name]).values():
        if isinstance(value, Dispatcher) and value.py_func.__module__ == name:
            pin(value)
        elif isinstance(value, _Intrinsic) and value._defn.__module__ == name:
            pin(value)


CACHE_LOCK = ".sweep-numba-cache.lock"
"""The lock file :func:`serialise_cache_files` takes, one per cache folder."""


def serialise_cache_files() -> None:
    """Make numba's save of a cached overload (read the index, pick a data file, write both) exclusive, and its
    load shared, under an flock of the cache folder's CACHE_LOCK, in every process that imports sweep (module
    docstring). Where flock is missing (not POSIX) or fails (a file system without locks), or the folder is not
    writable (numba then saves nothing there), numba's own behaviour stands."""
    try:
        import fcntl

        from numba.core.caching import IndexDataCacheFile
    except ImportError:
        return
    if getattr(IndexDataCacheFile, "_sweep_serialised", False):
        return
    save, load = IndexDataCacheFile.save, IndexDataCacheFile.load

    @contextlib.contextmanager
    def locked(cache_file, kind):
        try:
            fd = os.open(os.path.join(cache_file._cache_path, CACHE_LOCK), os.O_RDWR | os.O_CREAT, 0o666)
        except OSError:
            yield
            return
        try:
            with contextlib.suppress(OSError):  # a file system without locks (some network mounts): as numba does
                fcntl.flock(fd, kind)
            yield
        finally:
            os.close(fd)  # (releases the lock)

    def locked_save(self, key, data):
        with locked(self, fcntl.LOCK_EX):
            return save(self, key, data)

    def locked_load(self, key):
        with locked(self, fcntl.LOCK_SH):
            return load(self, key)

    IndexDataCacheFile.save, IndexDataCacheFile.load = locked_save, locked_load
    IndexDataCacheFile._sweep_serialised = True


serialise_cache_files()
