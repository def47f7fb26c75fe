"""Say so before numba compiles sweep's kernels: on a machine whose numba cache holds none of them, the first run
compiles for 5-45 s per kernel family, with nothing else to show for it.

:func:`announce_if_cold` logs one INFO line (logger ``sweep``) at once when numba's on-disk cache holds no index
file (``*.nbi``) of the package, checked once per process, with the seconds of the kernel families the scene
needs (:func:`kernel_families`: its protocol's); :func:`timed` wraps an explicit warm-up and logs a line if it is
still running after :data:`SLOW_S` (a cache that holds some kernels but not the ones a scene needs), then how long
it took. :data:`COLD_COMPILE_S` holds each family's compile time, measured alone in a new process with an empty
cache (NUMBA_CACHE_DIR set to an empty folder) on the 2-core development machine and rounded up: the relaxed-slip
engine (the adaptive lanes' ``relax_runs`` with the first-order inertial correction of model "auto", ~9-12 s, and
the tolerance ladder's and the model choice's small kernels) ~11 s of CPU, the sampled lanes of the time-resolved
path ~22 s, the longest family (benchmarks/cold_start.py times a whole cold default run). Loading every family from
the cache takes ~1.5 s. :func:`compiled_aside` compiles a family in a second process beside this one
(the inertial stop before a dask fan-out, the fit's per-point path).
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from .. import protocols
from ..log import LOGGER

__all__ = ["COLD_COMPILE_S", "HELPER_WAIT_S", "SLOW_S", "announce_if_cold", "cache_is_cold", "compiled_aside",
           "driven_families", "inertial_stop_compiled_aside", "kernel_families", "timed"]


COLD_COMPILE_S = {"relaxed-slip engine": 12, "time-resolved stop": 18, "time-resolved lanes": 25, "inertial stop": 18,
                  "slip-law stop": 6, "driven quasi-static": 27, "driven inertial": 40}
"""Seconds to compile each kernel family from an empty cache on the 2-core development machine (module docstring)."""
SLOW_S = 3.0
"""A warm-up still running after this many seconds is compiling, not loading: say so."""
HELPER_WAIT_S = 300.0
"""At most this long a block of :func:`compiled_aside` waits for its helper once it is done itself (a family compiles
in ~20-45 s on 2 cores): a helper stuck for any reason is killed, and this process compiles what it still needs."""
PACKAGE = Path(__file__).resolve().parents[1]
"""The package's folder (numba keeps its cache in the __pycache__ folders below it)."""
_checked = False
_compiling_announced = False


