"""The stop protocol: steady sliding at V, the drive frozen at t = 0, the slider relaxes towards its final slip
(docs/physics.md 3a). Its observables are the relaxed slip xi_inf and, on request, values inside the transient; a
stop scene may sweep friction parameters beside (K/M, V)."""

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

__all__ = ["PROTOCOL", "StopProtocol"]

LARGE_CHUNK_POINTS = 16384
"""The largest default chunk of a stop scene that samples nothing in time (:meth:`StopProtocol.chunk_size`)."""
ONE_CHUNK_POINTS = 32768
"""A stop grid that samples nothing in time, of model "quasistatic" or "auto", is one chunk up to this many points
(:meth:`StopProtocol.chunk_size`): a quasi-static point costs ~1-10 us on one core (the default grid at rtol 1e-3, its
costly corner at rtol 1e-10), and the chunk's fixed cost is paid once: the tolerance ladder's numpy between its kernel
calls, the choice of model, the kernel calls' hand-over to the threads and each call's last runs, on which the other
threads wait (benchmarks/README.md). The points that "auto" solves with inertia (~1 ms each) are solved in batches
with a bar of their own (model_choice.RELAX_BATCH, sweep.run.runner.in_process), which the run's bar, counting
chunks, would not show until the end. Not with model "inertial", whose chunks are its progress."""
CHUNKS_AT_LEAST = 60
"""A grid keeps at least this many chunks when its chunks grow: ~8 a thread on 8 threads to share out side by side
(sweep/run/concurrent_chunks.py), the last chunks' idle share small."""
FILE_PER_VALUE = {"t50": 16, "t90": 16, "trajectory": 32, "slip_at": 16}
"""Bytes per point that each observable adds to the file, per value (trajectory: per sampled time, xi, psi and
their errors; slip_at: per time of t_obs, with its error)."""


