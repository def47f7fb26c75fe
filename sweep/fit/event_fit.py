"""Stick-slip (sawtooth) records: starts in the basin of the record's slip events for the least squares (issue 34).

Why: a slip is a near-discontinuity in time, so a record's weighted residuals depend on the parameters that move an
event in time flat-then-cliff (the samples across a fall change only as the fall crosses them), and the misfit of a
model whose event is a few samples off is lowered most by shrinking the event, towards a stable model through the
sawtooth. Measured on a one-event sawtooth (600 samples, noise 2e-4, a, b, Dc, mu0 free, six draws from starts 30 %
off, tests/fit/test_records_sawtooth_fit.py): the plain fit ended ok with covering intervals on 1 of 6 (4
events_missed, 1 not_converged); with this stage on 6 of 6, 2.5-3.1 s a fit instead of 0.5-5.7 s (2 shared cores). From
the same draws' starts: 10 starts (boxes in a and Dc only) gave 5 of 6 (one events_missed: a local minimum with the
record's event, serially correlated residuals, sweep.fit.events), the start's box alone 4 of 6; plain least squares
from 9 starts (a box of factor 1.3, no aligned stage, search local) 4 of 6, and two fits ok at a wrong local minimum
(noise 1.18x and 2.42x; before the serial-correlation check). A three-event sawtooth (600 samples over 35 s; its
plain misfit's valley ~0.25 % wide in b) was reached by none of 6 draws (all events_missed) until the continuation
and the finer forward differences below (:data:`EVENT_FD_STEP`): 6 of 6 ok with covering intervals, 2.9-3.8 s a
fit; a record sampled at two rates with a gap: 4 of 4 ok (before: 3 not_converged, 1 events_missed).

What: for the problems whose records show slip events (sweep.fit.events.slip_events), before the least squares
(sweep.fit.core), :func:`event_start` runs, from several starts each, a least squares of event-aligned residuals
(:class:`AlignedStack`) and then one of the plain residuals (profile-point tolerances), and hands the plain least
squares the result with the least plain misfit. The final fit, its intervals and its verdict stay on the plain
residuals (the likelihood of the data). The aligned residuals of a record, in its weighted units:

* each stick phase compared in time since its own slip: a sample at time t after the record's event j (from its
  lowest sample on) against the model at t - T_j + T'_j (T, T': the record's and the model's event times, where
  friction falls through the middle of the fall: sweep.fit.events.event_times), interpolated linearly within the
  model's own phase j (clamped at its ends: a model phase shorter than the record's is compared with its last
  value); before the first event, in plain time; the samples inside a fall count 0;
* per event, its time w F (T'_j - T_j)/dt (F the record's fall, dt its median sample interval: one sample of
  misplacement weighs as the one residual of height F it makes in the plain residuals) and its fall w (F'_j - F_j);
  an event the model lacks counts as one at the record's end (time) with no fall term (both continuous as an event
  leaves through the end).

Continuation: the stage above runs on the records cut midway between their first and second slip events (all of a
record with one); a record with more is extended one event at a time, each cut fitted by a plain least squares from
the last one's best, and the fit's least squares take the whole records from there (measured on the three-event
sawtooth: without it 0 of 6, 3 not_converged and 3 events_missed, from the whole records' stage).

Starts: the global stage's best point and the given start, each also multiplied by SPREAD^(+-1) in every free
parameter but the offset (the corners of a box; 2 (2^3 + 1) = 18 starts for a, b, Dc, mu0 free), all of them as
tasks of one vectorised least squares (sweep.fit.levenberg). Records without events take none of this (their fits
are identical, measured on 20 velocity-step records; the cost is one event count per record, ~0.2 ms per 1,000
samples).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from .events import event_scale, event_times, record_slip_events, slip_events
from .levenberg import FD_STEP, FIT, HOLD, Tolerances, solve
from .problem import Problem
from .stack import ProblemStack

__all__ = ["ALIGNED", "EVENT_FD_STEP", "SPREAD", "STAGE_RTOL", "AlignedStack", "event_problems", "event_start"]

ALIGNED = Tolerances(ftol=1e-6, xtol=1e-5, max_rounds=60)
"""Stopping rules of the aligned least squares: it only needs to land in the plain misfit's basin."""
SPREAD = 1.5
"""Factor of the box of starts around the given start (module docstring)."""
EVENT_FD_STEP = 1e-5
"""Forward-difference step (relative to each parameter's scale) of the least squares of a stick-slip problem,
instead of sweep.fit.levenberg.FD_STEP = 1e-3: a three-event sawtooth's misfit valley is ~0.25 % wide in b (with a,
Dc at the truth), so a step of 1e-3 of the scale spans much of it and the least squares stall on its wall (from a
point 2-4 % off along the valley: no move at 1e-3, part of the way at 1e-4, to the truth at 1e-5; measured on the
two-event window of tests/fit/test_records_sawtooth_fit.py's three-event record). The slips make the model's
derivatives large, so the engine's error (rtol) stays far below the differences."""
STAGE_RTOL = 1e-4
"""Engine rtol of the stage's forward solves (at least; the global stage's default): it only finds the basin, and the
fit's least squares follow at the fit's rtol. Measured on the one-event sawtooth from 30 % off (six draws, one after
the other): 2.5-3.1 s a fit against 4.3-9.4 s with the stage at the fit's rtol (1e-6), the same fits (6 of 6 ok)."""


