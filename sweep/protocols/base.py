"""What a protocol is: the hooks through which the scene, the plan, the run, the size check, the compile notice, the
dry run, the command line and the pictures reach the one protocol a scene names (:func:`sweep.protocols.get`).

A protocol's module keeps its own imports inside its methods, so that validating a scene or naming a file's kind
loads no kernels.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..errors import InputError

if TYPE_CHECKING:
    import xarray as xr

    from ..plan.plan import Plan
    from ..scene.scene import Scene
    from ..write.regions import RunTotals

__all__ = ["AxisSpec", "ChunkCompute", "Options", "Protocol"]

ChunkCompute = Callable[[np.ndarray], dict[str, np.ndarray]]
"""compute(points) -> per-point arrays of one chunk (points: rows of the plan it was made with)."""


@dataclass(frozen=True)
class AxisSpec:
    """A grid axis that a protocol's options name (:meth:`Protocol.option_axes`), e.g. a history's hold time."""

    units: str
    """The axis's unit, from the option that names it (e.g. "s" for a hold)."""
    long_name: str
    """Words for the Dataset's coordinate."""
    where: str
    """Where the options name it, for messages (e.g. "segments[1].hold")."""
    minimum: float = 0.0
    """Values must be > minimum (>= minimum where ``inclusive``)."""
    inclusive: bool = False


class Options(Mapping):
    """A protocol's own fields of a scene (Scene.options): read-only, by key or as attributes."""

    def __init__(self, values: Mapping[str, Any]) -> None:
        object.__setattr__(self, "_values", MappingProxyType(dict(values)))

    def __getitem__(self, name: str) -> Any:
        return self._values[name]

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):  # (not a field: also keeps a half-built copy from recursing)
            raise AttributeError(name)
        try:
            return self._values[name]
        except KeyError:
            raise AttributeError(name) from None

    def __reduce__(self):  # pickled (a dask worker's scene) by its values
        return Options, (dict(self._values),)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("a scene's options cannot change (dataclasses.replace the scene)")

    def __iter__(self):
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return f"Options({dict(self._values)!r})"


