"""The plan of a history scene and its chunks: per point the reduced inputs, two runs of the load-history driver
(sweep/integrate/history.py) at local tolerances rtol/TIGHTER and rtol/TIGHTER^2, and the observables read off the
tighter run, each with the difference to the looser run as its error estimate; where the scene asks for mu_t, the
runs are those of the dense-output driver, which also give mu at the times t_obs (sweep/protocols/history/sampled.py),
and at the points that need inertia those of the inertial driver (sweep/protocols/history/inertial.py)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from ... import physics
from ...accuracy import TIGHTER
from ...plan.plan import point_params
from ...scene.scene import Scene
from ...status import Status
from .healing import healing_rate, hold_before, is_series
from .inertial import inertial_points, run_inertial
from .sampled import read_samples, run_sampled
from .segments import reduced_durations, segment_values

__all__ = ["DEFAULT_CHUNK", "OBSERVABLES", "HistoryPlan", "history_chunk", "history_plan", "read_off"]

OBSERVABLES = ("mu_end", "delta_mu_ss", "delta_mu_peak", "delta_mu_relax")
"""What a history point yields per segment (docs/physics.md, "Load histories")."""
DEFAULT_CHUNK = 256
"""Points per chunk (a history point costs about as much as a driven one, times its segments)."""


@dataclass(frozen=True)
class HistoryPlan:
    """Per-point inputs of a history scene (flat in the grid's C order) and the run's settings."""

    k: np.ndarray
    """chi/A."""
    a: np.ndarray
    """mu1(V)/A."""
    b: np.ndarray
    """m2/A."""
    A: np.ndarray
    """Direct-effect coefficient (the unit of s)."""
    mu_ref: np.ndarray
    """mu_d(V): the steady friction at the grid's V (paper eq. 6)."""
    durations: np.ndarray
    """Reduced durations V t_j/D0, (points, segments)."""
    ratios: np.ndarray
    """Load-point velocity / V, (points, segments) (a V_ratio axis makes it differ between points)."""
    state_law: str
    rtol: float
    max_steps: int
    perturbation: float
    chunk_size: int
    scale: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """V/D0 per point [1/s]: reduced time per second."""
    t_obs: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """Times [s] from the history's start of the observable mu_t (empty: not asked for)."""
    G: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """gamma/A at the grid's V per point (gamma = V^2/(g D0))."""
    inertial: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    """Per point: run with inertia (sweep.protocols.history.inertial.inertial_points)."""
    model: str = "quasistatic"
    healing: bool = False
    """Whether the chunk yields the healing rate beta (the history is a slide-hold-slide series, healing.is_series)."""

    @property
    def n_points(self) -> int:
        return self.k.size

    def take(self, rows: np.ndarray) -> HistoryPlan:
        return replace(self, k=self.k[rows], a=self.a[rows], b=self.b[rows], A=self.A[rows],
                       mu_ref=self.mu_ref[rows], durations=self.durations[rows], ratios=self.ratios[rows],
                       scale=self.scale[rows], G=self.G[rows], inertial=self.inertial[rows])

    def describe(self) -> dict[str, str]:
        models = {"quasistatic": "quasistatic",
                  "inertial": "inertial (RODAS3 on (s, u, ln xi', tau) in a plunge-resolving time, I control)",
                  "auto": "per point: inertial (RODAS3) where some segment's gamma/A exceeds model_tol or where "
                          "the quasi-static run runs away (slip velocity > 1e8 V, aging law), else quasistatic"}
        return {"model": f"{models[self.model]}, {self.state_law} law",
                "method": f"dp5 (adaptive, I control) on (s = (mu - mu_d(V))/A, u = ln psi), segment by segment, at "
                          f"local tolerances rtol/{TIGHTER:g} and rtol/{TIGHTER**2:g}: the tighter run's values, their "
                          f"difference as error estimate",
                "perturbation": f"z(0) = {self.perturbation:g} beyond steady sliding at the first segment's velocity"}


def history_plan(scene: Scene) -> HistoryPlan:
    """The plan of a history scene over its grid (sweep.protocols.history)."""
    pts = point_params(scene)
    k, a, b = pts.reduced
    flat = lambda name: np.broadcast_to(scene.broadcast(name), scene.shape).ravel().astype(float)  # noqa: E731
    V, D0 = flat("V"), flat("D0")
    p = scene.params
    mu_ref = physics.mu_d(V, p.m0, flat("m1"), flat("m2"), p.V0)
    table = segment_values(scene.options.segments, flat, V.size)  # per point: a segment's number may be an axis
    return HistoryPlan(k=k, a=a, b=b, A=pts.A, mu_ref=np.asarray(mu_ref, float),
                       durations=reduced_durations(table, V, D0),
                       ratios=table["V_ratio"], state_law=scene.state_law, rtol=scene.rtol,
                       max_steps=int(scene.max_steps), perturbation=float(scene.options.perturbation),
                       chunk_size=DEFAULT_CHUNK, scale=V / D0,
                       t_obs=np.asarray(scene.options.get("t_obs", ()) if "mu_t" in scene.observables else (), float),
                       G=pts.G, inertial=inertial_points(scene.model, pts.G, table["V_ratio"], scene.model_tol),
                       model=scene.model,
                       healing="delta_mu_peak" in scene.observables and is_series(scene.options.segments))


def read_off(rec: dict[str, np.ndarray], ratios: np.ndarray, a: np.ndarray, b: np.ndarray, A: np.ndarray,
             mu_ref: np.ndarray) -> dict[str, np.ndarray]:
    """The observables (points, segments) from one run's records: mu at each segment's end; the steady-state jump
    from the previous segment where both end in steady sliding; the peak after a hold above the steady friction at
    the reslide velocity; the relaxation during a hold (NaN where a segment has no such value)."""
    A_, a_, b_ = A[:, None], a[:, None], b[:, None]
    r = np.atleast_2d(ratios)  # (points, segments), or (segments,) shared by every point
    prev = np.concatenate([np.full((r.shape[0], 1), np.nan), r[:, :-1]], axis=1)
    steady = rec["steady"].astype(bool)
    both = steady & np.concatenate([np.zeros_like(steady[:, :1]), steady[:, :-1]], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        lr = np.log(np.where(r > 0, r, 1.0))
        s_ss = -a_ * lr + b_ * lr**2
        jump = rec["s_end"] - np.concatenate([np.full_like(rec["s_end"][:, :1], np.nan), rec["s_end"][:, :-1]], axis=1)
    return {"mu_end": mu_ref[:, None] + A_ * rec["s_end"],
            "delta_mu_ss": np.where(both, A_ * jump, np.nan),
            "delta_mu_peak": np.where((r > 0) & (prev == 0), A_ * (rec["s_peak"] - s_ss), np.nan),
            "delta_mu_relax": np.where(r == 0, A_ * (rec["s_start"] - rec["s_end"]), np.nan)}


def _add_samples(out: dict[str, np.ndarray], samples: dict[str, np.ndarray]) -> None:
    """mu_t and its error into a chunk's outputs; a point's status becomes the samples' where it was ok, or where
    the samples' run failed (max_steps, step_underflow) and the records' only missed the tolerance."""
    out["mu_t"], out["mu_t_error"] = samples["mu_t"], samples["mu_t_error"]
    failed = np.isin(samples["status"], (Status.MAX_STEPS, Status.STEP_UNDERFLOW))
    take = (out["status"] == Status.OK) | ((out["status"] == Status.ERROR_ABOVE_TOL) & failed)
    out["status"] = np.where(take, samples["status"], out["status"]).astype(np.int8)
    out["steps"] = out["steps"] + samples["steps"]


def history_chunk(scene: Scene, plan: HistoryPlan) -> Callable[[np.ndarray], dict[str, np.ndarray]]:
    """compute(points) -> per-point arrays (observables and their errors (points, segments); mu_t and its error
    (points, times) where asked for; the healing rate beta and its error of a slide-hold-slide series; model,
    status, steps). With model "auto" (aging law) a point whose quasi-static runs ran away (quasistatic_breakdown)
    is run again with inertia, its steps the sum of both."""

    def compute(points: np.ndarray) -> dict[str, np.ndarray]:
        inert = plan.inertial[points].copy()
        if not points.size:
            return {**_outputs(plan, points, run_inertial), "model": np.zeros(0, np.int8)}
        out: dict[str, np.ndarray] = {}
        for rows, run in ((np.flatnonzero(~inert), run_sampled), (np.flatnonzero(inert), run_inertial)):
            _merge(out, rows, run, plan, points)
        if plan.model == "auto" and plan.state_law == "aging":  # the quasi-static runaway: inertia is needed there
            again = np.flatnonzero((out["status"] == Status.QUASISTATIC_BREAKDOWN) & ~inert)
            if again.size:
                steps = out["steps"][again]
                _merge(out, again, run_inertial, plan, points)
                out["steps"][again] += steps
                inert[again] = True
        out["model"] = inert.astype(np.int8)
        if plan.healing:
            t_hold = hold_before(plan.ratios[points], plan.durations[points] / plan.scale[points, None])
            out["beta"], out["beta_error"] = healing_rate(out["delta_mu_peak"], out["delta_mu_peak_error"], t_hold)
        return out

    return compute


def _merge(out: dict[str, np.ndarray], rows: np.ndarray, run: Callable, plan: HistoryPlan, points: np.ndarray
           ) -> None:
    """The outputs of ``run`` (:func:`_outputs`) at the chunk's ``points[rows]`` into ``out`` (arrays over all the
    chunk's points, made on first use); nothing where ``rows`` is empty."""
    if not rows.size:
        return
    for name, x in _outputs(plan, points[rows], run).items():
        if name not in out:
            out[name] = np.empty((points.size, *x.shape[1:]), x.dtype)
        out[name][rows] = x


def _outputs(plan: HistoryPlan, points: np.ndarray, run: Callable) -> dict[str, np.ndarray]:
    """The chunk's outputs for ``points`` from two runs of ``run``: quasi-static
    sweep.protocols.history.sampled.run_sampled or sweep.protocols.history.inertial.run_inertial (both also sample s
    at the scene's t_obs, where it has any)."""
    loose, tight = (run(plan, points, plan.rtol / TIGHTER**e) for e in (1, 2))
    args = (plan.ratios[points], plan.a[points], plan.b[points], plan.A[points], plan.mu_ref[points])
    values, looser = read_off(tight, *args), read_off(loose, *args)
    status = np.where(tight["status"] != Status.OK, tight["status"], loose["status"]).astype(np.int8)
    out: dict[str, np.ndarray] = {"status": status, "steps": tight["steps"] + loose["steps"]}
    above = np.zeros(points.size, bool)
    for name in OBSERVABLES:
        err = np.abs(values[name] - looser[name])
        err = np.where(np.isnan(values[name]), np.nan, np.where(np.isnan(err), np.inf, err))
        above |= np.any(err > plan.rtol * (np.abs(values[name]) + plan.A[points, None]), axis=1)
        out[name], out[f"{name}_error"] = values[name], err
    out["status"] = np.where((status == Status.OK) & above, np.int8(Status.ERROR_ABOVE_TOL), status)
    if plan.t_obs.size:
        _add_samples(out, read_samples(loose["s_t"], tight["s_t"], loose["status"], tight["status"],
                                       plan.A[points], plan.mu_ref[points], plan.rtol, 0))
    return out