class _Events:
    """A record's slip events and the phase of each sample (0 before the first event, j after event j from its
    lowest sample on, -1 inside a fall)."""

    def __init__(self, d, sl: slice):
        self.sl, self.t, self.mu = sl, d.t - d.t[0], d.mu
        self.scale = event_scale(d.t, d.mu)
        ev = slip_events(d.mu, self.scale)
        self.n = len(ev)
        self.start = np.array([i for i, _ in ev], dtype=np.intp)
        self.times, low, self.falls = event_times(self.t, d.mu, ev)
        self.dt = float(np.median(np.diff(self.t)))
        self.phase = np.zeros(self.t.size, dtype=np.intp)
        for j, (i, lo) in enumerate(zip(self.start, low)):
            self.phase[i + 1:] = j + 1
            self.phase[i + 1:lo] = -1

    def aligned(self, model: np.ndarray, w: np.ndarray) -> np.ndarray:
        """The aligned residuals (n) and the event terms (2 n_events) of the model values ``model`` (module
        docstring), weights ``w``."""
        t, E = self.t, self.n
        ev = slip_events(model, self.scale)
        m_times, m_low, m_falls = event_times(t, model, ev)
        lo = np.concatenate(([0], m_low))
        hi = np.concatenate(([i for i, _ in ev], [t.size - 1])).astype(np.intp)
        out = np.zeros(t.size + 2 * E)
        for j in range(E + 1):
            sel = self.phase == j
            jm = min(j, len(ev))  # the model's phase j (its last where it has fewer events)
            shift = m_times[j - 1] - self.times[j - 1] if 0 < j <= len(ev) else 0.0
            a = lo[jm]
            b = max(hi[jm] + 1, a + 1)
            out[:t.size][sel] = (np.interp(t[sel] + shift, t[a:b], model[a:b]) - self.mu[sel]) * w[sel]
        we = w[self.start] * self.falls / self.dt
        found = min(E, len(ev))
        out[t.size:t.size + 2 * found:2] = we[:found] * (m_times[:found] - self.times[:found])
        out[t.size + 1:t.size + 2 * found:2] = w[self.start[:found]] * (m_falls[:found] - self.falls[:found])
        out[t.size + 2 * found::2] = we[found:] * (t[-1] - self.times[found:])
        return out


