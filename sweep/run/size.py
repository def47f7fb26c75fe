"""The size of a run from its grid's shape alone, before any plan is made. Memory, disk and a rough time are known
from the number of points, the chunk size, the observables and the protocol; a run whose memory would exceed what
the machine has available is refused with a message that says how to split it or to give it an output file.

A run with an output file holds O(chunk) in memory, whatever the grid's size: the chunks in flight (computing,
waiting for the journal and for the file: ~memory_per_point each point), and the Dataset it returns and draws, whole
up to sweep.write.regions.LATTICE_BYTES, else a lattice of that size. A run without one holds its whole Dataset (the
file's bytes per point) besides. The constants were measured on the 2-core development machine (the protocols'
memory_per_point under tracemalloc; the file, from the bytes of its variables before compression). They are rounded
up: the check refuses what would certainly not fit, it does not promise that the rest does.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from .. import protocols
from ..errors import InputError
from ..scene.scene import Scene
from ..write.targets import free_bytes, human_bytes

__all__ = ["RunSize", "available_memory", "check_fits", "estimate_size"]

MEMORY_PER_SAMPLE = 50
"""Peak bytes per point and sampled time of a chunk being computed."""
CHUNKS_IN_FLIGHT = 8
"""Chunks a run holds at once, at most: computing (one a thread, and those submitted ahead), finished and waiting for
the journal and for the file (sweep.write.writer.PENDING_CHUNKS each)."""
UNCHECKED_MEMORY = 32 * 2**20
"""Bytes of memory a run may need without a look at what the machine has (:func:`check_fits`): less than the
process's own imports took (numba, xarray: ~200 MB), and the look (/proc/meminfo, the control group's files) costs
0.05-0.2 ms, a few percent of a sweep of a few thousand points."""


@dataclass(frozen=True)
class RunSize:
    """What a run needs, from its grid's shape: ``memory`` [bytes] at its peak, ``file`` [bytes] before compression,
    ``disk`` [bytes] while it runs (the journal and the file side by side until the end), ``seconds`` at a typical
    rate on this machine's cores (the size check's rough time: the dry run times a pilot instead)."""

    points: int
    memory: int
    file: int
    disk: int
    seconds: float
    output: bool = True
    """With an output file (memory O(chunk)), or the whole Dataset in memory."""

    def lines(self, folder: str | os.PathLike | None = None) -> list[str]:
        """The dry run's lines about the size (``folder``: an existing folder where the output goes, for its free
        space)."""
        available = available_memory()
        room = f", {human_bytes(available)} available" if available is not None else ""
        held = ("chunks in flight and the picture's lattice: flat in the grid's size" if self.output
                else "the whole Dataset in memory")
        free = "" if folder is None else f", {human_bytes(free_bytes(folder))} free in {folder}"
        return [f"{'estimated memory':>28}: ~{human_bytes(self.memory)} ({held}{room})",
                f"{'estimated disk':>28}: ~{human_bytes(self.file)} file before compression, ~{human_bytes(self.disk)} "
                f"with the journal while running{free}"]


def _cores() -> int:
    threads = os.environ.get("NUMBA_NUM_THREADS", "")
    return int(threads) if threads.isdigit() and int(threads) > 0 else os.cpu_count() or 1


def file_bytes_per_point(scene: Scene) -> int:
    """Bytes per point of the scene's file before compression (its protocol's Protocol.file_bytes_per_point)."""
    return protocols.get(scene.protocol).file_bytes_per_point(scene)


def estimate_size(scene: Scene, journaled: bool, chunk_size: int | None = None) -> RunSize:
    """The size of running ``scene`` (``journaled``: with an output file, and its journal; ``chunk_size``: points per
    chunk, default the protocol's)."""
    from ..write.regions import LATTICE_BYTES

    n = scene.n_points
    protocol = protocols.get(scene.protocol)  # its bytes and seconds per point (sweep/protocols/)
    chunk = min(n, chunk_size or protocol.chunk_size(scene))
    per_point = protocol.memory_per_point + MEMORY_PER_SAMPLE * protocol.samples_per_point(scene)
    file = n * file_bytes_per_point(scene)
    memory = CHUNKS_IN_FLIGHT * chunk * per_point + (min(file, LATTICE_BYTES) if journaled else file)
    return RunSize(points=n, memory=memory, file=file, disk=2 * file if journaled else file,
                   seconds=n * protocol.core_seconds_per_point / _cores(), output=journaled)


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
    shape = " x ".join(f"{n} {'K/M' if d == 'K_over_M' else d}" for n, d in zip(scene.shape, scene.dims))
    raise InputError(f"the grid of {size.points:,} points ({shape}) needs ~{human_bytes(size.memory)} of "
                     f"memory (estimated from its shape), {human_bytes(available)} available: {split}, or give it an "
                     f"output file (output=..., whose run holds only its chunks in memory), or run it on a machine "
                     f"with more memory")
