"""The driven protocol: the drive keeps moving at V; steady sliding, perturbed by ``perturbation``, is followed until
its regime is decided: steady, stick-slip, runaway (docs/physics.md 3b)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from ...errors import InputError
from ..base import ChunkCompute, Options, Protocol

if TYPE_CHECKING:
    import xarray as xr

    from ...plan.plan import Plan
    from ...scene.scene import Scene
    from ...write.regions import RunTotals

__all__ = ["DRIVEN_METHODS", "PROTOCOL", "DrivenProtocol"]

DRIVEN_METHODS = ("auto", "dp5")
"""Methods a driven scene accepts: its stepper is the adaptive dp5 (with rodas3 in stiff stick phases)."""


class DrivenProtocol(Protocol):
    name = "driven"
    title = "driven scene"
    marker = "regime"
    observables = ("regime", "growth_rate", "period", "amplitude")
    always = "regime"
    default_observables = observables
    option_fields = MappingProxyType({"perturbation": 1e-3, "max_cycles": 2000})
    default_chunk = 1024  # a driven point costs ~10-100x a stop point
    memory_per_point = 300
    file_per_point = 80
    core_seconds_per_point = 3.2e-4
    warm_up_timed = False

    @property
    def models(self) -> frozenset[tuple[str, str]]:
        """Quasi-static with every state law (its rate composed into the driven right-hand side); inertial with the
        laws that have an inertial model."""
        from ...integrate.models.state_laws import STATE_LAWS

        return frozenset({("quasistatic", n) for n in STATE_LAWS} | {("inertial", n) for n, law in STATE_LAWS.items()
                                                                     if law.inertial})

    def make_options(self, scene: Scene, given: Mapping[str, Any]) -> Options:
        """The driven scene's own fields: the initial spring stretch ``perturbation`` away from steady sliding
        (reduced, z = tau - xi) and the budget of oscillation cycles ``max_cycles``."""
        from ...scene.params import require_positive
        from ...scene.scene import PERTURBATION_RANGE, _plain

        options = dict(super().make_options(scene, given))
        pert = require_positive("perturbation", options["perturbation"])
        if not PERTURBATION_RANGE[0] <= pert <= PERTURBATION_RANGE[1]:
            raise InputError(f"perturbation must be in [{PERTURBATION_RANGE[0]:g}, {PERTURBATION_RANGE[1]:g}] "
                             f"(reduced spring stretch), got {pert!r}")
        cycles = options["max_cycles"]
        if isinstance(cycles, bool) or not isinstance(cycles, (int, np.integer)) or cycles < 4:
            raise InputError(f"max_cycles must be an integer >= 4, got {_plain(cycles)!r}")
        return Options({"perturbation": pert, "max_cycles": cycles})

    def check(self, scene: Scene) -> None:
        if scene.method not in DRIVEN_METHODS:
            raise InputError(f"protocol 'driven' runs the adaptive dp5 stepper: method must be one of "
                             f"{list(DRIVEN_METHODS)}, got {scene.method!r}")

    def toml_lines(self, scene: Scene) -> list[str]:
        return [f"perturbation = {scene.options.perturbation!r}", f"max_cycles = {int(scene.options.max_cycles)}"]

    def make_plan(self, scene: Scene) -> Plan:
        from .plan import driven_plan

        return driven_plan(scene)

    def chunk(self, scene: Scene, plan: Plan, progress: bool | None = False) -> ChunkCompute:
        from .chunk import driven_chunk

        return driven_chunk(scene, plan)

    def kernel_families(self, scene: Scene) -> list[str]:
        from ...run.compile_notice import driven_families

        return driven_families(scene.model)

    def warm_up(self, scene: Scene, plan: Plan, fan_out: bool = False) -> None:
        """One point per variant of the driven kernel the plan uses (quasi-static, inertial)."""
        from ...run.runner import chunk_task

        inertial = plan.inertial & (plan.G > 0.0)
        firsts = np.unique([int(np.argmax(inertial == used)) for used in (False, True) if (inertial == used).any()])
        chunk_task(scene, plan.take(firsts), firsts)

    def coords(self, scene: Scene) -> dict[str, xr.Variable]:
        from .schema import driven_coords

        return driven_coords(scene)

    def variables(self, scene: Scene, plan: Plan, arrays: dict[str, np.ndarray]) -> dict[str, xr.Variable]:
        from .schema import driven_variables

        return driven_variables(scene, arrays)

    def attributes(self, scene: Scene, totals: RunTotals, history: str) -> dict[str, object]:
        from .schema import driven_attributes

        return driven_attributes(scene, totals.seconds, totals.plan_example.describe(totals.plan), history)

    def dry_run(self, scene: Scene) -> list[str]:
        from ...plan.plan import make_plan
        from ...plan.sample import plan_sample

        planned, note = plan_sample(scene)
        lines = [f"{'plan of':>28}: {note}"] if note else []
        return lines + [f"{key:>28}: {text}" for key, text in make_plan(planned).describe().items()]

    def summary(self, totals: RunTotals, ds: xr.Dataset) -> list[str]:
        from ...status import flag_summary

        return [*super().summary(totals, ds), flag_summary(ds, "regime", totals.counts)]

    def draw(self, ds: xr.Dataset, path: str | Path, variable: str | None = None) -> list[Path]:
        """The regime map with the Hopf lines and the stick-slip amplitude (``variable``: that variable's map)."""
        from ...plot.files import plot_landscape, plot_regimes

        if variable is not None:
            return [plot_landscape(ds, path, variable=variable, title=self.title, eq10=False)]
        return [plot_regimes(ds, path)]


PROTOCOL = DrivenProtocol()
