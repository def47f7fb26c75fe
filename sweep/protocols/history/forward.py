"""The friction of a load history at given times, for many parameter sets at once: the forward model of fits to
laboratory records (docs/physics.md 7b; sweep.fit builds on :func:`friction_at`).

Each parameter set is reduced with the first segment's velocity V = velocities[0] (section 2: xi = x/D0,
tau = V t/D0; k = chi/A, a = mu1(V)/A, b = m2/A) and integrated in s = (mu - mu_d(V))/A twice, at local tolerances
rtol/10 and rtol/100: quasi-statically by the dense-output dp5 (sweep/integrate/history_dense.py), or, where
gamma/A at the fastest segment exceeds INERTIA_LIMIT or where the quasi-static run runs away (slip velocity past
1e8 V: a spring softer than critical, k < (b - a)/Dc, whose records are stick-slip sawtooths) (aging law), with
inertia by RODAS3
(sweep/integrate/history_inertial.py; s is then the spring's force, the friction a laboratory measures). The
friction is the tighter run's mu = mu_d(V) + A s; its error estimate the difference of the two runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ... import physics
from ...errors import InputError
from ...status import Status

__all__ = ["INERTIA_LIMIT", "PARAMS", "FrictionSamples", "LoadHistory", "friction_at", "sample_friction",
           "sample_friction_rows"]

PARAMS = ("A", "m1", "m2", "D0", "m0", "V0", "K_over_M")
"""The parameters friction_at needs (``g`` optional, 9.81 m s-2)."""
INERTIA_LIMIT = 0.01
"""gamma/A = v^2/(g D0 A) at the fastest segment above which inertia matters: such a set runs the inertial model
(aging law); with the slip law, which has none, its status is quasistatic_breakdown (quasi-static values kept for
inspection)."""
RTOL_RANGE = (1e-10, 1e-2)
_BREAKDOWN = int(Status.QUASISTATIC_BREAKDOWN)  # (a plain int: numpy compares an IntEnum ~8x slower, ~5 us)


def _vector(name: str, value: ArrayLike) -> np.ndarray:
    try:
        x = np.array(value, dtype=float, ndmin=1)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a 1-D array of numbers, got {value!r}") from None
    if x.ndim != 1 or x.size == 0:
        raise InputError(f"{name} must be a non-empty 1-D array, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise InputError(f"{name} must be finite, got {x[~np.isfinite(x)][0]!r}")
    return x


@dataclass(frozen=True)
class LoadHistory:
    """A piecewise-constant load-point velocity: segment j moves the load point at ``velocities[j]`` [m/s] (0: a
    hold) for ``durations[j]`` [s]. The history starts in steady sliding at velocities[0] > 0."""

    velocities: np.ndarray
    """Load-point velocity per segment [m/s], >= 0, the first > 0."""
    durations: np.ndarray
    """Duration per segment [s], > 0."""

    def __post_init__(self) -> None:
        v, d = _vector("velocities", self.velocities), _vector("durations", self.durations)
        if v.size != d.size:
            raise InputError(f"durations must have one entry per segment ({v.size} velocities), got {d.size}")
        if np.any(v < 0):
            raise InputError(f"velocities must be >= 0 m/s (allowed range: 0 <= v < inf), got {v[v < 0][0]!r}")
        if v[0] <= 0:
            raise InputError(f"velocities[0] must be > 0 m/s (the history starts in steady sliding), got {v[0]!r}")
        if np.any(d <= 0):
            raise InputError(f"durations must be > 0 s (allowed range: 0 < t < inf), got {d[d <= 0][0]!r}")
        object.__setattr__(self, "velocities", v)
        object.__setattr__(self, "durations", d)

    @property
    def total(self) -> float:
        """The history's length [s]."""
        return float(np.sum(self.durations))


