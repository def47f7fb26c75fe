"""The history protocol: a piecewise load history (velocity steps, holds, slide-hold-slide) from steady sliding,
quasi-static, with the aging or the slip law; per segment what the laboratory reads off (docs/physics.md, "Load
histories")."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import InputError
from ..base import AxisSpec, ChunkCompute, Options, Protocol

if TYPE_CHECKING:
    import xarray as xr

    from ...scene.scene import Scene
    from ...write.regions import RunTotals
    from .engine import HistoryPlan

__all__ = ["HISTORY_METHODS", "PROTOCOL", "HistoryProtocol"]

HISTORY_METHODS = ("auto", "dp5")
"""Methods a history scene accepts: its stepper is the adaptive dp5."""

FILE_NAMES = frozenset({"segment", "V_ratio", "duration", "load_point_displacement", "status", "steps", "model",
                        "chi", "mu1", "chi_c", "chi_c_quasistatic", "gamma", "beta", "beta_error", "mu_t", "t",
                        "t_obs"})
"""Names of a history file's coordinates and variables besides the observables, which an axis may not take."""


class HistoryProtocol(Protocol):
    name = "history"
    title = "history scene"
    marker = "mu_end"
    observables = ("mu_end", "delta_mu_ss", "delta_mu_peak", "delta_mu_relax", "mu_t")
    always = "mu_end"
    default_observables = observables[:4]
    option_fields = MappingProxyType({"segments": (), "perturbation": 0.0, "t_obs": ()})
    default_chunk = 256
    memory_per_point = 400
    file_per_point = 80
    core_seconds_per_point = 1e-3
    warm_up_timed = False
    extra_axes = True

    @property
    def models(self) -> frozenset[tuple[str, str]]:
        """Quasi-static with every state law of the registry; inertial with the aging law."""
        from ...integrate.models.history import LAW_CODES

        return frozenset({("quasistatic", law) for law in LAW_CODES} | {("inertial", "aging")})

    def supports(self, model: str, state_law: str) -> bool:
        """Model "auto" runs the inertial model where some segment's gamma/A exceeds model_tol or where the
        quasi-static run runs away (a spring softer than critical), and the quasi-static one elsewhere; with a law
        that has no inertial model it runs where the quasi-static model is enough (:meth:`check` refuses a scene
        where inertia would matter; a runaway, known only once run, is flagged quasistatic_breakdown)."""
        return ("quasistatic" if model == "auto" else model, state_law) in self.models

    def make_options(self, scene: Scene, given: Mapping[str, Any]) -> Options:
        """The history scene's own fields: ``segments`` (sweep/protocols/history/segments.py), the initial spring
        stretch ``perturbation`` beyond steady sliding (reduced by D0, as the driven scene's; 0 by default) and the
        times ``t_obs`` [s] from the history's start of the observable mu_t."""
        from ...scene.params import require_finite
        from ...scene.scene import _times
        from .segments import check_segments

        options = dict(super().make_options(scene, given))
        segments = check_segments(options["segments"])
        pert = require_finite("perturbation", options["perturbation"])
        if abs(pert) > 1.0:
            raise InputError(f"perturbation must be in [-1, 1] (reduced spring stretch), got {pert!r}")
        t_obs = _times("t_obs", options["t_obs"])
        if "mu_t" in scene.observables and t_obs.size == 0:
            raise InputError("observable 'mu_t' needs t_obs: the times from the history's start [s], e.g. [0, 10, 60]")
        return Options({"segments": segments, "perturbation": float(pert), "t_obs": tuple(t_obs.tolist())})

    def option_axes(self, options: Mapping[str, Any]) -> dict[str, AxisSpec]:
        """The axes that the segments name (``hold = "t_hold"``): unit from the key (segments.AXIS_UNITS)."""
        from .segments import AXIS_WORDS, segment_axes

        out = {}
        for name, (unit, where, positive) in segment_axes(options.get("segments", ())).items():
            if name in FILE_NAMES or name.removesuffix("_error") in self.observables:
                raise InputError(f"{where} names axis {name!r}, which is a name of the history file's coordinates "
                                 f"or variables: choose another name (e.g. {'t_' + name!r})")
            key = where.rsplit(".", 1)[1]
            out[name] = AxisSpec(unit, AXIS_WORDS[key] + f" ({where})", where, 0.0, inclusive=not positive)
        return out

    def check(self, scene: Scene) -> None:
        from ... import physics

        if scene.method not in HISTORY_METHODS:
            raise InputError(f"protocol 'history' runs the adaptive dp5 stepper: method must be one of "
                             f"{list(HISTORY_METHODS)}, got {scene.method!r}")
        # the fastest segment over the grid: each segment's V_ratio (a number or an axis's largest value) x max V
        r_max = max(float(np.max(scene.axes[r])) if isinstance(r, str) else r
                    for r in (seg["V_ratio"] for seg in scene.options.segments))
        v_max = r_max * float(np.max(scene.V))
        G = float(np.max(physics.inertia_number(v_max, scene.broadcast("D0"), scene.params.g) / scene.broadcast("A")))
        if scene.model == "auto" and G > scene.model_tol and ("inertial", scene.state_law) not in self.models:
            raise InputError(f"protocol 'history' has no inertial model for the {scene.state_law} law, and inertia "
                             f"matters at the fastest segment (gamma/A = {G:.3g} > model_tol = {scene.model_tol:g} at "
                             f"{r_max:g} x V = {v_max:.3g} m/s): lower V, raise model_tol or use the aging law")

    def toml_lines(self, scene: Scene) -> list[str]:
        from ..base import toml_value

        return [f"perturbation = {scene.options.perturbation!r}",
                f"segments = {toml_value([dict(seg) for seg in scene.options.segments])}"]

    def make_plan(self, scene: Scene) -> HistoryPlan:
        from .engine import history_plan

        return history_plan(scene)

    def chunk(self, scene: Scene, plan: HistoryPlan, progress: bool | None = False) -> ChunkCompute:
        from .engine import history_chunk

        return history_chunk(scene, plan)

    def kernel_families(self, scene: Scene) -> list[str]:
        return []

    def warm_up(self, scene: Scene, plan: HistoryPlan, fan_out: bool = False) -> None:
        """One point through the kernel (compiled or loaded from numba's cache)."""
        self.chunk(scene, plan.take(np.arange(1)))(np.arange(1))

    def coords(self, scene: Scene) -> dict[str, xr.Variable]:
        from .schema import history_coords

        return history_coords(scene)

    def variables(self, scene: Scene, plan: HistoryPlan, arrays: dict[str, np.ndarray]) -> dict[str, xr.Variable]:
        from .schema import history_variables

        return history_variables(scene, arrays)

    def attributes(self, scene: Scene, totals: RunTotals, history: str) -> dict[str, object]:
        from .engine import history_plan
        from .schema import history_attributes

        example = totals.plan_example or history_plan(scene).take(np.arange(0))
        return history_attributes(scene, totals.seconds, example.describe(), history)

    def dry_run(self, scene: Scene) -> list[str]:
        from .engine import history_plan

        describe = history_plan(scene).take(np.arange(0)).describe()
        return [f"{key:>28}: {text}" for key, text in describe.items()]

    def draw(self, ds: xr.Dataset, path: str | Path, variable: str | None = None) -> list[Path]:
        """One figure (sweep/plot/history.py): mu at each segment's end over the grid's first axis; Delta mu_peak
        against log10 of the hold time where a hold's duration is an axis; mu(t) where the file has mu_t."""
        from ...plot.history import plot_history

        return [plot_history(ds, path, variable)]


PROTOCOL = HistoryProtocol()
