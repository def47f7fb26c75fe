"""Records as the fit's third kind of data: their parameter space (the laboratory's a, b, Dc, mu0, k) and the
:class:`RecordStack`, a :class:`sweep.fit.stack.ProblemStack` whose model values are friction_at's mu(t).

The seam: sweep.fit.core builds a RecordStack instead of a ProblemStack where the data are records; the global
stage, least squares, profiles, noise estimate and verdicts run unchanged on it (they see residuals only). The model
of a record is mu(t) of :func:`sweep.protocols.history.forward.friction_at` (aging law, steady sliding at the first
segment's velocity at the record's first time) with A = a, m1 = b - a, m2 = 0, D0 = Dc, m0 = mu0, K/M = k g
(docs/physics.md 7b). k: the fit's where free, else the record's own (``Record.k``), else the start's. g = N/M, the
machine's inertia: a record's own (``Record.g``; :func:`with_machine_g` gives the records without one the fit's
``g``, or ``params``' g where it is not FrictionParams' default), the model then friction_at's "auto" (inertia where
gamma/A > INERTIA_LIMIT or the quasi-static run breaks down); a record without g is quasi-static (a laboratory
machine's inertia is negligible while it slides) but where a parameter set's quasi-static run breaks down (a spring
softer than critical: stick-slip), whose slips run with inertia at ``params``' g (FrictionParams' default 9.81 m/s^2,
a block under its own weight), friction_at's "breakdown"; :func:`inertia_report` says which.
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

__all__ = ["RECORD_FREE", "RecordStack", "inertia_report", "make_record_space", "with_machine_g"]

RECORD_FREE = ("a", "b", "Dc", "mu0", "k")
"""Parameters a record fit may free, in the order they are reported (k = K/(M g) [1/m])."""

MAX_STEPS = 1_000_000
"""friction_at's step budget of a run (its default)."""
ROUND_CHUNK = 1024
"""Parameter sets of a round's records per compiled call at most (pieces whose arrays stay in the caches)."""
ALONE = 64
"""A record with more parameter sets than this in a round (a global stage's grid) is run by itself, as friction_at
would (batched with others, a global stage of 100 records of their own times took ~7 % longer: its quasi-static runs
that break down ran again with inertia)."""
_BREAKDOWN = int(Status.QUASISTATIC_BREAKDOWN)
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
        self.loads = [[_load_and_times(d) for d in pr.data] for pr in self.problems]
        # every record's times a row of one table, its history a row of the table of its number of segments: a
        # round's records in one compiled call (sample_friction_rows)
        flat = [ld for lds in self.loads for ld in lds]
        self.record_id = np.cumsum([0] + [len(lds) for lds in self.loads])
        self.record_n = np.array([t.size for _, t, _, _ in flat], dtype=np.intp)
        self.times_table = np.full((len(flat), int(self.record_n.max())), np.nan)
        for r, (_, t, _, _) in enumerate(flat):
            self.times_table[r, :t.size] = t
        self.segments = np.array([ld.velocities.size for ld, _, _, _ in flat], dtype=np.intp)
        self.history_table = {m: (np.array([ld.velocities for ld, _, _, _ in flat if ld.velocities.size == m]),
                                  np.array([ld.durations for ld, _, _, _ in flat if ld.velocities.size == m]))
                              for m in np.unique(self.segments)}
        self.history_row = np.array([np.count_nonzero(self.segments[:r] == self.segments[r])
                                     for r in range(len(flat))], dtype=np.intp)
        # problems whose records have the same histories, times and k share a layout, hence their model values (the
        # global grid is solved once for all of them); a detrended record's model depends on its data: its own
        keys: dict[tuple, int] = {}
        self.layout = np.array([keys.setdefault(
            (q,) if any(d.detrend for d in pr.data) else
            tuple((ld.velocities.tobytes(), ld.durations.tobytes(), t.tobytes(), k, g)
                  for ld, t, k, g in self.loads[q]),
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
        estimates, and ``self.inertial`` (U, records) says which record of each block ran with inertia."""
        from ..protocols.history.forward import RTOL_RANGE

        U = layout.size
        mu = np.empty((U, self.n_max))  # (every row's residuals filled, its padding NaN, below)
        err = np.full((U, self.n_max), np.nan) if errors else None
        # without estimates (the optimisations' rounds): friction_at's pair one decade looser, whose tighter run is
        # at rtol/TIGHTER, as the stop path's single run (sweep.fit.forward); ~0.65x the cost; the best fits are
        # checked at rtol with estimates (sweep.fit.core), the difference counted in engine_error
        rtol = self.rtol if self.estimates else min(self.rtol * TIGHTER, RTOL_RANGE[1])
        if errors:
            self.inertial = np.zeros((U, max(len(ld) for ld in self.loads)), bool)
        order = np.argsort(layout, kind="stable")  # the blocks of each layout, in order
        cuts = np.flatnonzero(np.diff(layout[order])) + 1
        jobs, size = [], 0  # (blocks, problem, record of it, record id, first residual): one friction_at each
        for rows in np.split(order, cuts) if U else []:
            q = self.representative[layout[rows[0]]]
            col = 0
            for i, (_, t, _, _) in enumerate(self.loads[q]):
                job = (rows, q, i, self.record_id[q] + i, col)
                col += t.size
                if rows.size > ALONE:  # (a global stage's grid: one call a record already amortises its Python)
                    self._jobs([job], params, rtol, mu, err, batched=False)
                    continue
                jobs.append(job)
                size += rows.size
                if size >= ROUND_CHUNK:
                    self._jobs(jobs, params, rtol, mu, err)
                    jobs, size = [], 0
            mu[rows, col:] = np.nan
        if jobs:
            self._jobs(jobs, params, rtol, mu, err)
        self.rounds += 1
        if self.on_round is not None:
            self.on_round(self.rounds, U)
        ok = np.ones(U, bool)
        return (mu, ok, err) if errors else (mu, ok)

    def _lab(self, p: np.ndarray, k_rec: np.ndarray, g: np.ndarray) -> dict[str, np.ndarray]:
        """friction_at's parameters of the sets ``p`` (rows of (a, b, Dc, mu0, k)) of records with k ``k_rec`` (NaN:
        the set's) and machine g ``g`` [m s-2] (docs/physics.md 7b)."""
        k = p[:, 4] if "k" in self.space.names else np.where(np.isnan(k_rec), p[:, 4], k_rec)
        return {"A": p[:, 0], "m1": p[:, 1] - p[:, 0], "m2": np.zeros(p.shape[0]), "D0": p[:, 2], "m0": p[:, 3],
                "V0": np.full(p.shape[0], self.V0), "K_over_M": k * g, "g": g}

    def _jobs(self, jobs: list[tuple], params: np.ndarray, rtol: float, mu: np.ndarray, err: np.ndarray | None,
              batched: bool = True) -> None:
        """Model values (and error estimates into ``err``) of ``jobs`` (:meth:`_model`'s) written into ``mu``: every
        set quasi-statically in one call per number of segments (sample_friction_rows); the sets that need inertia
        (a record with g given whose fastest slide has gamma/A > INERTIA_LIMIT, or a quasi-static run that breaks
        down) again by sample_friction (friction_at without its checks), which gives it; not ``batched``: every set
        by sample_friction."""
        from ..protocols.history.forward import INERTIA_LIMIT, sample_friction, sample_friction_rows

        sizes = np.array([rows.size for rows, *_ in jobs])
        blocks = np.concatenate([rows for rows, *_ in jobs])
        rid = np.repeat(np.array([r for *_, r, _ in jobs], dtype=np.intp), sizes)
        flat = [self.loads[q][i] for _, q, i, _, _ in jobs]
        k_rec = np.repeat(np.array([np.nan if k is None else k for _, _, k, _ in flat]), sizes)
        g_rec = [g for _, _, _, g in flat]
        g = np.repeat(np.array([self.g if gr is None else gr for gr in g_rec]), sizes)  # none given: quasi-static
        auto = np.repeat(np.array([gr is not None for gr in g_rec]), sizes)  # but where slips need inertia
        lab = self._lab(params[blocks], k_rec, g)
        mu_sets = np.empty((blocks.size, self.times_table.shape[1]))
        err_sets = np.empty_like(mu_sets) if err is not None else None
        status, inertial = np.empty(blocks.size, np.int8), np.full(blocks.size, not batched)
        for m in np.unique(self.segments[rid]) if batched else ():
            sel = np.flatnonzero(self.segments[rid] == m)
            vel, dur = (x[self.history_row[rid[sel]]] for x in self.history_table[m])
            out, fastest = sample_friction_rows({n: x[sel] for n, x in lab.items()}, vel, dur, self.times_table,
                                                rid[sel], self.record_n[rid[sel]], rtol, MAX_STEPS, self.estimates)
            mu_sets[sel], status[sel] = out.mu, out.status
            if err_sets is not None:
                err_sets[sel] = out.error
            inertial[sel] = ((fastest > INERTIA_LIMIT) & auto[sel]) | (out.status == _BREAKDOWN)
        start = np.concatenate(([0], np.cumsum(sizes)))
        for j, (rows, q, i, r, col) in enumerate(jobs):
            sets, n = slice(start[j], start[j + 1]), self.record_n[r]
            m, e, st = mu_sets[sets, :n], (err_sets[sets, :n] if err_sets is not None else None), status[sets]
            again = np.flatnonzero(inertial[sets])
            if again.size:  # those sets alone (a set's numbers are its own: the others' are friction_at's already)
                load, t, _, g_r = self.loads[q][i]
                out = sample_friction({name: x[sets][again] for name, x in lab.items()}, load, t, "aging", rtol,
                                      MAX_STEPS, 0.0, "breakdown" if g_r is None else "auto", self.estimates)
                m, st = m.copy(), st.copy()
                m[again], st[again] = out.mu, out.status
                if e is not None:
                    e = e.copy()
                    e[again] = out.error
                if err is not None:
                    self.inertial[rows[again], i] = out.model == 1
            ok = ((st == VALUED[0]) | (st == VALUED[1]))[:, None]
            m = m if ok.all() else np.where(ok, m, np.nan)
            x = self.trends[q][i]
            if x is not None:  # the record's linear trend: its best slope per set, projected out
                w2 = self.weights[q, col:col + n] ** 2
                resid = self.observed[q, col:col + n] - m
                m = m + np.sum(w2 * x * resid, axis=1, keepdims=True) / np.sum(w2 * x * x) * x
            mu[rows, col:col + n] = m
            if err is not None:
                err[rows, col:col + n] = np.where(ok, e, np.nan)


def _load_and_times(d) -> tuple:
    """(load history, times from its start [s] checked as friction_at checks them, k, g) of a record."""
    from ..protocols.history.forward import _times

    load = load_history(d)
    return load, _times(d.t - d.t[0], load.total), d.k, d.g


def with_machine_g(data, g: float | None, params: FrictionParams) -> list:
    """``data`` (a sequence, or one data set) with each record's machine inertia g = N/M [m s-2]: its own
    (``Record.g``), else ``g`` (the fit's, checked in sweep.fit.records.G_RANGE), else ``params.g`` where that is not
    FrictionParams' default 9.81 (a call that gives the machine's g in its params); None otherwise (the module
    docstring's default: quasi-static but where a slip runs away)."""
    from dataclasses import replace

    from .records import Record, check_g

    fallback = check_g("g", g) if g is not None else (params.g if params.g != FrictionParams.g else None)
    items = list(data) if isinstance(data, (list, tuple)) else [data]
    return [replace(d, g=fallback) if isinstance(d, Record) and d.g is None and fallback is not None else d
            for d in items]


def inertia_report(problems: Sequence[Problem], inertial: np.ndarray, space: ParamSpace) -> tuple[dict, str | None]:
    """What a record fit chose for each record's inertia (problem and record order): ``fit_settings`` entries
    (``record_g``: the g = N/M [m s-2] given, None where none was; ``record_inertial``: whether the best fit ran the
    record with inertia, ``inertial`` of :class:`RecordStack` at the best fits; ``inertia``: the rule) and a warning
    line where a record without a given g slips at the best fit: its slips ran at ``params``' g, which sets their
    falls (friction_at of a stick-slip record: its lowest friction ~0.0095 lower per decade of g at a = 0.01, b =
    0.015, Dc = 10 um, g 9.81 .. 1e5), None otherwise."""
    from ..protocols.history.forward import INERTIA_LIMIT

    given = [d.g for pr in problems for d in pr.data]
    ran = [bool(inertial[q, i]) for q, pr in enumerate(problems) for i in range(len(pr.data))]
    settings = {"inertia": f"a record with g = N/M given: friction_at's auto (inertia where gamma/A = v^2/(g Dc a) > "
                           f"{INERTIA_LIMIT:g} or the quasi-static run breaks down); without: quasi-static, inertia "
                           f"only where the quasi-static run breaks down (stick-slip), at g = {space.g:g} m/s^2",
                "record_g": given, "record_inertial": ran}
    names = [d.name for pr in problems for d in pr.data]
    slipped = [n for n, g, r in zip(names, given, ran) if g is None and r]
    if not slipped:
        return settings, None
    more = f" (and {len(slipped) - 1} more)" if len(slipped) > 1 else ""
    return settings, (f"record {slipped[0]!r}{more} slips at the best fit (its quasi-static model runs away: "
                      f"stick-slip), and no g = N/M was given: its slips ran with inertia at g = {space.g:g} m/s^2 ("
                      f"params' g; FrictionParams' default 9.81 is a block under its own weight), which sets "
                      f"their falls; give the machine's g (Record(g=...), sweep.fit(g=...), the fit file's g, "
                      f"'# g = ... m/s^2' in the record) (docs/fit.md)")


def record_k(data) -> float | None:
    """The first record's k [1/m], the default start of a free k."""
    return next((d.k for d in data if getattr(d, "k", None)), None)
