"""Records as the fit's third kind of data: their parameter space (the laboratory's a, b, Dc, mu0, k) and the
:class:`RecordStack`, a :class:`sweep.fit.stack.ProblemStack` whose model values are friction_at's mu(t).

The seam: sweep.fit.core builds a RecordStack instead of a ProblemStack where the data are records; the global
stage, least squares, profiles, noise estimate and verdicts run unchanged on it (they see residuals only). The model
of a record is mu(t) of :func:`sweep.protocols.history.forward.friction_at` (quasi-static, aging law, steady sliding
at the first segment's velocity at the record's first time) with A = a, m1 = b - a, m2 = 0, D0 = Dc, m0 = mu0,
K/M = k g (docs/physics.md 7b). k: the fit's where free, else the record's own (``Record.k``), else the start's.
A record with ``detrend`` adds c x to its model (x its time or displacement from the start) with the slope c that
minimises its weighted residuals at each parameter set (a linear nuisance parameter projected out: the profiles of
the other parameters are then profiled over c too; it counts as a parameter in the degrees of freedom and the
noise estimate, sweep.fit.core, and its value at the best fit is reported, sweep.fit.result.trend_slopes).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from ..accuracy import TIGHTER
from ..errors import InputError
from ..scene.params import FrictionParams, require_finite
from ..status import Status
from .problem import Problem
from .segments import load_history
from .space import ParamSpace, bounded_space
from .stack import ProblemStack

__all__ = ["RECORD_FREE", "RecordStack", "inertia_warning", "make_record_space"]

RECORD_FREE = ("a", "b", "Dc", "mu0", "k")
"""Parameters a record fit may free, in the order they are reported (k = K/(M g) [1/m])."""

VALUED = (int(Status.OK), int(Status.ERROR_ABOVE_TOL))
"""friction_at statuses whose values a record fit uses: error_above_tol too (in stick-slip the estimate exceeds the
error ~9x, and a sawtooth's own truth got it; its error enters engine_error like any other)."""


def _default_bounds(name: str, v: Mapping[str, float]) -> tuple[float, float]:
    """a, Dc, k within a factor 10 of the start; b within 5 max(|b|, a) of it; mu0 within 0.2."""
    if name in ("a", "Dc", "k"):
        return v[name] / 10.0, v[name] * 10.0
    if name == "b":
        w = 5.0 * max(abs(v["b"]), v["a"])
        return v["b"] - w, v["b"] + w
    return v["mu0"] - 0.2, v["mu0"] + 0.2


def make_record_space(free: Sequence[str], params: FrictionParams, k: float | None,
                      bounds: Mapping[str, Sequence[float]] | None = None,
                      start: Mapping[str, float] | None = None) -> ParamSpace:
    """The space of a record fit: ``free`` from :data:`RECORD_FREE`, the others at ``params``' laboratory values
    (FrictionParams.to_lab) and ``k`` [1/m], ``start`` overriding them (InputError naming the field otherwise)."""
    free = (free,) if isinstance(free, str) else tuple(free)
    if not free or any(n not in RECORD_FREE for n in free) or len(set(free)) != len(free):
        raise InputError(f"free must name distinct parameters of a record fit from {list(RECORD_FREE)}, got "
                         f"{list(free)}")
    values = {**{n: v for n, v in params.to_lab().items() if n != "V0"}, "k": float(k) if k else np.nan}
    for name, value in dict(start or {}).items():
        if name not in RECORD_FREE:
            raise InputError(f"start names {name!r}; a record fit allows {list(RECORD_FREE)}")
        values[name] = require_finite(f"start {name}", value)
    if "k" in free and not np.isfinite(values["k"]):
        raise InputError("k is free but has no start: give start={'k': value [1/m]} or records with k")
    return bounded_space(free, values, bounds, _default_bounds, params)


class RecordStack(ProblemStack):
    """The problems of a record fit (each a sample's records) for the fit's stages: the index tables of a
    ProblemStack (observed, weights, one layout per problem) and the model of the module docstring."""

    def __init__(self, problems: Sequence[Problem], rtol: float,
                 on_round: Callable[[int, int], None] | None = None, estimates: bool = True):
        self.problems = list(problems)
        self.space = self.problems[0].space
        self.rtol, self.on_round, self.rounds, self.estimates = rtol, on_round, 0, estimates
        self.V0, self.g = self.space.V0, self.space.g
        self.n_res = np.array([pr.n_residuals for pr in self.problems])
        self.n_max = int(self.n_res.max())
        Q = len(self.problems)
        self.observed, self.weights = np.zeros((Q, self.n_max)), np.zeros((Q, self.n_max))
        for q, pr in enumerate(self.problems):
            self.observed[q, :pr.n_residuals], self.weights[q, :pr.n_residuals] = pr.observed, pr.weights
        self.loads = [[(load_history(d), d.t - d.t[0], d.k) for d in pr.data] for pr in self.problems]
        # problems whose records have the same histories, times and k share a layout, hence their model values (the
        # global grid is solved once for all of them); a detrended record's model depends on its data: its own
        keys: dict[tuple, int] = {}
        self.layout = np.array([keys.setdefault(
            (q,) if any(d.detrend for d in pr.data) else
            tuple((ld.velocities.tobytes(), ld.durations.tobytes(), t.tobytes(), k) for ld, t, k in self.loads[q]),
            len(keys)) for q, pr in enumerate(self.problems)], dtype=np.intp)
        self.representative = np.array([int(np.flatnonzero(self.layout == u)[0]) for u in range(len(keys))],
                                       dtype=np.intp)
        self.trends = [[None if d.detrend is None else (d.t - d.t[0] if d.detrend == "time" else
                                                         d.displacement - d.displacement[0]) for d in pr.data]
                       for pr in self.problems]
        # mu0 shifts every model value alike (mu = mu0 + a function of the others): an offset parameter
        self.offset = self.space.names.index("mu0") if "mu0" in self.space.names else None

    def offset_direction(self) -> np.ndarray:
        """d(weighted residual)/d mu0 (Q, n_max): the weight, where a record is detrended times 1 - x <x>/<x^2>
        (weighted means over the record: its trend's slope absorbs part of a shift)."""
        out = np.zeros_like(self.weights)
        for q, pr in enumerate(self.problems):
            col = 0
            for d, x in zip(pr.data, self.trends[q]):
                w = self.weights[q, col:col + d.t.size]
                out[q, col:col + d.t.size] = w if x is None else w * (1.0 - x * np.sum(w**2 * x) / np.sum(w**2 * x**2))
                col += d.t.size
        return out

    def _params(self, sets: np.ndarray) -> np.ndarray:
        """(a, b, Dc, mu0, k) of each parameter set (rows of ``sets``); k NaN where neither fitted nor given."""
        full = self.space.full(sets)
        return np.column_stack([full[n] for n in RECORD_FREE])

    def _model(self, layout: np.ndarray, params: np.ndarray, errors: bool = False):
        """mu (U, n_max) in residual order of U blocks (a layout and a parameter set each), NaN where friction_at
        did not give a value (status not in VALUED); all stable (a record may hold stick-slip); with ``errors`` their
        estimates."""
        from ..protocols.history.forward import RTOL_RANGE, friction_at

        U = layout.size
        mu, err = np.full((U, self.n_max), np.nan), np.full((U, self.n_max), np.nan)
        # without estimates (the optimisations' rounds): friction_at's pair one decade looser, whose tighter run is
        # at rtol/TIGHTER, as the stop path's single run (sweep.fit.forward); ~0.65x the cost; the best fits are
        # checked at rtol with estimates (sweep.fit.core), the difference counted in engine_error
        rtol = self.rtol if self.estimates else min(self.rtol * TIGHTER, RTOL_RANGE[1])
        k_free = "k" in self.space.names
        for u in np.unique(layout):
            rows, q = np.flatnonzero(layout == u), self.representative[u]
            p = params[rows]
            col = 0
            for (load, t, k_rec), x in zip(self.loads[q], self.trends[q]):
                k = p[:, 4] if k_free or k_rec is None else np.full(rows.size, k_rec)
                lab = {"A": p[:, 0], "m1": p[:, 1] - p[:, 0], "m2": np.zeros(rows.size), "D0": p[:, 2],
                       "m0": p[:, 3], "V0": np.full(rows.size, self.V0), "K_over_M": k * self.g,
                       "g": np.full(rows.size, self.g)}  # g = N/M: the machine's inertia (docs/physics.md 7b)
                out = friction_at(lab, load, t, rtol=rtol)
                ok = np.isin(out.status, VALUED)[:, None]
                m = np.where(ok, out.mu, np.nan)
                if x is not None:  # the record's linear trend: its best slope per set, projected out
                    w2 = self.weights[q, col:col + t.size] ** 2
                    resid = self.observed[q, col:col + t.size] - m
                    m = m + np.sum(w2 * x * resid, axis=1, keepdims=True) / np.sum(w2 * x * x) * x
                mu[rows, col:col + t.size] = m
                err[rows, col:col + t.size] = np.where(ok, out.error, np.nan)
                col += t.size
        self.rounds += 1
        if self.on_round is not None:
            self.on_round(self.rounds, U)
        ok = np.ones(U, bool)
        return (mu, ok, err) if errors else (mu, ok)


def inertia_warning(records, space: ParamSpace) -> str | None:
    """One line where some record's fastest slide runs with inertia at the start values (gamma/A = v^2/(g Dc a) >
    friction_at's INERTIA_LIMIT) and g is the default 9.81 m/s^2 of FrictionParams (a block under its own weight: a
    laboratory machine's moving mass M is far below N/g, so its g = N/M is far larger and its inertia negligible);
    None otherwise. docs/fit.md, "Laboratory records"."""
    from ..protocols.history.forward import INERTIA_LIMIT

    if space.g != FrictionParams.g:  # (the dataclass default)
        return None
    full = space.full(space.start[None, :])
    a, Dc = float(full["a"][0]), float(full["Dc"][0])
    fast = [(d.name, float(np.max(load_history(d).velocities))) for d in records]
    over = [(name, v, v**2 / (space.g * Dc * a)) for name, v in fast if v**2 / (space.g * Dc * a) > INERTIA_LIMIT]
    if not over:
        return None
    name, v, ratio = max(over, key=lambda x: x[2])
    more = f" (and {len(over) - 1} more)" if len(over) > 1 else ""
    return (f"record {name!r}{more} slides at {v:.3g} m/s: with g = N/M = {space.g} m/s^2, the default (a block "
            f"under its own weight), gamma/A = {ratio:.3g} > {INERTIA_LIMIT:g} and the fit models its inertia; a "
            "laboratory machine's moving mass is far below N/g: give its g = N/M in params "
            "(FrictionParams.from_lab(..., g=...)), or the inertia biases a and b (docs/fit.md)")


def record_k(data) -> float | None:
    """The first record's k [1/m], the default start of a free k."""
    return next((d.k for d in data if getattr(d, "k", None)), None)
