"""A third protocol for tests/protocols/test_protocols.py: each point's reduced stiffness chi = K D0/(M g) times its
own scene field ``scale``, "computed" chunk by chunk. It lives outside the package, as a user's protocol would, and
plugs in through sweep.protocols.register."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sweep.assemble.dataset import global_attrs, grid_coords, variable
from sweep.errors import InputError
from sweep.plan.plan import point_params
from sweep.protocols.base import Protocol
from sweep.status import Status, flag_attrs


@dataclass(frozen=True)
class EchoPlan:
    chi: np.ndarray
    chunk_size: int

    @property
    def n_points(self) -> int:
        return self.chi.size

    def take(self, rows: np.ndarray) -> EchoPlan:
        return EchoPlan(self.chi[rows], self.chunk_size)

    def describe(self) -> dict[str, str]:
        return {"rule": "scale x chi = K D0/(M g) per point"}


class EchoProtocol(Protocol):
    name = "echo"
    title = "echo scene"
    marker = "echo"
    observables = ("echo",)
    always = "echo"
    default_observables = ("echo",)
    models = frozenset({("quasistatic", "aging"), ("inertial", "aging")})
    default_chunk = 7
    memory_per_point = 64
    file_per_point = 16
    core_seconds_per_point = 1e-7
    option_fields = {"scale": 1.0}

    def make_options(self, scene, given):
        options = super().make_options(scene, given)
        if not options.scale > 0:
            raise InputError(f"scale must be > 0, got {options.scale!r}")
        return options

    def check(self, scene):
        pass

    def make_plan(self, scene):
        return EchoPlan(scene.options.scale * point_params(scene).chi, self.chunk_size(scene))

    def chunk(self, scene, plan, progress=False):
        def compute(rows):
            return {"echo": plan.chi[rows].copy(), "status": np.full(rows.size, Status.OK, np.int8)}
        return compute

    def kernel_families(self, scene):
        return []

    def warm_up(self, scene, plan):
        pass

    def coords(self, scene):
        return grid_coords(scene)

    def variables(self, scene, plan, arrays):
        grid = lambda a: a.reshape(scene.shape)  # noqa: E731
        return {"echo": variable(scene.dims, grid(arrays["echo"]), "1", "reduced stiffness, echoed"),
                "status": variable(scene.dims, grid(arrays["status"]), "1", "numerical status", **flag_attrs())}

    def attributes(self, scene, totals, history):
        return global_attrs(scene, "echo", f"a test protocol over {totals.points} points", history, totals.seconds)

    def dry_run(self, scene):
        return [f"{'plan':>28}: echo chi at {scene.n_points} points"]

    def summary(self, totals, ds):
        return [f"echo: {totals.points} points"]

    def draw(self, ds, path, variable=None):
        Path(path).write_text("echo picture")
        return [Path(path)]


PROTOCOL = EchoProtocol()