class AlignedStack:
    """The problems ``problems`` of a record stack with the event-aligned residuals of the module docstring in place
    of the plain ones (the interface of ProblemStack that sweep.fit.levenberg.solve uses): per problem its n plain
    residuals' places, then 2 per event. Failed solves keep the plain MODEL_FAILED residuals."""

    def __init__(self, base: ProblemStack, problems: np.ndarray):
        self.base, self.space, self.offset, self.fd_step = base, base.space, base.offset, base.fd_step
        self.events = {int(q): [] for q in problems}
        for q in self.events:
            col = 0
            for d in base.problems[q].data:
                self.events[q].append(_Events(d, slice(col, col + d.t.size)))
                col += d.t.size
        extra = np.zeros(len(base.problems), dtype=np.intp)
        for q, evs in self.events.items():
            extra[q] = sum(2 * e.n for e in evs)
        self.n_res = base.n_res + extra
        self.n_max = int(self.n_res.max())

    def residuals(self, problem: np.ndarray, sets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """As ProblemStack.residuals, aligned."""
        problem = np.asarray(problem, dtype=np.intp)
        r, stable, failures = self.base.residuals(problem, sets)
        out = np.zeros(r.shape[:2] + (self.n_max,))
        out[..., :r.shape[-1]] = r
        for i, q in enumerate(problem):
            w = self.base.weights[q]
            for s in np.flatnonzero(failures[i] == 0):
                extra = self.base.n_res[q]
                for e in self.events[int(q)]:
                    a = e.aligned(e.mu + r[i, s, e.sl] / w[e.sl], w[e.sl])
                    out[i, s, e.sl] = a[:e.t.size]
                    out[i, s, extra:extra + 2 * e.n] = a[e.t.size:]
                    extra += 2 * e.n
        return out, stable, failures

    def offset_direction(self) -> np.ndarray:
        """The plain residuals' (an offset moves the aligned residuals alike, not the event times and falls)."""
        g = self.base.offset_direction()
        out = np.zeros((g.shape[0], self.n_max))
        out[:, :g.shape[1]] = g
        return out


def event_problems(stack: ProblemStack) -> np.ndarray:
    """Indices of the problems of a record stack with slip events in some record (sweep.fit.events.slip_events)."""
    return np.array([q for q, pr in enumerate(stack.problems)
                     if any(record_slip_events(d) for d in pr.data)], dtype=np.intp)


def _box(theta: np.ndarray, spread: float, offset: int | None) -> list[np.ndarray]:
    """``theta`` times spread^(+-1) in every parameter but the ``offset`` one (the corners of a box; clipped to the
    bounds by the caller)."""
    cols = [j for j in range(theta.size) if j != offset]
    out = []
    for signs in itertools.product((-1.0, 1.0), repeat=len(cols)):
        th = theta.copy()
        th[cols] *= spread ** np.array(signs)
        out.append(th)
    return out


def _cut(d, j: int):
    """Record ``d`` up to midway between its slip events j and j + 1 (1-based; itself where it has at most j)."""
    ev = record_slip_events(d)
    if len(ev) <= j:
        return d
    times = event_times(d.t - d.t[0], d.mu, ev)[0]
    end = float(d.t[0] + 0.5 * (times[j - 1] + times[j]))
    return d.window(t_end=end) if np.count_nonzero(d.t <= end) >= 10 else d  # (a Record keeps 10 samples at least)


def _stage(stack: ProblemStack, qs: np.ndarray, j: int) -> ProblemStack:
    """A record stack of the problems ``qs`` of ``stack`` with their records cut after their j-th slip event
    (:func:`_cut`), at the stack's engine settings and stick-slip forward-difference step."""
    from .record_forward import RecordStack

    cut = [Problem(stack.problems[q].name, tuple(_cut(d, j) for d in stack.problems[q].data), stack.space)
           for q in qs]
    out = RecordStack(cut, stack.rtol, estimates=False)
    out.fd_step = np.full(len(cut), EVENT_FD_STEP)
    return out


def event_start(stack: ProblemStack, theta0: Sequence[np.ndarray], start: np.ndarray | None = None,
                spread: float = SPREAD) -> list[np.ndarray]:
    """Starts for the plain least squares of every problem of the record stack ``stack``: ``theta0[q]`` (the global
    stage's best point, or the start) as it is for problems without slip events; for the others the best of the
    aligned-then-plain least squares (module docstring) from theta0[q], ``start`` (the given start; None: theta0
    alone) and the boxes around them (factor ``spread``), on the records cut after their first slip event, then
    extended by one event at a time (a plain least squares from the last one's best each: a continuation). Sets
    ``stack.fd_step``: :data:`EVENT_FD_STEP` for the problems with slip events (the fit's own least squares too)."""
    theta = [np.array(th, dtype=float) for th in theta0]
    qs = event_problems(stack)
    if not qs.size:
        return theta
    stack.fd_step = np.full(len(stack.problems), FD_STEP)
    stack.fd_step[qs] = EVENT_FD_STEP
    n_events = max(len(record_slip_events(d)) for q in qs for d in stack.problems[q].data)
    full, stack = stack, _stage(stack, qs, 1)  # the first event's window (all of it where one event)
    qs_full, qs = qs, np.arange(qs.size)
    sp = stack.space
    given = [] if start is None else [np.asarray(start, dtype=float)]
    starts = [[s for c in [theta[q]] + given for s in [c] + _box(c, spread, stack.offset)] for q in qs]
    C = len(starts[0])
    tasks = np.repeat(qs, C)
    th = np.clip(np.array([s for per in starts for s in per]), sp.lower, sp.upper)
    loose = stack.with_settings(max(stack.rtol, STAGE_RTOL), estimates=False)  # the basin only: a looser engine
    th = solve(AlignedStack(loose, qs), tasks, th, tol=ALIGNED).theta
    plain = solve(loose, tasks, th, tol=HOLD)
    full.rounds += loose.rounds  # counted with the fit's least squares (sweep.fit.core)
    # the least plain misfit, a set the model solved throughout first (a failed solve never wins: sweep.fit.stack)
    rss = np.where(plain.failures == 0, plain.rss, np.inf).reshape(qs.size, C)
    best = np.argmin(rss, axis=1)
    for i, q in enumerate(qs_full):
        if np.isfinite(rss[i, best[i]]):
            theta[q] = plain.theta[i * C + best[i]]
    for j in range(2, n_events + 1):  # one more event each (the last stage is the fit's own least squares)
        stage = _stage(full, qs_full, j - 1) if j > 2 else stack
        stage.rounds = 0
        fit = solve(stage, qs, np.array([theta[q] for q in qs_full]), tol=FIT)
        full.rounds += stage.rounds
        for i, q in enumerate(qs_full):
            if fit.failures[i] == 0:
                theta[q] = fit.theta[i]
    return theta