def cache_is_cold() -> bool:
    """True when numba's on-disk cache holds no index file (``*.nbi``) of the package yet, so that the next kernel
    call compiles. numba keeps the cache in NUMBA_CACHE_DIR where that is set, else beside the sources
    (``__pycache__``), else (package folder not writable) in the user-wide ~/.cache/numba, under the sources' path."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return not _has_index(Path(os.environ["NUMBA_CACHE_DIR"]))
    user_wide = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "numba"
    return not (any(_has_index(d) for d in PACKAGE.rglob("__pycache__"))
                or _has_index(user_wide, must_contain=PACKAGE.name))


def _has_index(folder: Path, must_contain: str = "") -> bool:
    """Whether ``folder`` holds a numba index file (anywhere below it, in a path containing ``must_contain``)."""
    return folder.is_dir() and any(must_contain in str(p) for p in folder.rglob("*.nbi"))


def kernel_families(scene=None) -> list[str]:
    """The kernel families (keys of :data:`COLD_COMPILE_S`) a scene compiles on first use (its protocol's
    Protocol.kernel_families; the simulated Hopf line adds the driven variant of the scene's model); every family
    without a scene."""
    if scene is None:
        return list(COLD_COMPILE_S)
    families = protocols.get(scene.protocol).kernel_families(scene)
    if scene.simulated_hopf_line:
        families += [f for f in driven_families(scene.model) if f not in families]
    return families


def driven_families(model: str) -> list[str]:
    """The driven kernel's variants a driven scene or a Hopf line of ``model`` compiles."""
    return [f"driven {m}" for m, used in (("quasi-static", model != "inertial"), ("inertial", model != "quasistatic"))
            if used]


def _total(families: list[str]) -> int:
    return sum(COLD_COMPILE_S[f] for f in families)


def announce_if_cold(scene=None, families: list[str] | None = None) -> bool:
    """Log, once per process, that the kernels are about to be compiled, if numba's cache is empty, with the
    seconds it takes for ``families`` or those of ``scene`` (all families without either); True if it logged."""
    global _checked, _compiling_announced
    if _checked:
        return False
    _checked = True
    if not cache_is_cold():
        return False
    _compiling_announced = True
    families = families or kernel_families(scene)
    LOGGER.info("compiling numba kernels, first run on this machine only: up to ~%d s on 2 cores (%s); later runs "
                "load them from numba's cache in ~1.5 s", _total(families),
                ", ".join(f"{k} ~{COLD_COMPILE_S[k]} s" for k in families))
    return True


@contextmanager
def compiled_aside(code: str, wanted: bool = True) -> Iterator[None]:
    """On a cold cache (and where ``wanted``), run ``code`` (a warm-up that compiles one kernel family) in a second
    Python process while this one runs the block (and compiles the rest); on leaving, wait for it, so that this
    process then loads that family from numba's cache. Nothing happens where the cache is warm or the helper cannot
    start; a helper that fails only means this process compiles the family itself, as without it."""
    if not wanted or not cache_is_cold():
        yield
        return
    import subprocess
    import sys

    try:
        # run from the folder that holds this very package: "python -c" puts its working directory first on the
        # path, and started inside a source checkout beside an installed copy (the README's quick start) the helper
        # compiled the checkout's files, whose cache entries the installed package never finds (45 s instead of 20 s)
        helper = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                  cwd=PACKAGE.parent)
    except OSError:
        yield
        return
    try:
        yield
        helper.wait(timeout=HELPER_WAIT_S)
    except subprocess.TimeoutExpired:
        pass  # killed below; what the helper did not cache, this process compiles when it needs it
    finally:
        if helper.poll() is None:  # interrupted, failed or stuck: the helper's work is not needed any more
            helper.kill()


@contextmanager
def inertial_stop_compiled_aside(scene, wanted: bool = True) -> Iterator[None]:
    """:func:`compiled_aside` of the inertial stop kernels, where they are ``wanted`` beside another family of the
    scene (lanes ~6 s beside inertial ~13 s, on 2 cores)."""
    others = [family for family in kernel_families(scene) if family != "inertial stop"]  # compiled in this process
    with compiled_aside("from sweep.protocols.stop.model_choice import warm_up_models; warm_up_models()",
                        wanted and scene.model != "quasistatic" and bool(others)):
        yield


@contextmanager
def timed(what: str = "kernels") -> Iterator[None]:
    """Around a warm-up: :func:`announce_if_cold`, a line if it is still running after :data:`SLOW_S` (compiling),
    and at the end its duration (INFO if it compiled, else DEBUG)."""
    announce_if_cold()
    done = threading.Event()

    def notice() -> None:
        if not done.wait(SLOW_S) and not _compiling_announced:
            LOGGER.info("compiling %s not yet in numba's cache (first use only, up to ~%d s on 2 cores)", what,
                        _total(kernel_families()))

    t0 = time.perf_counter()
    thread = threading.Thread(target=notice, daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()
        seconds = time.perf_counter() - t0
        LOGGER.log(20 if seconds > SLOW_S else 10, "%s ready in %.1f s (%s)", what, seconds,
                   "compiled, now cached" if seconds > SLOW_S else "loaded from numba's cache")
