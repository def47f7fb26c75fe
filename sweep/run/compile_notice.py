"""Say so before numba compiles sweep's kernels: on a machine whose numba cache holds none of them, the first run
compiles for 5-30 s per kernel family, with nothing else to show for it.

:func:`announce_if_cold` logs one INFO line (logger ``sweep``) at once when numba's on-disk cache holds no index
file (``*.nbi``) of the package, checked once per process, with the seconds of the kernel families the scene
needs (:func:`kernel_families`); :func:`timed` wraps an explicit warm-up and logs a line if it is still running
after :data:`SLOW_S` (a cache that holds some kernels but not the ones a scene needs), then how long it took.
Measured on the 2-core development machine, each family alone in a new process with an empty cache
(NUMBA_CACHE_DIR set to an empty folder; a 3 x 3 scene of each kind, 2026-11-25, load average 0.5-1.1): relaxed
slip (lanes, rk4 and ros4) 5.6 s (6.4 s on the default grid, whose stiff corner uses ros4), time-resolved stop
(per-point path) 30 s, inertial stop 17 s, slip-law stop 5.5 s, driven quasi-static 7.4 s, driven inertial 16 s;
the default scene (relaxed slip + inertial stop) 22 s in all. Loading all of them from the cache takes ~1.5 s.
Re-measured once the inertial stop family also held the lanes that carry the first-order correction (model="auto",
2026-11-25, load 0.6): relaxed slip 7.8 s, inertial stop 17.7 s; a cold default `sweep run` 19.9 s in all; and
the time-resolved stop once each of its functions compiled once (no literal specialisations): 17.2 s (25.4 s before,
same conditions). Re-measured once relaxed slip ran in the adaptive dop853 lanes (model "auto" compiles only the
variant that carries the correction; 2026-11-25, load 2.5 from other work): relaxed slip (model "quasistatic") 14.6 s,
a cold default `sweep run` 17.4 s of kernels, 20.2 s in all; with the fine twin's steps written once in a loop of
their own (load 0.8): relaxed slip 11.9 s, a cold default `sweep run` 17.9 s of kernels (the inertial family,
compiled beside it, takes longest), 21.1 s in all. The sampled adaptive lanes (time-resolved, method "auto": the
"time-resolved lanes" family; 2026-11-26, load 2.6 from other work): 45-49 s for one point's first run (the
generated attempt alone 26 s, the relaxed lanes' 18 s in the same conditions), the relaxed lanes 13 s beside it.
A cold first sweep.fit (one curve, 2026-11-27, load ~1): 61 s with the sampled lanes and the per-point path compiled
one after the other, 38-44 s with the per-point path compiled aside (:func:`compiled_aside`, sweep.fit.core).
With the adaptive lanes' stage loops and their callees inlined into relax_runs (2026-11-27, load 0.9): relaxed slip
(model "quasistatic", 3 x 3) 19.5-21.0 s; a cold default `sweep run` 31.8-35.8 s of kernels.
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


COLD_COMPILE_S = {"relaxed-slip engine": 20, "time-resolved stop": 18, "time-resolved lanes": 45, "inertial stop": 18,
                  "slip-law stop": 6, "driven quasi-static": 8, "driven inertial": 16}
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
