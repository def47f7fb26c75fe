"""Plan: what to model and how to step, decided once per scene ("model only what the scene requires"); the Plan record
of the stop and driven protocols, and the stop's method and step rules.

For the stop scene the model is the quasi-static one (the paper's; with model "auto" the stop protocol solves the
points that need it with inertia, sweep/protocols/stop/model_choice.py), the state is xi alone (plus the quadrature
tau only when a time-resolved observable is asked for), integrated in the scaled log time sigma of
:mod:`sweep.integrate.models.stop`. The method (:func:`choose_method`): for the relaxed slip alone the adaptive
LANES_METHOD (dop853) in lanes, its first trial step from the local tolerance; where a fixed step is asked for (method
rk4, a step, float32), rk4 (ros4 at the stiff points); for values inside the transient the cheapest measured method
of its rtol (sweep.accuracy.AUTO_METHOD). The fixed-step rules:

* the time map is scaled to the point: s_c = 1/(1 + (chi + |mu1|)/A) (stiff start) and the late step follows
  the local rate (mu1 + 2 m2 u)/A (:mod:`sweep.integrate.models.stop`), so that the RK4 error constant is nearly the
  same at every point;
* in lanes each point's step is chosen at run time, down a step ladder (sweep/integrate/ladder.py) from the pilot
  step h0 = min(H_PILOT, PILOT_FACTOR (TARGET rtol / (SHARP_GAIN C))^(1/4)) given here;
* one point per thread, the step h in sigma meets ``rtol`` at each point: h = min(H_MAX, (rtol / (SAFETY * C))^(1/4));
  in both rules C is the largest error constant err/h^4 measured on a calibration set spanning chi/A 1e-2..1e3,
  mu1/A -3..3, m2/A 0..3 (benchmarks/calibrate_rk4.py): C_STABLE where steady sliding is stable (chi > mu1; measured
  max 4.4e-4 as h -> 0, 7.4e-4 at h = 0.7) and C_UNSTABLE on the stick-slip side, where the stop starts on an
  unstable fixed point and the error constant is ~3x larger (measured max 1.7e-3); C is multiplied by
  TIME_RESOLVED_FACTOR when values inside the transient are asked for; tests/plan/test_accuracy.py checks the rule
  against an independent scipy reference.

Every point stops when its closed-form tail is accurate to 0.1 * (rtol xi + atol), so its number of steps follows
from its own dynamics: a few tens on most of the grid, thousands in the costly corner (small chi/A with mu1 < 0 and
small m2, where the slider creeps along a slow manifold).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from .. import physics, protocols
from ..accuracy import (
    AUTO_METHOD,
    C_STABLE,
    C_STIFF,
    C_UNSTABLE,
    COARSE_GAIN,
    CONSERVATIVE_GAIN,
    CTRL_TOL_FACTOR,
    ERROR_GAIN,
    H_MAX,
    H_PILOT,
    LANE_H0_FACTOR,
    LANE_H0_MAX,
    MAX_RATIO,
    MAX_RUNS,
    MIN_RATIO,
    ORDER_WINDOW,
    PILOT_FACTOR,
    RATE_FLOOR,
    SHARP_GAIN,
    STEP_SAFETY,
    STIFF_H_PILOT,
    STIFF_K_MAX,
    STIFF_PILOT_FACTOR,
    STIFF_RATE_FLOOR,
    STIFF_WORK_MIN,
    TAIL_SAFETY,
    TAIL_SHARE,
    TARGET,
    TIME_RESOLVED_FACTOR,
    TOL_RATIO,
    lane_control_tolerance,
)
from ..integrate.models.state_laws import STATE_LAWS
from ..integrate.solvers import METHODS
from ..scene.scene import Scene

__all__ = ["Plan", "PlanStats", "PointParams", "scene_plan_hash", "chunk_size_for", "common_fields", "point_params",
           "make_plan", "choose_method",
           "line_uses_inertia",
           "samples_in_lanes", "stop_plan_for_points"]

LANES_METHOD = "dop853"
"""The embedded pair of the adaptive lanes (model "auto", relaxed slip): fewer attempts than dp5 at every rtol of
1e-4..1e-10 and as cheap at 1e-3 for the same achieved error (measured on the default scene)."""

def chunk_size_for(scene: Scene) -> int:
    """The default chunk size of ``scene``: its protocol's (sweep.protocols.base.Protocol.chunk_size). The layout
    depends on the grid only, never on the machine: a journal resumes anywhere."""
    return protocols.get(scene.protocol).chunk_size(scene)


ROUNDOFF = {np.dtype(np.float64): 2.0 * np.finfo(np.float64).eps, np.dtype(np.float32): 2.0 * np.finfo(np.float32).eps}
"""Rounding error per step, relative (added to the estimate as steps * ROUNDOFF * |xi_inf|)."""


def _step_rule(method: str, lanes: bool) -> str:
    tab = METHODS[method]
    time_map = (f"time map ds/dsigma = 1/(1/(s + s_c) + r), s = int dtau/psi, u = ln psi = s - xi, "
                f"r = sqrt(((mu1 + 2 m2 u)/A)^2 + |m2|/(4 A)) + {RATE_FLOOR}, s_c = 1/(1 + (chi + |mu1|)/A)")
    common = f"{time_map}; stop when the closed-form tail is accurate to {TAIL_SAFETY}*(rtol*xi + atol)"
    if tab.adaptive and lanes:
        return (f"{method} in lanes: adaptive steps in sigma per lane, PI controller on the embedded "
                f"order-{tab.order_hat} estimate, local tolerance tol = rtol min(20, sqrt(1e-3/rtol)), first trial "
                f"step min({LANE_H0_MAX:g}, {LANE_H0_FACTOR:g} tol^(1/{tab.error_order + 1})), each step also taken "
                f"as two half steps for the estimate; {TOL_RATIO:g}x tighter where the estimate exceeds the "
                f"tolerance, at most {MAX_RUNS} runs (sweep/integrate/tolerance_ladder.py); {time_map}; stop when the "
                f"closed-form tail's bound is below {TAIL_SHARE:g} |fine - run| or {TAIL_SAFETY}*(atol + 2^-52 xi)")
    if tab.adaptive:
        return (f"{method}: adaptive steps in sigma, PI controller on the embedded order-{tab.order_hat} estimate, "
                f"local tolerance {CTRL_TOL_FACTOR[method]:g} rtol; " + common)
    if lanes:
        rule = f"({TARGET:g} rtol/({SHARP_GAIN:g} C))**0.25"
        h0 = f"min({H_PILOT:g}, {PILOT_FACTOR:g} {rule})"
        if tab.implicit:
            h0 = f"max({h0}, min({STIFF_H_PILOT:g}, {STIFF_PILOT_FACTOR:g} {rule}))"
        step = (f"step ladder per point (sweep/integrate/ladder.py): pilot pair 2 h0, h0, h0 = {h0}, then rungs "
                f"{MIN_RATIO:g}..{MAX_RATIO:g}x finer aimed at {TARGET:g} x tolerance from the "
                f"point's measured error, at most {MAX_RUNS} runs")
    else:
        step = (f"fixed step h = min({H_MAX / 2}, (rtol/({STEP_SAFETY * ERROR_GAIN:g} C))**0.25), coarse step 2h, "
                f"C times {TIME_RESOLVED_FACTOR:g} when trajectory, slip_at, t50 or t90 are asked for")
    if tab.implicit:
        return (f"{method}: Rosenbrock steps H = h w in contact-age time s, w = 1/(1/(s + s_c) + (g + sqrt(g^2 + "
                f"|m2|/(4A)))/2 + {STIFF_RATE_FLOOR}), g = (mu1 + 2 m2 u)/A; {step}, C = {C_STIFF}; " + common)
    return (f"{method}: steps h in sigma; {step}, C = {C_STABLE} where chi > mu1 (stable sliding) else "
            f"{C_UNSTABLE}; " + common)


def time_scale(k, a):
    """Per-point scale s_c of the early log time, from k = chi/A and a = mu1/A (see module doc)."""
    return 1.0 / (1.0 + k + np.abs(a))


def stiff_points(k, a, b) -> np.ndarray:
    """Points where the Rosenbrock lanes are cheaper than RK4 (:data:`STIFF_K_MAX`), from k = chi/A, a = mu1/A,
    b = m2/A."""
    with np.errstate(divide="ignore", invalid="ignore"):
        work = np.where((a < 0) & (b > 0), np.abs(a) ** 3 / (4.0 * b * k), 0.0)
    return (k <= STIFF_K_MAX) & (work >= STIFF_WORK_MIN)


def pilot_step_for(rtol: float, error_constant, factor: float = PILOT_FACTOR, cap: float = H_PILOT):
    """Fine step h0 of the pilot pair (2 h0, h0) of the lanes' step ladder (sweep/integrate/ladder.py): PILOT_FACTOR
    times the step whose checked estimate (SHARP_GAIN x the error) meets TARGET x rtol at the error constant
    ``error_constant`` (the largest measured), so that the point's own next rung is 2..8x finer."""
    sharp = (TARGET * rtol / (SHARP_GAIN * np.asarray(error_constant))) ** 0.25
    return np.minimum(cap, factor * sharp)