@dataclass(frozen=True)
class FrictionSamples:
    """The friction of each parameter set at the requested times."""

    mu: np.ndarray
    """(n_sets, n_t) friction coefficient at the times [1] (the run at local tolerance rtol/100)."""
    error: np.ndarray
    """(n_sets, n_t) its error estimate [1]: |the run at rtol/100 - the run at rtol/10|."""
    status: np.ndarray
    """(n_sets,) int8 sweep.Status: ok, max_steps, step_underflow (values NaN from the failure on),
    error_above_tol (some error estimate above rtol (|mu| + A)), quasistatic_breakdown (slip law only: gamma/A >
    INERTIA_LIMIT at the fastest segment, or the quasi-static run ran away, values NaN from there on)."""
    steps: np.ndarray
    """(n_sets,) accepted and rejected steps of both runs."""
    model: np.ndarray | None = None
    """(n_sets,) int8: 0 the quasi-static model, 1 the inertial one (sweep.status.MODEL_FLAG)."""


def _params(params: Mapping[str, ArrayLike]) -> dict[str, np.ndarray]:
    missing = [name for name in PARAMS if name not in params]
    if missing:
        raise InputError(f"params is missing {missing}; needed: {list(PARAMS)} (and optionally g)")
    unknown = sorted(set(params) - set(PARAMS) - {"g"})
    if unknown:
        raise InputError(f"params has unknown name(s) {unknown}; allowed: {list(PARAMS)} and g")
    names = [*PARAMS, "g"]
    raw = {name: np.asarray(params.get(name, 9.81), dtype=float) for name in names}
    for name, x in raw.items():
        if x.ndim > 1:
            raise InputError(f"params[{name!r}] must be a number or a 1-D array (one per set), got shape {x.shape}")
    try:
        arrays = np.broadcast_arrays(*raw.values())
    except ValueError:
        raise InputError(f"params' arrays must broadcast to one length (n_sets), got sizes "
                         f"{ {n: x.size for n, x in raw.items()} }") from None
    out = {name: np.ascontiguousarray(x, dtype=float).reshape(-1) for name, x in zip(names, arrays)}
    for name, x in out.items():
        if not np.all(np.isfinite(x)):
            raise InputError(f"params[{name!r}] must be finite, got {x[~np.isfinite(x)][0]!r}")
        if name in ("A", "D0", "V0", "K_over_M", "g") and np.any(x <= 0):
            raise InputError(f"params[{name!r}] must be > 0 (allowed range: 0 < {name} < inf), got {x[x <= 0][0]!r}")
    return out


def _times(t: ArrayLike, total: float) -> np.ndarray:
    times = _vector("t", t)
    if np.any(np.diff(times) < 0):
        raise InputError("t must be sorted (non-decreasing times from the history's start)")
    if times[0] < 0 or times[-1] > total * (1 + 1e-12):
        raise InputError(f"t must lie in [0, {total:g}] s (the history's length), got [{times[0]:g}, {times[-1]:g}]")
    return np.minimum(times, total)


