"""The driven protocol: the drive keeps moving at V; steady sliding, perturbed by ``perturbation``, is followed until
its regime is decided: steady, stick-slip, runaway (docs/physics.md 3b)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...errors import InputError
from ..base import ChunkCompute, Protocol

if TYPE_CHECKING:
    import xarray as xr

    from ...plan.plan import Plan
    from ...scene.scene import Scene

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

    def check(self, scene: Scene) -> None:
        if scene.method not in DRIVEN_METHODS:
            raise InputError(f"protocol 'driven' runs the adaptive dp5 stepper: method must be one of "
                             f"{list(DRIVEN_METHODS)}, got {scene.method!r}")
        for name, value, default in (("step", scene.step, None), ("precision", scene.precision, "float64"),
                                     ("t_obs", scene.t_obs, ())):
            if value != default:
                raise InputError(f"{name} is not used by protocol 'driven' (leave it at {default!r}), got {value!r}")

    def toml_lines(self, scene: Scene) -> list[str]:
        return [f"perturbation = {scene.perturbation!r}", f"max_cycles = {int(scene.max_cycles)}"]

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

    def dataset(self, scene: Scene, plan: Plan, flat: dict[str, np.ndarray], seconds: float, history: str,
                sampled: bool) -> xr.Dataset:
        from .schema import build_driven_dataset

        return build_driven_dataset(scene, flat, seconds, plan.describe(), history=history)

    def dry_run(self, scene: Scene) -> list[str]:
        from ...plan.plan import make_plan
        from ...plan.sample import plan_sample

        planned, note = plan_sample(scene)
        lines = [f"{'plan of':>28}: {note}"] if note else []
        return lines + [f"{key:>28}: {text}" for key, text in make_plan(planned).describe().items()]

    def summary(self, ds: xr.Dataset) -> list[str]:
        from ...status import flag_summary

        return [*super().summary(ds), flag_summary(ds, "regime")]

    def draw(self, ds: xr.Dataset, path: str | Path, variable: str | None = None) -> list[Path]:
        """The regime map with the Hopf lines and the stick-slip amplitude (``variable``: that variable's map)."""
        from ...plot.files import plot_landscape, plot_regimes

        if variable is not None:
            return [plot_landscape(ds, path, variable=variable, title=self.title, eq10=False)]
        return [plot_regimes(ds, path)]


PROTOCOL = DrivenProtocol()