class StopProtocol(Protocol):
    name = "stop"
    title = "stop scene"
    marker = "xi_inf"
    observables = ("xi_inf", "trajectory", "slip_at", "t50", "t90")
    always = "xi_inf"
    default_observables = ("xi_inf",)
    extra_axes = True
    option_fields = MappingProxyType({"trajectory_tau": (1e-3, 1e6, 61), "t_obs": (), "step": None,
                                      "precision": "float64"})
    default_chunk = 4096
    memory_per_point = 180
    file_per_point = 80
    core_seconds_per_point = 2.2e-5

    # --- the scene ------------------------------------------------------------------------------------------------
    @property
    def models(self) -> frozenset[tuple[str, str]]:
        """Quasi-static: every law with a stop kernel (StateLaw.stop_family); inertial: the aging identity's laws
        with an inertial model (the inertial stop integrates (xi, ln(xi' psi)) with that identity)."""
        from ...integrate.models.state_laws import STATE_LAWS

        return frozenset({("quasistatic", n) for n, law in STATE_LAWS.items() if law.stop_family}
                         | {("inertial", n) for n, law in STATE_LAWS.items() if law.inertial and law.aging_identity})

    def make_options(self, scene: Scene, given: Mapping[str, Any]) -> Options:
        """The stop's own fields: trajectory_tau (min, max, num) of the sampled reduced times, t_obs [s] of slip_at,
        the fixed step and the precision of the lanes, each checked against the scene's method, rtol and
        observables."""
        from ...integrate.solvers import METHODS
        from ...scene.params import require_positive
        from ...scene.scene import FLOAT32_RTOL_MIN, PRECISIONS, TAU_MAX, _plain, _times

        options = dict(super().make_options(scene, given))
        try:
            lo, hi, num = options["trajectory_tau"]
        except (TypeError, ValueError):
            raise InputError("trajectory_tau must be (min, max, num)") from None
        lo, hi = require_positive("trajectory_tau min", lo), require_positive("trajectory_tau max", hi)
        if not lo < hi <= TAU_MAX:
            raise InputError(f"trajectory_tau needs 0 < min < max <= {TAU_MAX:g}, got ({lo!r}, {hi!r})")
        if isinstance(num, bool) or int(num) != num or num < 2:
            raise InputError(f"trajectory_tau num must be an integer >= 2, got {_plain(num)!r}")
        options["trajectory_tau"] = (lo, hi, int(num))
        t_obs = _times("t_obs", options["t_obs"])
        if "slip_at" in scene.observables and t_obs.size == 0:
            raise InputError("observable 'slip_at' needs t_obs: the times after the stop [s], e.g. [0.1, 1, 10]")
        options["t_obs"] = tuple(t_obs.tolist())
        method, step, precision = scene.method, options["step"], options["precision"]
        if step is not None:
            step = require_positive("step", step)
            if step > 2.0:
                raise InputError(f"step must be in (0, 2] (explicit RK stability in sigma), got {step!r}")
            if method != "auto" and METHODS[method].adaptive:
                raise InputError(f"step is for fixed-step methods; method {method!r} chooses its own steps "
                                 "(leave step unset, or use method='rk4')")
            options["step"] = step
        if method != "auto" and METHODS[method].implicit and self.time_resolved(scene):
            raise InputError(f"method {method!r} computes the relaxed slip only (observables = ['xi_inf']), "
                             f"got observables={list(scene.observables)}; use rk4, dp5 or dop853")
        if precision not in PRECISIONS:
            raise InputError(f"precision must be one of {PRECISIONS}, got {precision!r}")
        if precision == "float32":
            if scene.rtol < FLOAT32_RTOL_MIN:
                raise InputError(f"precision 'float32' needs rtol >= {FLOAT32_RTOL_MIN:g} (float32 keeps ~7 "
                                 f"digits and rounding accumulates over the steps), got rtol={scene.rtol!r}")
            if self.time_resolved(scene):
                raise InputError("precision 'float32' is offered for relaxed-slip sweeps only (observables = "
                                 f"['xi_inf']), got observables={list(scene.observables)}")
            if method != "auto" and METHODS[method].adaptive:
                raise InputError(f"precision 'float32' runs fixed-step methods only (rk4), got method {method!r}")
        return Options(options)

    def toml_lines(self, scene: Scene) -> list[str]:
        """None: the stop's fields are written by Scene.to_toml where they always were (before ``method``)."""
        return []

    def check(self, scene: Scene) -> None:
        from ...integrate.models.state_laws import STATE_LAWS

        if not STATE_LAWS[scene.state_law].aging_identity:
            _require_relaxed_slip_only(scene, f"state_law {scene.state_law!r}",
                                       "the adaptive dp5 of the general two-state path")
        if scene.model == "inertial":
            _require_relaxed_slip_only(scene, "model 'inertial'", "the adaptive Rosenbrock rodas3")

    def time_resolved(self, scene: Scene) -> bool:
        return any(o != "xi_inf" for o in scene.observables)

    def samples_per_point(self, scene: Scene) -> int:
        return (("trajectory" in scene.observables) * scene.trajectory_tau[2]
                + ("slip_at" in scene.observables) * len(scene.t_obs))

    def file_bytes_per_point(self, scene: Scene) -> int:
        values = {"t50": 1, "t90": 1, "trajectory": scene.trajectory_tau[2], "slip_at": len(scene.t_obs)}
        return self.file_per_point + sum(FILE_PER_VALUE[name] * values[name]
                                         for name in scene.observables if name in FILE_PER_VALUE)

    # --- the plan and the chunks ------------------------------------------------------------------------------------
    def chunk_size(self, scene: Scene) -> int:
        """The default chunk, doubled up to LARGE_CHUNK_POINTS while the grid still has CHUNKS_AT_LEAST chunks, for a
        scene that samples nothing in time (a chunk's trajectories are held whole until it is journaled); a grid of
        at most ONE_CHUNK_POINTS such points (model not "inertial") is one chunk. A chunk has a fixed cost besides
        its points (~1 ms of numpy between its kernel calls and in the choice of model, ~2.4 ms writing it to the
        journal): at 4096 points it was ~25 % of the compute of a 1e6-point run (2 cores), at 16384 (61 chunks)
        ~7 % (benchmarks/end_to_end.py)."""
        size = self.default_chunk
        if {"trajectory", "slip_at"} & set(scene.observables):
            return size
        if scene.model != "inertial" and scene.n_points <= ONE_CHUNK_POINTS:
            return max(1, scene.n_points)
        while 2 * size <= LARGE_CHUNK_POINTS and scene.n_points >= CHUNKS_AT_LEAST * 2 * size:
            size *= 2
        return size

    def make_plan(self, scene: Scene) -> Plan:
        from ...plan.plan import point_params, stop_plan_for_points

        return stop_plan_for_points(scene, point_params(scene))

    def chunk(self, scene: Scene, plan: Plan, progress: bool | None = False) -> ChunkCompute:
        from .chunk import stop_chunk

        return stop_chunk(scene, plan, progress)

    def kernel_families(self, scene: Scene) -> list[str]:
        """The relaxed-slip engine, or the per-point path for time-resolved observables (the sampled lanes where
        sweep.plan.plan.samples_in_lanes takes them; their points without a finite relaxed slip compile the per-point
        path besides, which the scene alone does not tell), the slip law's own march, the inertial kernels where
        the model can be inertial."""
        from ...integrate.models.state_laws import STATE_LAWS
        from ...plan.plan import samples_in_lanes

        families = []
        law = STATE_LAWS[scene.state_law]
        if not law.aging_identity:
            families.append(law.stop_family)
        elif scene.model != "inertial":
            families.append("relaxed-slip engine" if scene.observables == ("xi_inf",) else
                            "time-resolved lanes" if samples_in_lanes(scene) else "time-resolved stop")
        if scene.model == "inertial":  # with "auto", compiled in the chunk whose points first need it (warm_up)
            families.append("inertial stop")
        return families

    def warm_up(self, scene: Scene, plan: Plan, fan_out: bool = False) -> None:
        """The stop chunks' kernels. The inertial stop kernels with model "inertial", and with ``fan_out`` where the
        model policy can use them (on a cold cache the two families compile side by side on two cores); with model
        "auto" in this process they compile in the chunk whose points first need them: most scenes need none
        (the default scene: 0 of 20,000 points), and a first run then compiles the relaxed-slip lanes alone."""
        from ...run.compile_notice import inertial_stop_compiled_aside
        from .chunk import warm_up
        from .model_choice import warm_up_models

        inertial = scene.model == "inertial" or (fan_out and scene.model != "quasistatic")
        with inertial_stop_compiled_aside(scene, inertial):
            warm_up(scene, plan)
        if inertial:
            warm_up_models()

    # --- the output -------------------------------------------------------------------------------------------------
    def coords(self, scene: Scene) -> dict[str, xr.Variable]:
        from ...assemble.dataset import grid_coords

        return grid_coords(scene)

    def variables(self, scene: Scene, plan: Plan, arrays: dict[str, np.ndarray]) -> dict[str, xr.Variable]:
        from .chunk import stop_outputs
        from .schema import stop_variables

        return stop_variables(scene, plan, *stop_outputs(arrays))

    def attributes(self, scene: Scene, totals: RunTotals, history: str) -> dict[str, object]:
        from .schema import stop_attributes

        return stop_attributes(scene, totals, history)

    def reduce(self, variables: Mapping[str, xr.Variable]) -> dict[str, float]:
        """The largest estimated error of the quasi-static model where it was used (model_error where model = 0)."""
        if "model_error" not in variables:
            return {}
        used = variables["model_error"].values[variables["model"].values == 0]
        used = used[np.isfinite(used)]
        return {"model_error_used": float(used.max())} if used.size else {}

    # --- what the user sees -------------------------------------------------------------------------------------------
    def dry_run(self, scene: Scene) -> list[str]:
        from ...plan.plan import make_plan
        from ...plan.sample import plan_sample
        from .estimate import estimate_seconds

        planned, note = plan_sample(scene)
        lines = [f"{'plan of':>28}: {note}"] if note else []
        plan = make_plan(planned)
        seconds, mean_steps = estimate_seconds(planned, plan, n_points=scene.n_points)
        return lines + [_plan_text(scene, plan),
                        f"{'estimated steps per point':>28}: {mean_steps:.0f} (mean of a pilot subsample)",
                        f"{'estimated time':>28}: {seconds:.1f} s on this machine (timed pilot)"]

    def summary(self, totals: RunTotals, ds: xr.Dataset) -> list[str]:
        from ...status import flag_summary

        text = flag_summary(ds, "model", totals.counts)
        if "model_error_used" in totals.maxima:
            text += (" (largest estimated error of the quasi-static model where used: "
                     f"{totals.maxima['model_error_used']:.2g})")
        return [flag_summary(ds, "status", totals.counts), text]

    def picture_paths(self, path: str | Path, trajectories: bool, points: int, variable: str | None = None
                      ) -> list[Path]:
        """``path``, and for the transients of a sweep over more than one point ``<path stem>_trajectories.png``."""
        path = Path(path)
        if variable is None and trajectories and points > 1:
            return [path, path.with_name(path.stem + "_trajectories.png")]
        return [path]

    def draw(self, ds: xr.Dataset, path: str | Path, variable: str | None = None) -> list[Path]:
        """The relaxation landscape (slices along the extra axes where the file has them) and, where the file holds
        transients, the transients of up to six points."""
        from ...plot.files import as_K_over_M, has_trajectories, plot_extra_axes, plot_landscape, plot_trajectories
        from ...plot.slices import extra_dims

        ds = as_K_over_M(ds)  # a grid over the laboratory's k [1/m] is drawn over K/M = k g
        if extra_dims(ds):
            return plot_extra_axes(ds, Path(path), variable)
        pictures = self.picture_paths(path, has_trajectories(ds), ds.sizes.get("K_over_M", 1) * ds.sizes.get("V", 1),
                                      variable)
        if variable is not None:
            return [plot_landscape(ds, pictures[0], variable=variable, title=self.title, eq10=True)]
        if has_trajectories(ds) and len(pictures) == 1:
            return [plot_trajectories(ds, pictures[0], title=self.title)]  # one point: its transient is the story
        written = [plot_landscape(ds, pictures[0], title=self.title, eq10=True)]
        if len(pictures) > 1:
            written.append(plot_trajectories(ds, pictures[1], title=self.title))
        return written