def friction_at(params: Mapping[str, ArrayLike], load: LoadHistory, t: ArrayLike, *, state_law: str = "aging",
                rtol: float = 1e-6, max_steps: int = 1_000_000, stretch: float = 0.0,
                inertia: str = "auto", estimates: bool = True) -> FrictionSamples:
    """Friction mu(t) of a spring-slider under the load history ``load`` at the times ``t`` [s] from its start
    (sorted, in [0, load.total]), for every parameter set of ``params`` in one compiled call.

    ``params``: A, m1, m2 [1], D0 [m], m0 [1], V0 [m/s] (paper eqs. 1, 6), K_over_M [s-2] (and g [m s-2], 9.81
    unless given), each a number or an array; they broadcast to (n_sets,). The history starts in steady sliding at
    velocities[0] with the spring stretched ``stretch`` [m] beyond it (mu raised by K/(M g) x stretch). The
    quasi-static equations of docs/physics.md 7b, or with inertia (aging law) for the sets where gamma/A at the
    fastest segment exceeds INERTIA_LIMIT and those whose quasi-static run breaks down (the runaway of a spring
    softer than critical: a stick-slip record) (``model`` of the result); ``state_law`` "aging" or "slip" (a
    slip-law set that would need inertia keeps the status quasistatic_breakdown, its values NaN from the runaway
    on). ``rtol``: the relative accuracy asked of mu in units of (|mu| + A); ``max_steps``: the step budget of one
    run over all segments. ``inertia`` "auto" (the above) or "breakdown": inertia only for the sets whose
    quasi-static run breaks down, whatever gamma/A (a machine whose inertia is negligible while it slides steadily,
    g the one its slips need: sweep.fit's records without a given g). ``estimates`` False: the tighter run alone
    (half the work; ``error`` NaN, and no error_above_tol: the rounds of a fit, whose best fits are checked with
    estimates).
    """
    from ...integrate.models.history import LAW_CODES

    if state_law not in LAW_CODES:
        raise InputError(f"state_law must be one of {sorted(LAW_CODES)}, got {state_law!r}")
    if inertia not in ("auto", "breakdown"):
        raise InputError(f"inertia must be 'auto' or 'breakdown', got {inertia!r}")
    if not isinstance(load, LoadHistory):
        raise InputError(f"load must be a LoadHistory, got {type(load).__name__}")
    rtol = float(rtol)
    if not RTOL_RANGE[0] <= rtol <= RTOL_RANGE[1]:
        raise InputError(f"rtol must be in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}], got {rtol!r}")
    if isinstance(max_steps, bool) or int(max_steps) != max_steps or max_steps < 1:
        raise InputError(f"max_steps must be an integer >= 1, got {max_steps!r}")
    stretch = float(stretch)
    if not math.isfinite(stretch):
        raise InputError(f"stretch must be finite [m], got {stretch!r}")
    return sample_friction(_params(params), load, _times(t, load.total), state_law, rtol, int(max_steps), stretch,
                           inertia, bool(estimates))


def sample_friction(p: dict[str, np.ndarray], load: LoadHistory, times: np.ndarray, state_law: str, rtol: float,
                    max_steps: int, stretch: float, inertia: str, estimates: bool) -> FrictionSamples:
    """:func:`friction_at` of checked arguments: ``p`` a float array (n_sets,) for each name of PARAMS and g,
    ``times`` sorted in [0, load.total] (a record fit's rounds, whose sets lie within their bounds, call it without
    the checks: ~0.1 ms a call of ~0.3)."""
    n = p["A"].size
    k, a, b, A, mu_ref, s_kick, ratios, durations, scale, G, fastest = _reduced(
        p, np.repeat(load.velocities[None, :], n, axis=0), np.repeat(load.durations[None, :], n, axis=0), stretch)
    inertial = (fastest > INERTIA_LIMIT) & (inertia == "auto")
    quasistatic = np.flatnonzero(~inertial if state_law == "aging" else np.ones(A.size, bool))
    if quasistatic.size == A.size:  # every set (a fit's rounds): the quasi-static run's arrays are the result's
        out = _quasistatic(k, a, b, A, mu_ref, state_law, s_kick, ratios, durations, scale, G, times, rtol,
                           max_steps, estimates)
    else:
        out = {"mu_t": np.full((A.size, times.size), np.nan), "mu_t_error": np.full((A.size, times.size), np.nan),
               "status": np.zeros(A.size, np.int8), "steps": np.zeros(A.size, np.int64)}

    def run(rows: np.ndarray, model) -> None:
        if not rows.size:
            return
        part = model(k[rows], a[rows], b[rows], A[rows], mu_ref[rows], state_law, s_kick[rows], ratios[rows],
                     durations[rows], scale[rows], G[rows], times, rtol, max_steps, estimates)
        for name, x in part.items():
            out[name][rows] = x + out[name][rows] if name == "steps" else x  # steps: a run that broke down too

    if quasistatic.size < A.size:
        run(quasistatic, _quasistatic)
    status = out["status"]
    if state_law == "aging":  # the quasi-static runaway (a spring softer than critical): inertia is needed there
        inertial[quasistatic[status[quasistatic] == _BREAKDOWN]] = True
        run(np.flatnonzero(inertial), _inertial)
    else:
        status[(status == Status.OK) & inertial] = Status.QUASISTATIC_BREAKDOWN
    model = (inertial & (state_law == "aging")).astype(np.int8)
    return FrictionSamples(mu=out["mu_t"], error=out["mu_t_error"], status=status, steps=out["steps"], model=model)