def stiff_pilot_step_for(rtol: float) -> float:
    """Pilot step h0 of the ros4 lanes: the general rule at the bound C_STIFF, or, where that is finer than
    STIFF_H_PILOT, the rule with STIFF_PILOT_FACTOR capped at STIFF_H_PILOT (the coarser of the two). At loose rtol
    the general rule's coarse pilot meets the tolerance at once (rtol 1e-3: 96 steps in all on the costly corner,
    against 164 from h0 = 0.6)."""
    return float(max(pilot_step_for(rtol, C_STIFF), pilot_step_for(rtol, C_STIFF, STIFF_PILOT_FACTOR, STIFF_H_PILOT)))


def rk4_step_for(rtol: float, stable_sliding, time_resolved: bool = False):
    """Fine step in sigma whose error estimate meets ``rtol`` at each point (:func:`_step_rule`), on xi_inf
    alone or, if ``time_resolved``, also on the trajectory, slip_at, t50 and t90."""
    error_constant = np.where(stable_sliding, C_STABLE, C_UNSTABLE) * (TIME_RESOLVED_FACTOR if time_resolved else 1.0)
    return np.minimum(H_MAX / 2, (rtol / (STEP_SAFETY * ERROR_GAIN * error_constant)) ** 0.25)


def samples_in_lanes(scene: Scene) -> bool:
    """Whether the time-resolved points of ``scene`` go through the sampled adaptive lanes
    (sweep/integrate/lanes_sampled.py: LANES_METHOD with its fine twin, samples from its dense output): method "auto"
    in float64 with no step given, aging law, samples only (t50/t90 and explicitly named methods keep the per-point
    path, which also takes the points the lanes fail on and those without a finite relaxed slip)."""
    return (scene.time_resolved and scene.method == "auto" and scene.step is None and scene.precision == "float64"
            and STATE_LAWS[scene.state_law].aging_identity and not {"t50", "t90"} & set(scene.observables))