def _require_relaxed_slip_only(scene: Scene, what: str, stepper: str) -> None:
    """InputError unless the scene asks for the relaxed slip alone, with the default method, step and precision
    (``what`` computes xi_inf only, with its own ``stepper``)."""
    if scene.observables != ("xi_inf",):
        raise InputError(f"{what} computes the relaxed slip only (observables = ['xi_inf']), got "
                         f"observables={list(scene.observables)}")
    for name, value, default in (("method", scene.method, "auto"), ("step", scene.step, None),
                                 ("precision", scene.precision, "float64")):
        if value != default:
            raise InputError(f"{name} is not used by {what} (its stepper is {stepper}; leave {name} at "
                             f"{default!r}), got {value!r}")


def _plan_text(scene: Scene, plan: Plan) -> str:
    """The plan's text with one line about the model: the scene's (the plan describes the quasi-static pass; with
    model "auto" the inertial points are chosen per point after it)."""
    model = f"{'model':>28}: {scene.model}" + (
        f" (model_tol {scene.model_tol:g}): the quasi-static plan below for every point, then the inertial model "
        "where the estimated error of the quasi-static one is larger" if scene.model == "auto" else "")
    lines = plan.text().splitlines()
    keep = [line for line in lines if line.split(":")[0].strip() != "model"]
    hopf = f"{'hopf_line':>28}: " + ("analytic chi_c and the line located by simulation (driven kernel)"
                                     if scene.simulated_hopf_line else
                                     "analytic chi_c (simulated_hopf_line = true adds the line located by simulation)")
    return "\n".join([model, *keep, hopf])


PROTOCOL = StopProtocol()