def _reduced(p: dict[str, np.ndarray], velocities: np.ndarray, durations: np.ndarray, stretch: float) -> tuple:
    """(k, a, b, A, mu_ref, s_kick, ratios, durations, scale, G, gamma/A at the fastest segment) per set of the
    checked ``p``, each set with its own history (``velocities``, ``durations`` (sets, segments)): the reduction of
    the module docstring with V = its first velocity; G = gamma/A at V."""
    V = velocities[:, 0]
    chi = physics.reduced_stiffness(p["K_over_M"], p["D0"], p["g"])
    mu1 = physics.mu1(V, p["m1"], p["m2"], p["V0"])
    A = p["A"]
    k, a, b = np.asarray(chi / A, float), np.asarray(mu1 / A, float), p["m2"] / A
    s_kick = k * (stretch / p["D0"])
    scale = V / p["D0"]
    ratios = velocities / V[:, None]
    mu_ref = np.asarray(physics.mu_d(V, p["m0"], p["m1"], p["m2"], p["V0"]), float).reshape(-1)
    G = V**2 / (p["g"] * p["D0"]) / A  # gamma/A at V
    return (k, a, b, A, mu_ref, s_kick, ratios, np.ascontiguousarray(durations, dtype=float), scale, G,
            G * (np.max(velocities, axis=1) / V) ** 2)


def sample_friction_rows(p: dict[str, np.ndarray], velocities: np.ndarray, durations: np.ndarray, times: np.ndarray,
                         time_row: np.ndarray, n_times: np.ndarray, rtol: float, max_steps: int, estimates: bool
                         ) -> tuple[FrictionSamples, np.ndarray]:
    """:func:`sample_friction` (aging law, no stretch) of sets each with its own history and times: set i's load
    velocities[i], durations[i] (sets, segments), its times times[time_row[i], :n_times[i]] (a table of checked
    times, a row per record), all quasi-static, in one compiled call (a record fit's round: its records, each of its
    own times, at once). Returns the samples (mu and error (sets, times.shape[1]), NaN beyond a set's times) and
    gamma/A at each set's fastest segment (a set above INERTIA_LIMIT, or whose status is quasistatic_breakdown,
    needs :func:`sample_friction`'s inertia; the numbers of the others are its, bit for bit)."""
    k, a, b, A, mu_ref, s_kick, ratios, durations, scale, _, fastest = _reduced(p, velocities, durations, 0.0)
    from .sampled import two_runs

    out = two_runs(k, a, b, A, mu_ref, "aging", s_kick, ratios, durations, scale, times, rtol, max_steps, estimates,
                   time_row, n_times)
    return FrictionSamples(mu=out["mu_t"], error=out["mu_t_error"], status=out["status"], steps=out["steps"],
                           model=np.zeros(k.size, np.int8)), fastest


def _quasistatic(k, a, b, A, mu_ref, state_law, s_kick, ratios, durations, scale, G, times, rtol, max_steps,
                 estimates):
    from .sampled import two_runs

    return two_runs(k, a, b, A, mu_ref, state_law, s_kick, ratios, durations, scale, times, rtol, max_steps,
                    estimates)


def _inertial(k, a, b, A, mu_ref, state_law, s_kick, ratios, durations, scale, G, times, rtol, max_steps,
              estimates):
    """The inertial pair (aging law) at rtol/TIGHTER and rtol/TIGHTER^2 (the tighter alone without ``estimates``),
    read off as the quasi-static pair."""
    from ...accuracy import TIGHTER
    from .inertial import inertial_samples
    from .sampled import read_samples

    reduced = np.ascontiguousarray(durations * scale[:, None])
    runs = [inertial_samples(k, a, b, G, s_kick, ratios, reduced, scale, times, rtol / TIGHTER**e, max_steps)
            for e in ((1, 2) if estimates else (2,))]
    (s1, st1, n1), (s2, st2, n2) = runs[0], runs[-1]
    return read_samples(s1, s2, st1, st2, A, mu_ref, rtol, n2 + (n1 if estimates else 0), estimates)