def choose_method(scene: Scene) -> tuple[str, str]:
    """(method, why): the scene's own choice, or the cheapest measured method for its rtol."""
    if scene.method != "auto":
        return scene.method, "chosen by the scene"
    if scene.step is not None or scene.precision == "float32":
        return "rk4", "auto: fixed step asked for (step or float32)"
    if not scene.time_resolved:
        return LANES_METHOD, ("auto: relaxed slip only, an embedded pair in adaptive lanes "
                              "(benchmarks/peers.py: 2-10x fewer evaluations than the rk4 step ladder)")
    for method, rtol_min in AUTO_METHOD:
        if scene.rtol >= rtol_min:
            return method, f"auto: cheapest measured method of the time-resolved path for rtol >= {rtol_min:g}"
    raise AssertionError("AUTO_METHOD covers every rtol")


PER_POINT = ("point_method", "step", "chi", "mu1", "k", "a", "b", "s_c", "finite", "G", "inertial")
"""The per-point arrays of a Plan (flat over its points)."""


@dataclass(frozen=True, eq=False)
class Plan:
    """The resolved plan of a scene, for every protocol; per-point arrays are flat in C order over the scene's grid
    (K_over_M, V and its extra axes, Scene.dims).

    ``model`` is the scene's model policy and ``inertial`` its per-point part known before any run (driven scene: per
    V, inertial where gamma/A > model_tol with "auto"; stop scene: "inertial" forced); with "auto" a stop point's
    model is decided from its measured error estimate (sweep/protocols/stop/model_choice.py), within the policy
    ``model_tol``.
    """

    protocol: str
    model: str
    model_tol: float
    method: str
    method_reason: str
    point_methods: tuple[str, ...]
    point_method: np.ndarray
    adaptive: bool
    lanes: bool
    dtype: np.dtype
    step: np.ndarray
    step_source: str
    ctrl_tol: float
    rule: str
    max_steps: int
    chi: np.ndarray
    mu1: np.ndarray
    k: np.ndarray
    a: np.ndarray
    b: np.ndarray
    s_c: np.ndarray
    finite: np.ndarray
    tau_samples: np.ndarray
    needs_tau: bool
    G: np.ndarray
    """gamma/A per point (the inertia number over A)."""
    inertial: np.ndarray
    """Per point: the inertial model decided by the policy before any run."""
    chunk_size: int
    state_law: str = "aging"
    sampled_lanes: bool = False
    """Time-resolved points in the sampled adaptive lanes (:func:`samples_in_lanes`); ``method`` is then the per-point
    path's, for the points the lanes leave to it."""
    notes: tuple[tuple[str, str], ...] = ()
    """The description of a protocol other than the stop scene's (:meth:`describe`)."""
    index: np.ndarray | None = None
    """Flat indices in the scene's grid (C order over Scene.dims: i_K n_V + i_V in 2-D) of the points of a plan
    restricted by :meth:`take`; None:
    every point of the scene, in order."""

    @property
    def n_points(self) -> int:
        return self.k.size

    def take(self, points: np.ndarray) -> Plan:
        """The plan of ``points`` only (indices into this plan): what one chunk needs, ~60 bytes a point, so that a
        chunk shipped to a dask worker carries its share of the plan instead of every worker holding all of it."""
        points = np.asarray(points)
        return replace(self, **{name: getattr(self, name)[points] for name in PER_POINT},
                       index=self.flat_index(points))

    def flat_index(self, points: np.ndarray) -> np.ndarray:
        """Flat indices in the scene's grid of this plan's ``points`` (for lookups along the scene's axes)."""
        points = np.asarray(points)
        return points if self.index is None else self.index[points]

    @property
    def tableau(self):
        return METHODS[self.method]

    @property
    def order(self) -> int:
        return self.tableau.order

    @property
    def roundoff(self) -> float:
        return float(ROUNDOFF[np.dtype(self.dtype)])

    def stats(self) -> PlanStats:
        """What :meth:`describe` counts over the plan's points, mergeable over the chunks of a run (PlanStats)."""
        finite_steps = self.step[np.isfinite(self.step)]
        return PlanStats(points=self.n_points,
                         step_min=float(finite_steps.min()) if finite_steps.size else np.nan,
                         step_max=float(finite_steps.max()) if finite_steps.size else np.nan,
                         not_finite=int(np.count_nonzero(~self.finite)),
                         methods=tuple((m, int(np.count_nonzero(self.point_method == i)))
                                       for i, m in enumerate(self.point_methods)))

    def describe(self, stats: PlanStats | None = None) -> dict[str, str]:
        """Human-readable summary, also stored in the Dataset attrs; ``stats``: the counts of the whole scene (its
        chunks' :meth:`stats` merged) where this plan is one chunk's."""
        if self.notes:
            return dict(self.notes)
        stats = stats or self.stats()
        step = (f"{stats.step_min:.6g}..{stats.step_max:.6g}" if stats.step_min < stats.step_max
                else f"{stats.step_min:.6g}")
        methods = stats.method_names(self.method)
        text = {
            "model": _model_policy(self.model, self.model_tol),
            "state_law": self.state_law,
            "state": ("xi (u = s - xi)" + (" + tau quadrature" if self.needs_tau else "") if self.aging_identity
                      else "(xi, u) in the phase plane, then xi in t = 1/u (docs/physics.md 7.3)"),
            "method": f"{self.method} ({self.method_reason})" + "".join(
                f"; {m} at {stats.count(m)} stiff points (chi/A <= {STIFF_K_MAX:g}, mu1 < 0, m2 > 0, "
                f"|mu1/A|^3/(4 m2 chi/A^2) >= {STIFF_WORK_MIN:g})" for m in methods[1:]),
            "stepper": (("adaptive" if self.adaptive else "fixed-step")
                        + (f", {self.dtype.name} lanes" if self.lanes else ", one point per thread")),
            **({"sampled_lanes": f"{LANES_METHOD} in adaptive lanes with its fine twin, each sample read off the dense "
                                 "output of the step that holds it (sweep/integrate/lanes_sampled.py), 2 |fine - run| "
                                 f"+ roundoff a sample; {self.method} one point per thread only where the lanes fail "
                                 "or no finite relaxed slip exists"} if self.sampled_lanes else {}),
            "step": (f"first trial {step} in sigma, local tolerance {self.ctrl_tol:.3g}" if self.adaptive
                     else f"{step} in sigma ({self.step_source})"),
            "error_estimate": ((f"each run with a fine twin on its mesh halved, in the same lanes "
                                f"(sweep/integrate/tolerance_ladder.py): the run returned, {COARSE_GAIN:g} "
                                "|fine - run| + 2 x both tail bounds + roundoff"
                                if self.lanes and self.adaptive else
                                "step ladder per point (sweep/integrate/ladder.py): finest run returned, "
                                f"{SHARP_GAIN:g} x Richardson at the order q observed on the last three "
                                f"runs where |q - p| <= {ORDER_WINDOW:g}, else {CONSERVATIVE_GAIN:g} "
                                "max(|x_b - x_a|, |x_c - x_b|); + 2 x tail bound + roundoff" if self.lanes else
                                "Richardson pair per point (coarse mesh, same mesh halved): coarse run returned, "
                                "2 |coarse - fine| + bound on cancelled contributions (integrate/stop_point.py)")
                               + ": <name>_error variables"),
            "step_rule": (self.rule if methods == self.point_methods
                          else "; ".join(_step_rule(m, self.lanes) for m in methods)),
            "max_steps": str(self.max_steps),
            "horizon": "per point: until the closed-form tail is accurate (and all requested times are passed)",
            "points": str(stats.points),
            "points_without_finite_limit": str(stats.not_finite),
        }
        if not self.aging_identity:  # the general path (its rule says the rest)
            text.update(step=f"adaptive, local tolerance {self.ctrl_tol:.3g}",
                        error_estimate="from the solutions at three local tolerances (step_rule): <name>_error "
                                       "variables",
                        horizon="exact: xi at t = 1/u = 0")
        return text

    @property
    def aging_identity(self) -> bool:
        """Whether the plan's state law has the aging identity xi + u = s (the one-state stop paths)."""
        return STATE_LAWS[self.state_law].aging_identity

    def points_of(self, method: str) -> np.ndarray:
        """Flat indices of the points integrated with ``method``."""
        return np.flatnonzero(self.point_method == self.point_methods.index(method))

    def text(self) -> str:
        return "\n".join(f"{k:>28}: {v}" for k, v in self.describe().items())


