"""The size of a run from its grid's shape alone, before any plan is made: a plan holds ~70 bytes a point, so a
1e5 x 1e5 grid could not even be planned (700 GB). Memory, disk and a rough time are known from the number of points,
the observables and the protocol; a run whose memory would exceed what the machine has available is refused with a
message that says how to split it.

The constants were measured on the 2-core development machine: the peak of ``run_sweep`` under
tracemalloc, as the slope between grids of 4e4 and 1.6e5 points (stop, relaxed slip: 163 bytes a point, with or
without an output; driven: 279; each sampled time held in memory, i.e. trajectory or slip_at without an output:
46 more, a journaled run keeping those in its journal instead); the file, from the bytes of its variables before
compression; the rates, from the default scene (benchmarks/scaling.py: 94,500 points/s on 2 threads at 1e6 points)
and the driven grid of benchmarks/hopf.py (3,220 points/s on one thread). They are rounded up: the check refuses
what would certainly not fit, it does not promise that the rest does.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from .. import protocols
from ..errors import InputError
from ..scene.scene import Scene
from ..write.targets import human_bytes

__all__ = ["RunSize", "available_memory", "check_fits", "estimate_size"]

MEMORY_PER_SAMPLE = 50
"""Peak bytes per point and sampled time held in memory (a run without an output file)."""
UNCHECKED_MEMORY = 32 * 2**20
"""Bytes of memory a run may need without a look at what the machine has (:func:`check_fits`): less than the
process's own imports took (numba, xarray: ~200 MB), and the look (/proc/meminfo, the control group's files) costs
0.05-0.2 ms, a few percent of a sweep of a few thousand points."""


@dataclass(frozen=True)
class RunSize:
    """What a run needs, from its grid's shape: ``memory`` [bytes] at its peak, ``file`` [bytes] before compression,
    ``disk`` [bytes] while it runs (the journal and the file side by side at the end), ``seconds`` at a typical
    rate on this machine's cores."""

    points: int
    memory: int
    file: int
    disk: int
    seconds: float

    def lines(self) -> list[str]:
        """The dry run's lines about the size."""
        available = available_memory()
        room = f", {human_bytes(available)} available" if available is not None else ""
        return [f"{'estimated memory':>28}: ~{human_bytes(self.memory)} (from the grid's shape{room})",
                f"{'estimated disk':>28}: ~{human_bytes(self.file)} file before compression, ~{human_bytes(self.disk)} "
                "with the journal while running",
                f"{'typical time':>28}: ~{_duration(self.seconds)} at a typical rate on {_cores()} cores (from the "
                "grid's shape)"]


def _cores() -> int:
    threads = os.environ.get("NUMBA_NUM_THREADS", "")
    return int(threads) if threads.isdigit() and int(threads) > 0 else os.cpu_count() or 1


def _duration(seconds: float) -> str:
    for unit, length in (("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= 2 * length:
            return f"{seconds / length:.3g} {unit}"
    return f"{seconds:.2g} s"


def file_bytes_per_point(scene: Scene) -> int:
    """Bytes per point of the scene's file before compression (its protocol's Protocol.file_bytes_per_point)."""
    return protocols.get(scene.protocol).file_bytes_per_point(scene)


def estimate_size(scene: Scene, journaled: bool) -> RunSize:
    """The size of running ``scene`` (``journaled``: with an output file, whose journal keeps the sampled times)."""
    n = scene.n_points
    protocol = protocols.get(scene.protocol)  # its bytes and seconds per point (sweep/protocols/)
    samples = 0 if journaled else protocol.samples_per_point(scene)
    memory = n * (protocol.memory_per_point + MEMORY_PER_SAMPLE * samples)
    file = n * file_bytes_per_point(scene)
    return RunSize(points=n, memory=memory, file=file, disk=2 * file if journaled else file,
                   seconds=n * protocol.core_seconds_per_point / _cores())


def available_memory() -> int | None:
    """Bytes of memory this process can still take: the system's available memory (Linux MemAvailable, else the
    free pages), within the limit of its control group where it has one; None where unknown."""
    found = []
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                found.append(int(line.split()[1]) * 1024)
    except (OSError, ValueError, IndexError):
        pass
    if not found:
        try:
            found.append(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
        except (OSError, ValueError, AttributeError):
            pass
    try:  # cgroup v2: a container's limit, which MemAvailable does not show
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if limit != "max":
            found.append(int(limit) - int(Path("/sys/fs/cgroup/memory.current").read_text()))
    except (OSError, ValueError):
        pass
    return min(found) if found else None


def check_fits(scene: Scene, size: RunSize) -> None:
    """InputError, before any plan is made, if ``size`` needs more memory than is available: the message says how
    to split the grid (each part its own scene and file). A run of at most UNCHECKED_MEMORY is not checked."""
    if size.memory <= UNCHECKED_MEMORY:
        return
    available = available_memory()
    if available is None or size.memory <= available:
        return
    n_k, rest = scene.shape[0], math.prod(scene.shape[1:])  # a K_over_M row: V and any extra axes
    per_point = size.memory / size.points
    fit = int(available // per_point)
    k_rows = fit // rest
    split = (f"split the K_over_M axis into {math.ceil(n_k / k_rows)} scenes of at most {k_rows} values each (one "
             f"file each)" if k_rows >= 1 else
             f"split the grid into scenes of at most {fit:,} points each (one file each)")
    shape = " x ".join(f"{n} {name}" for n, name in zip(scene.shape, ("K/M", "V", *scene.dims[2:])))
    raise InputError(f"the grid of {size.points:,} points ({shape}) needs ~{human_bytes(size.memory)} of "
                     f"memory (estimated from its shape), {human_bytes(available)} available: {split}, or run it on "
                     f"a machine with more memory")
