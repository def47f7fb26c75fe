"""A run's output block by block: each finished chunk becomes the variables of its block of the grid
(sweep/plan/layout.py), built once by its protocol (Protocol.variables over the chunk's sub-grid scene and plan) and
handed to the run's sinks, none of which holds more than it keeps by design:

* :class:`GridArrays`: the Dataset in memory, every point (a run without a file, or a grid small enough to return
  whole) or a regular lattice of them (the picture of a grid too large to hold: at most LATTICE_BYTES);
* sweep.write.netcdf.NetCDFRegions: the netCDF file, each block written into its region (its own storage chunk).

A chunk's block is built where the chunk is computed (:func:`build_block`, called by sweep.run.runner.chunk_task: in
the computing threads or dask workers, side by side), and stored in one helper thread while the next chunks compute
(at most PENDING_CHUNKS waiting); :class:`RunTotals` gathers what the file's attributes and the run's summary say of
the whole grid: the flags' counts, the plan's counts, the seconds of computing, the protocol's maxima
(Protocol.reduce). Nothing here is O(grid) except what a sink keeps.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import xarray as xr

from .. import protocols
from ..plan.layout import block_slices
from ..plan.plan import Plan, PlanStats, make_plan
from ..scene.scene import Scene
from .writer import Behind, Writer

__all__ = ["BLOCK", "LATTICE_BYTES", "Block", "GridArrays", "Regions", "RunTotals", "Sink", "build_block",
           "lattice_steps"]

LATTICE_BYTES = 32 * 2**20
"""Most bytes a run with an output file keeps in memory for its picture and returned Dataset (the whole grid up to
this size, else a regular lattice of its points, every n-th along each dim: ~400,000 points of the default scene,
as many cells as a picture has pixels). Small beside the process itself (~300 MB of imports and kernels), so that
the run's memory stays flat as the grid grows (with 64 MB, the drawing of the larger lattice made a 1e8-point run's
peak 20.5 % above a 1e6-point run's)."""


BLOCK = "__block__"
"""The key of a chunk's results that holds its :class:`Block` where it was built beside the computing
(sweep.run.runner.chunk_task); writers that keep arrays (the journal) leave it out."""


class Block(NamedTuple):
    """One chunk's output: its block of the grid (a slice per grid dim), its variables over that block, and what
    the run's totals take from it."""

    slices: tuple[slice, ...]
    variables: dict[str, xr.Variable]
    counts: dict[str, dict[int, int]]
    """Points per flag value of each variable with ``flag_values``."""
    plan_stats: PlanStats | None
    plan_choices: object
    """The chunk's plan without its points (Plan.take of none): the scene-level choices its description states."""
    maxima: dict[str, float]
    """The protocol's maxima over the block (Protocol.reduce)."""


def build_block(scene: Scene, points: np.ndarray, arrays: Mapping[str, np.ndarray], plan=None,
                sub: Scene | None = None) -> Block:
    """The :class:`Block` of a chunk of ``scene``: ``points``, its flat points (a consecutive range of the grid,
    shuffled, sweep.run.runner.ChunkLayout) in the order of its ``arrays``; ``sub`` and ``plan``: the block's
    sub-grid scene and plan where the caller has them (else made here)."""
    protocol = protocols.get(scene.protocol)
    lo = int(points.min())
    order = np.empty(points.size, np.intp)
    order[points - lo] = np.arange(points.size)  # the grid's C order within the block
    slices = block_slices(scene.shape, lo, lo + points.size)
    sub = scene.sub_grid(slices) if sub is None else sub
    plan = make_plan(sub) if plan is None else plan
    ordered = {name: value[order] for name, value in arrays.items() if isinstance(value, np.ndarray) and value.ndim}
    variables = protocol.variables(sub, plan, ordered)
    counts = {}
    for name, var in variables.items():
        if "flag_values" in var.attrs:
            low = int(np.min(var.attrs["flag_values"]))
            n = np.bincount(var.values.ravel().astype(np.intp) - low)
            counts[name] = {code + low: int(k) for code, k in enumerate(n.tolist()) if k}
    stats = plan.stats() if isinstance(plan, Plan) else None
    return Block(slices, variables, counts, stats, plan.take(np.arange(0)), protocol.reduce(variables))


@dataclass
class RunTotals:
    """What a run's attributes and summary say of its whole grid, gathered chunk by chunk."""

    seconds: float = 0.0
    """Seconds of computing, summed over the chunks."""
    points: int = 0
    counts: dict[str, dict[int, int]] = field(default_factory=dict)
    """Points per flag value, for every variable with ``flag_values`` (status, model, stable, regime...)."""
    plan: PlanStats | None = None
    """The chunks' plan counts, merged."""
    plan_example: Plan | None = None
    """A chunk's plan without its points: the scene-level choices (method, rules) that every chunk's plan shares."""
    maxima: dict[str, float] = field(default_factory=dict)
    """The protocol's running maxima (Protocol.reduce)."""

    def add(self, seconds: float, points: int, block: Block) -> None:
        self.seconds += seconds
        self.points += points
        for name, found in block.counts.items():
            counts = self.counts.setdefault(name, {})
            for code, k in found.items():
                counts[code] = counts.get(code, 0) + k
        if block.plan_stats is not None:
            self.plan = block.plan_stats if self.plan is None else self.plan + block.plan_stats
        self.plan_example = self.plan_example or block.plan_choices
        for name, value in block.maxima.items():
            self.maxima[name] = float(np.fmax(self.maxima.get(name, np.nan), value))