class PlanStats(NamedTuple):
    """The counts of a plan that its description states (Plan.describe), over one chunk or, merged with ``+``,
    over every chunk of a run."""

    points: int
    step_min: float
    step_max: float
    not_finite: int
    """Points without a finite relaxed slip."""
    methods: tuple[tuple[str, int], ...]
    """(method, points) of each method used (the plan's own method first, counted even at 0 points)."""

    def count(self, method: str) -> int:
        return sum(n for m, n in self.methods if m == method)

    def method_names(self, first: str) -> tuple[str, ...]:
        """``first`` (the plan's method), then every other method with points, in the order met."""
        return (first,) + tuple(dict.fromkeys(m for m, n in self.methods if m != first and n > 0))

    def __add__(self, other: PlanStats) -> PlanStats:  # type: ignore[override]
        counts: dict[str, int] = {}
        for m, n in self.methods + other.methods:
            counts[m] = counts.get(m, 0) + n
        return PlanStats(self.points + other.points, float(np.fmin(self.step_min, other.step_min)),
                         float(np.fmax(self.step_max, other.step_max)), self.not_finite + other.not_finite,
                         tuple(counts.items()))


def scene_plan_hash(scene: Scene) -> str:
    """Digest of what determines a run's numbers besides sweep's own code (the journal adds the sources' digest):
    the scene (its canonical TOML: every parameter, axis value, setting and protocol field) and the values of the
    calibrated constants (sweep/accuracy.py). Computed from the scene alone, in microseconds whatever the grid's size:
    each chunk's plan follows from the scene by the rules of this module."""
    from .. import accuracy

    constants = sorted((k, v) for k, v in vars(accuracy).items() if k.isupper())
    return hashlib.sha256(repr((scene.to_toml(), constants)).encode()).hexdigest()[:16]