class Protocol(ABC):
    """One loading of the spring-block: its scene fields, plan, chunk computation, output schema and picture."""

    name: ClassVar[str]
    """The scene's ``protocol`` value."""
    title: ClassVar[str]
    """Words for pictures and messages, e.g. "stop scene"."""
    marker: ClassVar[str]
    """The variable that marks this protocol's files (sweep.write.read.file_kind)."""
    observables: ClassVar[tuple[str, ...]]
    """Observables a scene of this protocol may ask for, in the order the scene stores them."""
    always: ClassVar[str]
    """The observable always computed and stored."""
    default_observables: ClassVar[tuple[str, ...]]
    """Observables of a scene that names none."""
    models: frozenset[tuple[str, str]]
    """The (model, state law) pairs it runs (model "auto" needs both models of a law): a property where it follows
    the state laws' registry (sweep.integrate.models.state_laws.STATE_LAWS)."""
    extra_axes: ClassVar[bool] = False
    """Whether a scene of this protocol may sweep friction parameters beside (K/M, V) (Scene.axes)."""
    default_chunk: ClassVar[int]
    """Points per chunk by default (:meth:`chunk_size` may grow it)."""
    memory_per_point: ClassVar[int]
    """Peak bytes of a run per point, besides its sampled times (sweep/run/size.py)."""
    file_per_point: ClassVar[int]
    """Bytes per point of its file before compression, besides what its observables add."""
    core_seconds_per_point: ClassVar[float]
    """Typical core-seconds a point takes (the size check's rough time; the dry run measures its own)."""
    warm_up_timed: ClassVar[bool] = True
    """Whether ``sweep run`` loads the kernels before the chunk loop and reports how long that took."""

    option_fields: ClassVar[Mapping[str, Any]] = MappingProxyType({})
    """The protocol's own scene fields beyond those every scene has: name -> default. A scene holds them in
    ``Scene.options`` (given as ``options={...}`` in Python, as top-level keys in a scene file), checked by
    :meth:`make_options`, written into the canonical TOML by :meth:`toml_lines`. The stop's and the driven scene's
    fields (trajectory_tau, t_obs, step, precision; perturbation, max_cycles) are theirs the same way, and are also
    Scene keywords and attributes (sweep.scene.scene.PROTOCOL_FIELDS), for the code and files that name them."""

    # --- the scene ------------------------------------------------------------------------------------------------
    def make_options(self, scene: Scene, given: Mapping[str, Any]) -> Options:
        """The scene's options: ``given`` over the defaults of :attr:`option_fields`; InputError for a name the
        protocol does not have. A protocol with fields to check overrides this (and calls it first)."""
        unknown = sorted(set(given) - set(self.option_fields))
        if unknown:
            raise InputError(f"options {unknown} are not fields of protocol {self.name!r}; its fields: "
                             f"{sorted(self.option_fields) or 'none'}")
        return Options({**self.option_fields, **given})

    def supports(self, model: str, state_law: str) -> bool:
        """Whether the protocol runs ``model`` ("auto": both models) with ``state_law``."""
        wanted = ("quasistatic", "inertial") if model == "auto" else (model,)
        return all((m, state_law) in self.models for m in wanted)

    def option_axes(self, options: Mapping[str, Any]) -> dict[str, AxisSpec]:
        """The grid axes that ``options`` name (the scene's options, checked or as given: a value that is not
        understood names none): axis name -> its unit, long name and bound. The scene accepts these names in
        ``Scene.axes`` (tables of a scene file) beside the friction parameters, refuses one that clashes with a
        parameter, and refuses a named axis it is not given. None by default."""
        return {}

    @abstractmethod
    def check(self, scene: Scene) -> None:
        """InputError for settings this protocol does not use or cannot run (the common checks are made)."""

    def toml_lines(self, scene: Scene) -> list[str]:
        """The protocol's own lines of the scene's canonical TOML (after max_steps): its options."""
        return [f"{name} = {toml_value(value)}" for name, value in scene.options.items()]

    def time_resolved(self, scene: Scene) -> bool:
        """Whether values inside the transient are asked for."""
        return False

    def samples_per_point(self, scene: Scene) -> int:
        """Values sampled in time per point (held in memory by a run without a file)."""
        return 0

    def file_bytes_per_point(self, scene: Scene) -> int:
        """Bytes per point of the scene's file before compression."""
        return self.file_per_point

    # --- the plan and the chunks ------------------------------------------------------------------------------------
    def chunk_size(self, scene: Scene) -> int:
        """The default chunk size of ``scene`` (a layout that depends on the grid only: a journal resumes anywhere)."""
        return self.default_chunk

    @abstractmethod
    def make_plan(self, scene: Scene) -> Plan:
        """What to model and how to step, for every point of ``scene``."""

    @abstractmethod
    def chunk(self, scene: Scene, plan: Plan, progress: bool | None = False) -> ChunkCompute:
        """compute(points) of one chunk of ``plan``."""

    @abstractmethod
    def kernel_families(self, scene: Scene) -> list[str]:
        """The kernel families (sweep.run.compile_notice.COLD_COMPILE_S) the scene compiles on first use."""

    @abstractmethod
    def warm_up(self, scene: Scene, plan: Plan, fan_out: bool = False) -> None:
        """Compile (or load from numba's cache) the kernels the scene uses, on one point each: those every run of
        the scene calls, and with ``fan_out`` (before the chunks go to dask workers, which should load every kernel
        from the cache rather than each compile it) also those only some points may need."""

    # --- the output -------------------------------------------------------------------------------------------------
    @abstractmethod
    def coords(self, scene: Scene) -> dict[str, xr.Variable]:
        """The coordinates of the scene's file over its whole grid (the axes and the quantities along them:
        sweep.assemble.dataset.grid_coords and the protocol's own)."""

    @abstractmethod
    def variables(self, scene: Scene, plan: Plan, arrays: dict[str, np.ndarray]) -> dict[str, xr.Variable]:
        """The data variables over the grid of ``scene`` from its chunk's arrays (what :meth:`chunk` computed, in
        the grid's C order). A run calls it once per chunk, with the chunk's block of the grid as ``scene`` and that
        block's plan (sweep/write/regions.py): the variables depend on each point alone."""

    @abstractmethod
    def attributes(self, scene: Scene, totals: RunTotals, history: str) -> dict[str, object]:
        """The global attributes of the scene's file, from the run's totals over every chunk (sweep.write.regions:
        the flags' counts, the plans' counts, the seconds)."""

    def reduce(self, variables: Mapping[str, xr.Variable]) -> dict[str, float]:
        """Maxima over one chunk's variables that :meth:`summary` reports (merged over the chunks by max)."""
        return {}

    # --- what the user sees -------------------------------------------------------------------------------------------
    @abstractmethod
    def dry_run(self, scene: Scene) -> list[str]:
        """The dry run's lines after the size: the plan (of a subsample where the grid is large) and, where it is
        measured, the time."""

    def summary(self, totals: RunTotals, ds: xr.Dataset) -> list[str]:
        """Lines ``sweep run`` prints about a finished run: the flags' counts (``ds``: its Dataset, for the flags'
        meanings)."""
        from ..status import flag_summary

        return [flag_summary(ds, "status", totals.counts), flag_summary(ds, "model", totals.counts)]

    def picture_paths(self, path: str | Path, trajectories: bool, points: int, variable: str | None = None
                      ) -> list[Path]:
        """The pictures :meth:`draw` writes for a file with ``points`` grid points (``trajectories``: it holds
        transients), so that a command checks them before any work."""
        return [Path(path)]

    @abstractmethod
    def draw(self, ds: xr.Dataset, path: str | Path, variable: str | None = None) -> list[Path]:
        """The pictures of a file of this protocol (``variable``: that variable alone); returns the paths written."""


def toml_value(value: Any) -> str:
    """``value`` (a bool, number, string or a list of them, nested) in TOML, numbers as Python's repr (exact)."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, float, np.integer, np.floating)):
        return repr(value.item() if isinstance(value, np.generic) else value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    return "[" + ", ".join(toml_value(v) for v in value) + "]"