class Sink(ABC):
    """Where a run's blocks go (module docstring). Called from one thread: start, put..., close or abort."""

    def start(self, scene: Scene, coords: Mapping[str, xr.Variable]) -> None:  # noqa: B027 (nothing to prepare)
        """Before the first block: the scene and its whole grid's coordinates."""

    @abstractmethod
    def put(self, block: Block) -> None:
        """Store one block."""

    def close(self, attrs: Mapping[str, object]) -> None:  # noqa: B027 (nothing to finish)
        """After the last block: the global attributes, made from the run's totals."""

    def abort(self) -> None:  # noqa: B027 (nothing kept)
        """After a failure: drop what is unfinished."""


class Regions(Writer):
    """The writer of a run's chunk loop that turns chunks into blocks for its ``sinks`` (module docstring)."""

    def __init__(self, scene: Scene, sinks: Sequence[Sink], coords: Mapping[str, xr.Variable]) -> None:
        self.scene, self.sinks, self.coords = scene, list(sinks), coords
        self.totals = RunTotals()

    def start(self, layout) -> None:
        super().start(layout)
        for sink in self.sinks:
            sink.start(self.scene, self.coords)
        self._behind = Behind("sweep-regions")

    def put(self, index: int, arrays: dict[str, np.ndarray]) -> None:
        self._behind.submit(self._store, index, dict(arrays))

    def _store(self, index: int, arrays: dict[str, np.ndarray]) -> None:
        block = arrays.get(BLOCK) or build_block(self.scene, self.layout[index], arrays)  # (a resumed chunk: here)
        self.totals.add(float(arrays.get("seconds", 0.0)), self.layout.size(index), block)
        for sink in self.sinks:
            sink.put(block)

    def close(self) -> None:
        self._behind.close()

    def finish(self, attrs: Mapping[str, object]) -> None:
        """Close every sink with the global attributes (made by the caller from :attr:`totals`)."""
        for sink in self.sinks:
            sink.close(attrs)

    def abort(self, error: BaseException) -> None:
        if hasattr(self, "_behind"):  # (not where a sink failed to start)
            self._behind.close(raise_errors=False)
        for sink in self.sinks:
            sink.abort()


def lattice_steps(shape: tuple[int, ...], bytes_per_point: float, budget: float = LATTICE_BYTES) -> tuple[int, ...]:
    """Every how many points along each dim a lattice of the grid keeps, so that it holds at most ``budget`` bytes
    (1 everywhere where the whole grid fits): the same step on every dim larger than it, the smaller dims whole."""
    n_max = max(1, int(budget // max(1.0, bytes_per_point)))
    if math.prod(shape) <= n_max:
        return (1,) * len(shape)
    step = 1
    while math.prod(-(-n // step) for n in shape) > n_max:
        step += max(1, step // 8)
    return tuple(step for _ in shape)


class GridArrays(Sink):
    """The run's Dataset in memory: every point, or the lattice of every ``steps[d]``-th point along each dim d
    (:func:`lattice_steps`), filled block by block."""

    def __init__(self, steps: tuple[int, ...] | None = None) -> None:
        self.steps = steps
        self.arrays: dict[str, np.ndarray] = {}
        self.meta: dict[str, tuple[tuple[str, ...], dict]] = {}

    def start(self, scene: Scene, coords: Mapping[str, xr.Variable]) -> None:
        self.dims = scene.dims
        self.steps = self.steps or (1,) * len(self.dims)
        self.shape = tuple(-(-n // s) for n, s in zip(scene.shape, self.steps))
        self.coords = {name: var.isel({d: slice(None, None, s) for d, s in zip(self.dims, self.steps)
                                       if d in var.dims}) for name, var in coords.items()}

    @property
    def whole(self) -> bool:
        return all(s == 1 for s in self.steps)

    def put(self, block: Block) -> None:
        source, target = [], []
        for s, step in zip(block.slices, self.steps):
            first = -(-s.start // step) * step  # the first lattice index in the block
            source.append(slice(first - s.start, s.stop - s.start, step))
            target.append(slice(first // step, -(-s.stop // step)))
        for name, var in block.variables.items():
            if name not in self.arrays:
                trailing = var.shape[len(self.dims):]
                fill = np.nan if var.dtype.kind == "f" else 0
                self.arrays[name] = np.full(self.shape + trailing, fill, dtype=var.dtype)
                self.meta[name] = (var.dims, dict(var.attrs))
            self.arrays[name][tuple(target)] = var.values[tuple(source)]

    def dataset(self, attrs: Mapping[str, object]) -> xr.Dataset:
        """The Dataset of the blocks put (the lattice's where it is one), with the global attributes ``attrs``."""
        from ..assemble.construct import assemble

        data = {name: xr.Variable(self.meta[name][0], value, self.meta[name][1]) for name, value in self.arrays.items()}
        ds = assemble(data, self.coords, attrs)
        if not self.whole:
            ds.attrs["lattice"] = ("every " + ", ".join(f"{s}th {d}" for d, s in zip(self.dims, self.steps))
                                   + " point of the run's grid (the file holds them all)")
        return ds