def line_uses_inertia(gamma_over_A: np.ndarray, model: str, model_tol: float) -> np.ndarray:
    """Per V: whether the Hopf line / driven points use the inertial model. Inertia shifts the line
    chi_c = mu1 (1 + gamma/A) by exactly gamma/A relative (linear theory), so with "auto" the inertial model is used
    where gamma/A > model_tol."""
    g = np.asarray(gamma_over_A, dtype=float)
    if model == "auto":
        return g > model_tol
    return np.full(g.shape, model == "inertial")


def _model_policy(model: str, model_tol: float) -> str:
    """What a stop plan says of the model (the same words as the Dataset's plan_model)."""
    if model != "auto":
        return model
    return (f"auto (model_tol {model_tol:g}): per point, inertial where the estimated error of the quasi-static model "
            f"is larger (variable model)")


class PointParams(NamedTuple):
    """Per-point physical inputs of a stop or driven plan, flat arrays of one length (reduced where marked)."""

    chi: np.ndarray
    """Reduced stiffness chi = K D0/(M g) [1]."""
    mu1: np.ndarray
    """mu1(V) = m1 - 2 m2 ln(V/V0) [1]."""
    A: np.ndarray
    """Direct-effect coefficient [1]."""
    m2: np.ndarray
    """Curvature of mu_d [1]."""
    G: np.ndarray
    """gamma/A = V^2/(g D0 A) [1]."""

    @property
    def reduced(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(k, a, b) = (chi, mu1, m2)/A (docs/physics.md 2)."""
        return self.chi / self.A, self.mu1 / self.A, self.m2 / self.A


def point_params(scene: Scene) -> PointParams:
    """The per-point inputs, flat in C order over the scene's grid (K_over_M, V and its extra axes: each point
    with its own A, m1, m2, D0 where the scene sweeps them). Each formula is evaluated per point, so a point's
    inputs are the same numbers whatever the other axes."""
    at = {name: scene.broadcast(name) for name in ("K_over_M", "V", "A", "m1", "m2", "D0", "V0", "g")}
    flat = lambda x: np.broadcast_to(x, scene.shape).ravel().copy()  # noqa: E731
    chi = flat(physics.reduced_stiffness(at["K_over_M"], at["D0"], at["g"]))
    mu1 = flat(physics.mu1(at["V"], at["m1"], at["m2"], at["V0"]))
    G = flat(physics.inertia_number(at["V"], at["D0"], at["g"]) / at["A"])
    return PointParams(chi, mu1, flat(at["A"]).astype(float), flat(at["m2"]).astype(float), G)


def common_fields(scene: Scene, chi, mu1, k, a, b, G, finite, inertial) -> dict:
    """The fields of a Plan that every protocol fills the same way."""
    return dict(protocol=scene.protocol, model=scene.model, model_tol=scene.model_tol, max_steps=int(scene.max_steps),
                chi=chi, mu1=mu1, k=k, a=a, b=b, s_c=time_scale(k, a), finite=finite, G=G, inertial=inertial,
                chunk_size=chunk_size_for(scene), state_law=scene.state_law)


def finite_relaxed_slip(a: np.ndarray, b: np.ndarray, state_law: str = "aging") -> np.ndarray:
    """Where the relaxed slip is finite, from a = mu1/A and b = m2/A (the law's StateLaw.finite_relaxed_slip)."""
    return STATE_LAWS[state_law].finite_relaxed_slip(a, b)


def _general_plan(scene: Scene, chi, mu1, k, a, b, G, finite) -> Plan:
    """The plan of a state law without the aging identity: the general two-state path of sweep/integrate/stop_slip.py
    (dp5, PI controller, a pair of tolerances per point)."""
    from ..accuracy import GENERAL_ESTIMATE_GAIN, TIGHTER

    return Plan(method="dp5", method_reason=f"general two-state path of the {scene.state_law} law",
                point_methods=("dp5",), point_method=np.zeros(k.size, np.int8), adaptive=True, lanes=False,
                dtype=np.dtype(np.float64), step=np.full(k.size, np.nan), step_source="controller",
                ctrl_tol=scene.rtol / TIGHTER**2,
                rule=(f"dp5 (adaptive, PI controller) on du/dxi = (chi xi + mu1 u + m2 u^2)/A from (0, 0), then on "
                      f"dxi/dt = -1/(b + a t + k xi t^2) in t = 1/u to t = 0; local tolerances rtol/{TIGHTER:g}, "
                      f"rtol/{TIGHTER**2:g}, rtol/{TIGHTER**3:g}, the middle one returned, {GENERAL_ESTIMATE_GAIN:g} x "
                      f"the larger difference to its neighbours its error estimate"),
                tau_samples=scene.tau_samples, needs_tau=False,
                **common_fields(scene, chi, mu1, k, a, b, G, finite, np.zeros(k.size, bool)))


def make_plan(scene: Scene) -> Plan:
    """What to model and how to step for every point of ``scene``: its protocol's plan
    (sweep.protocols.base.Protocol.make_plan)."""
    return protocols.get(scene.protocol).make_plan(scene)


def stop_plan_for_points(scene: Scene, points: PointParams) -> Plan:
    """The stop plan of ``scene``'s settings (rtol, method, observables, model, state law) for the flat per-point
    inputs ``points`` instead of the scene's (K/M, V) grid: every point may have its own A, m2, chi and mu1 (the
    forward model of sweep.fit). Only the per-point arrays come from ``points``; ``index`` is left None."""
    chi, mu1, G = points.chi, points.mu1, points.G
    k, a, b = points.reduced
    finite = finite_relaxed_slip(a, b, scene.state_law)
    if not STATE_LAWS[scene.state_law].aging_identity:
        return _general_plan(scene, chi, mu1, k, a, b, G, finite)
    method, reason = choose_method(scene)
    tab = METHODS[method]
    # relaxed slip alone runs in lanes: fixed-step methods, and the embedded pair that "auto" picks (an explicitly
    # named dp5 or dop853 keeps the per-point path and its Richardson pair)
    lanes = not scene.time_resolved and (not tab.adaptive or scene.method == "auto")
    ctrl_tol = (lane_control_tolerance(scene.rtol) if lanes and tab.adaptive
                else scene.rtol * CTRL_TOL_FACTOR.get(method, 1.0))
    stable = physics.stable_sliding(chi, mu1, points.A)
    if tab.adaptive:
        scale = ctrl_tol ** (1.0 / (tab.error_order + 1))  # the step whose local error is ~ctrl_tol
        h0 = min(LANE_H0_MAX, LANE_H0_FACTOR * scale) if lanes else min(0.5, scale)
        step, source = np.full(k.size, h0), "controller"
    elif scene.step is not None:
        step, source = np.full(k.size, scene.step), "override"
    elif lanes:
        step = (stiff_pilot_step_for(scene.rtol) * np.ones(k.size) if tab.implicit
                else pilot_step_for(scene.rtol, np.where(stable, C_STABLE, C_UNSTABLE)))
        source = "rule"
    else:
        step, source = rk4_step_for(scene.rtol, stable, scene.time_resolved), "rule"
    point_methods, point_method = (method,), np.zeros(k.size, np.int8)
    if scene.method == "auto" and lanes and method == "rk4":
        stiff = stiff_points(k, a, b) & finite
        if stiff.any():
            point_methods, point_method = ("rk4", "ros4"), stiff.astype(np.int8)
            if scene.step is None:
                step = np.where(stiff, stiff_pilot_step_for(scene.rtol), step)
    return Plan(
        method=method,
        method_reason=reason,
        point_methods=point_methods,
        point_method=point_method,
        adaptive=tab.adaptive,
        lanes=lanes,
        dtype=np.dtype(scene.precision),
        step=step,
        step_source=source,
        ctrl_tol=ctrl_tol,
        rule="; ".join(_step_rule(m, lanes) for m in point_methods),
        tau_samples=scene.tau_samples,
        needs_tau=scene.time_resolved,
        sampled_lanes=samples_in_lanes(scene),
        **common_fields(scene, chi, mu1, k, a, b, G, finite, finite & (scene.model == "inertial")),
    )
