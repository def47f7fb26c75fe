"""Slip events of a friction record: the sharp drops of a stick-slip sawtooth (issue 34).

A fit of a sawtooth whose best model slides stably through it has no slip events; with the noise estimated its
misfit is dof by construction, so only the events tell (sweep.fit.core compares the record's count with the model's
at the best fit: fit_status ``events_missed``, sweep.fit.verdict).

An event starts at a sample i where friction falls, within :data:`SHORT` sample intervals, by more than
:data:`DROP` noise scales, and that fall is at least :data:`SHARP` of its fall over a wider neighbourhood of
:data:`WIDE` intervals after it: a slip (a stress drop in a time ~ sqrt(M/K), shorter than a sample interval at
laboratory rates) falls almost all at once, a smooth transient (the decay after a velocity step or a hold, over a
slip of ~Dc) falls gradually over several samples (for an exponential decay sampled at dt, the ratio is
(1 - e^(-2 dt/tau)) / (1 - e^(-10 dt/tau)): below SHARP for dt < ~0.8 tau). A transient sampled coarser than that
(or a direct effect faster than a sample interval: a stiff machine's step down) counts as an event, in the record and
in its model at the same times alike. Samples that pass in a row are one event. The noise scale is the record's own,
a robust one that neither a linear trend nor irregular sampling nor a few events bias (:func:`noise_scale`);
a model's series is counted with its record's scale.

A best fit with the record's events (as many, each near its place, its fall within DROP noise scales) can still be
a local minimum of the misfit that describes them another way: the peak before a fall rounded, a stick phase's slope
off (a one-event sawtooth from starts 30 % off, measured: a few such minima, with an estimated noise 1.1-1.4 times
the record's, which the noise estimate cannot tell from a good fit). Their residuals are serially correlated where a
fit's to white noise are not: :func:`record_events` counts them missed too where the lag-1 correlation of a record's
residuals exceeds :data:`SERIAL` / sqrt(n) (sweep.fit.event_fit brings most fits into the right basin first), and
where an event is a sample or two off (a single residual the size of a fall, which an estimated noise absorbs: a
three-event sawtooth from 2 % off ended ok at noise 11.8x before this check).
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numba
import numpy as np

__all__ = ["DROP", "RANGE_FLOOR", "SERIAL", "SHARP", "SHORT", "WIDE", "away_from_changes", "count_events",
           "event_scale", "event_times", "load_changes", "noise_scale", "record_events", "record_slip_events",
           "same_events", "serial_correlation", "slip_events"]

DROP = 10.0
"""A fall of more than DROP noise scales within SHORT intervals can be a slip: two noise draws differ by more than
10 sigma (7 standard deviations of their difference) with a probability ~1e-12."""
SHARP = 0.8
"""Fraction of the neighbourhood's fall that falls within SHORT intervals at an event. The margin is narrow
(measured on the reference records of the tests, noise-free and with noise 2e-4): at 0.75 a velocity step down's
direct effect across a 0.5 s gap between samples counts; at 0.85 one of a three-event sawtooth's events does not."""
SHORT = 2
"""Sample intervals within which a slip falls (one, or two where a sample lies inside the slip)."""
WIDE = 8
"""Sample intervals of the neighbourhood after the fall."""
BEFORE = 4
"""Sample intervals of the neighbourhood before the fall (fewer than after: a slip's creep before it matters less)."""
SERIAL = 3.0
"""Lag-1 serial correlation of a record's residuals, in units of its standard deviation for white noise (1/sqrt(n)),
above which a best fit with the record's events still misses them (module docstring): 3 standard deviations, a false
alarm on ~1e-3 of the fits to white noise; measured on a one-event sawtooth (600 samples, noise 2e-4, five draws):
0.07 at most at the truth, 0.14-0.37 at the local minima a fit from 30 % off found (threshold 0.12)."""
COARSER = (2, 4, 8, 16, 32, 64)
"""Strides at which a record without slip events at its own sampling is looked at again (:func:`record_events`)."""
MIN_COARSE = 100
"""Fewest samples a coarser look at a record keeps."""
RANGE_FLOOR = 2e-3
"""Least scale, as a fraction of the record's range: in a record without noise (or nearly), a fall of less than
DROP RANGE_FLOOR = 2 % of its range is no event (the undershoot of a velocity step down ends in a smooth minimum whose
last fall within SHORT is all the fall there is)."""


def noise_scale(t: np.ndarray, mu: np.ndarray) -> float:
    """A robust standard deviation [units of mu] of a series' noise: each inner sample's departure from the line
    through its two neighbours (zero for a linear trend, at any spacing), divided by its standard deviation in units
    of the noise (sqrt(1 + w^2 + (1 - w)^2), w the interpolation weight), its median absolute value / 0.6745."""
    t, mu = np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(mu, dtype=np.float64)
    return float(_noise_kernel(t, mu)) if mu.size >= 3 else 0.0


@numba.njit(cache=True, nogil=True)
def _noise_kernel(t, mu):  # pragma: no cover (compiled)
    """:func:`noise_scale` of n >= 3 samples in one compiled pass (numpy's temporaries and median took ~30 us of a
    1,000-sample record, up to seven times a record in :func:`_finest_events`); the same operations in the same
    order, so the same bits."""
    n = mu.size
    r = np.empty(n - 2)
    for i in range(n - 2):
        w = (t[i + 2] - t[i + 1]) / (t[i + 2] - t[i])
        r[i] = abs((mu[i + 1] - (w * mu[i] + (1.0 - w) * mu[i + 2])) / np.sqrt(1.0 + w * w + (1.0 - w) * (1.0 - w)))
        if np.isnan(r[i]):  # numpy's median of a series with a NaN is NaN (numba's quickselect's is not)
            return np.nan
    return np.median(r) / 0.6745


def slip_events(mu: np.ndarray, scale: float) -> list[tuple[int, float]]:
    """The slip events (module docstring) of the series ``mu`` [1] (in time order) at the noise scale ``scale`` [1]
    (the record's, :func:`event_scale`) as (index of the sample before the fall, fall [1]: the highest of the run's
    samples less the lowest within SHORT after it); a floor of 1e-9 max(|mu|, 1) on the scale keeps a constant
    series' threshold above rounding; none where a sample is not finite."""
    mu = np.ascontiguousarray(mu, dtype=np.float64)
    if mu.size < 2:
        return []
    starts, falls = _slip_kernel(mu, float(scale))
    return [(int(i), float(f)) for i, f in zip(starts, falls)]


@numba.njit(cache=True, nogil=True)
def _slip_kernel(mu, scale):  # pragma: no cover (compiled)
    """:func:`slip_events` of n >= 2 samples: (the first sample of each run, its fall), empty where a sample is not
    finite. One compiled pass (numpy's sliding minimum and a max/min pair per candidate sample took ~0.1 ms of a
    1,000-sample record, looked at up to seven strides); the same comparisons, so the same events and falls."""
    n = mu.size
    top = 1.0
    for i in range(n):
        if not np.isfinite(mu[i]):
            return np.empty(0, np.intp), np.empty(0)
        top = max(top, abs(mu[i]))
    floor = 1e-9 * top
    drop = DROP * (floor if floor > scale else scale)  # (as Python's max(scale, floor): a NaN scale stays NaN)
    starts, falls = np.empty(n, np.intp), np.empty(n)
    m, last = 0, -SHORT - 1  # runs found, the last sample that passed
    for i in range(n - 1):
        low = mu[i + 1]  # the lowest within SHORT after i
        for j in range(i + 2, min(i + 1 + SHORT, n)):
            low = min(low, mu[j])
        if not mu[i] - low > drop:
            continue
        high = mu[i]  # the wider neighbourhood: BEFORE samples before i, SHORT + WIDE after
        for j in range(max(i - BEFORE, 0), i):
            high = max(high, mu[j])
        deep = low
        for j in range(i + 1 + SHORT, min(i + 1 + SHORT + WIDE, n)):
            deep = min(deep, mu[j])
        if not mu[i] - low >= SHARP * (high - deep):
            continue
        if i - last > SHORT:  # a new run (samples that pass in a row are one event)
            starts[m] = i
            m += 1
        last = i
        first = starts[m - 1]
        peak, bottom = mu[first], mu[first + 1]  # the run's highest sample, its lowest within SHORT after it
        for j in range(first, i + 1):
            peak = max(peak, mu[j])
        for j in range(first + 1, min(i + 1 + SHORT, n)):
            bottom = min(bottom, mu[j])
        falls[m - 1] = peak - bottom
    return starts[:m], falls[:m]


def event_scale(t: np.ndarray, mu: np.ndarray) -> float:
    """The scale [1] at which a record's events (and its model's) are counted: its :func:`noise_scale`, at least
    RANGE_FLOOR times its range."""
    return max(noise_scale(t, mu), RANGE_FLOOR * float(np.ptp(mu)) if np.size(mu) else 0.0)


def count_events(mu: np.ndarray, scale: float) -> int:
    """The number of slip events of ``mu`` at the noise scale ``scale`` (:func:`slip_events`)."""
    return len(slip_events(mu, scale))


def same_events(record: list[tuple[int, float]], model: list[tuple[int, float]], scale: float) -> bool:
    """Whether a model's slip events are the record's (both :func:`slip_events` at the record's noise ``scale``):
    as many, each within WIDE samples of the record's and its fall within DROP noise scales of it (a fit that
    describes the record to its noise misses a fall by a few scales at most)."""
    return _differ(record, model, scale) is None


def _differ(record: list[tuple[int, float]], model: list[tuple[int, float]], scale: float
            ) -> tuple[str, float] | None:
    """How a model's slip events differ from the record's (:func:`same_events`): ("count", model's count), ("place",
    the largest offset [samples] beyond WIDE) or ("fall", the largest difference of a fall [noise scales] beyond
    DROP); None where they do not."""
    if len(record) != len(model):
        return "count", float(len(model))
    off = max(abs(i - j) for (i, _), (j, _) in zip(record, model))
    if off > WIDE:
        return "place", float(off)
    falls = max(abs(f - g) for (_, f), (_, g) in zip(record, model)) / scale
    return ("fall", float(falls)) if falls > DROP else None


def event_times(t: np.ndarray, mu: np.ndarray, events: list[tuple[int, float]]
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per event of :func:`slip_events` of the series ``mu`` at times ``t`` [s]: its time [s], where mu falls through
    the middle of its fall (linear between the two samples across it: a continuous function of the series, where
    the event's sample index jumps), the index of its lowest sample within SHORT after the fall starts, and its
    fall [1] (the highest sample less that lowest)."""
    times, low, falls = np.empty(len(events)), np.empty(len(events), np.intp), np.empty(len(events))
    for e, (i, _) in enumerate(events):
        j = i + 1 + int(np.argmin(mu[i + 1:i + 1 + SHORT]))
        mid = 0.5 * (mu[i] + mu[j])
        k = i + int(np.argmax(mu[i + 1:j + 1] < mid))  # mu[k] >= mid > mu[k + 1]
        times[e] = t[k] + (mu[k] - mid) / (mu[k] - mu[k + 1]) * (t[k + 1] - t[k])
        low[e], falls[e] = j, mu[i] - mu[j]
    return times, low, falls


def serial_correlation(r: np.ndarray) -> float:
    """The lag-1 serial correlation of the residuals ``r`` (in sample order) about their mean."""
    d = np.asarray(r, float) - np.mean(r)
    ss = float(d @ d)
    return float(d[:-1] @ d[1:]) / ss if ss > 0 else 0.0


def _misplaced(t: np.ndarray, mu: np.ndarray, model: np.ndarray, events: list[tuple[int, float]], scale: float
               ) -> float:
    """The largest difference of the model from the record [noise scales] at a sample of one of the record's events
    (from the sample before its fall to the one after its lowest): above DROP, a fall a sample or two off."""
    _, low, _ = event_times(t, mu, events)
    return max(float(np.max(np.abs(model[i:j + 2] - mu[i:j + 2]))) / scale for (i, _), j in zip(events, low))


def _missed(t: np.ndarray, mu: np.ndarray, model: np.ndarray, rec: list[tuple[int, float]],
            mod: list[tuple[int, float]], scale: float, residuals: np.ndarray) -> tuple[str, float] | None:
    """Why a model misses the record's slip events ``rec`` (its own ``mod``), None where it does not
    (:func:`record_events`)."""
    differ = _differ(rec, mod, scale)
    if differ is not None:
        return differ
    off = _misplaced(t, mu, model, rec, scale)
    if off > DROP:
        return "sample", off
    serial = serial_correlation(residuals) * np.sqrt(residuals.size)
    return ("serial", float(serial)) if serial > SERIAL else None


def load_changes(record) -> np.ndarray:
    """The times [s, the record's clock] at which the record's load-point velocity changes (sweep.fit.segments)."""
    from .segments import record_steps

    return np.array([s[0] for s in record_steps(record)][1:], dtype=float)


def away_from_changes(t: np.ndarray, events: list[tuple[int, float]], changes: np.ndarray
                      ) -> list[tuple[int, float]]:
    """The events of :func:`slip_events` (of a series at times ``t`` [s]) that are not the load history's own: a fall
    whose neighbourhood (WIDE samples before it to SHORT + WIDE after) holds a change of the load-point velocity
    (``changes`` [s]) is the direct effect of a step down, the relaxation at a hold's start or the evolution after a
    step up (its peak some samples after the step: 5 at every 8th sample of a 1 -> 10 um/s step at 16 Hz, k = 2e3
    1/m, Dc = 10 um), sampled coarser than its time scale, not a slip. The same rule for a record and its model."""
    if not changes.size:
        return events
    n = t.size
    return [(i, f) for i, f in events
            if not np.any((changes >= t[max(i - WIDE, 0)]) & (changes <= t[min(i + SHORT + WIDE, n - 1)]))]


def record_slip_events(record) -> list[tuple[int, float]]:
    """A record's slip events at its own sampling (:func:`slip_events` at :func:`event_scale`) away from the changes
    of its load history (:func:`away_from_changes`)."""
    stride, _, events = _record_finest(record, functools.partial(load_changes, record))
    return events if stride == 1 else []


def _finest_events(t: np.ndarray, mu: np.ndarray, changes: Callable[[], np.ndarray]
                   ) -> tuple[int, float, list[tuple[int, float]]]:
    """(stride, scale, the record's events) at the finest sampling of the record that shows slip events: every
    sample, else every 2nd, 4th, ... (COARSER), while at least MIN_COARSE samples remain; (1, 0, []) where none does.
    A record sampled finer than its slips (a slip spread over more than SHORT samples: a laboratory logger at a few
    hundred Hz, a slip lasting ~ half the machine's natural period) shows no event at its own rate; at a coarser one
    its slips fall within SHORT samples again, and a model through it is counted at that rate too. Falls at the load
    history's changes are not slips (:func:`away_from_changes`), at any rate."""
    for stride in (1, *COARSER):
        if stride > 1 and t.size // stride < MIN_COARSE:
            break
        ts, ms = t[::stride], mu[::stride]
        scale = event_scale(ts, ms)
        rec = slip_events(ms, scale)
        rec = away_from_changes(ts, rec, changes()) if rec else rec
        if rec:
            return stride, scale, rec
    return 1, 0.0, []


def _record_finest(record, changes: Callable[[], np.ndarray]) -> tuple[int, float, list[tuple[int, float]]]:
    """:func:`_finest_events` of a record (sweep.fit.records.Record), found once: a record's data do not change (a
    fit looks at them in its event stage and in its verdicts; ~1 ms a record of 1,000 samples without events)."""
    found = record.__dict__.get("_finest_events")
    if found is None:
        found = _finest_events(np.asarray(record.t, float), np.asarray(record.mu, float), changes)
        object.__setattr__(record, "_finest_events", found)  # (Record is frozen; not one of its fields)
    return found


def record_events(records, residuals: np.ndarray, weights: np.ndarray
                  ) -> list[tuple[str, list[float], list[float], str, float]]:
    """Per record of a problem whose best fit misses its slip events (``records`` in residual order,
    sweep.fit.records.Record): (name, the falls of the record's events, those of the model's at the best fit, why,
    by how much), the model from the weighted residuals r = (model - mu) w of the best fit. Missed, the first that
    applies: other events than the record's (:func:`same_events`: why "count", "place" or "fall", as
    :func:`_differ`), the same ones a sample or two off ("sample": a residual of more than DROP noise scales at one
    of the record's events, its size in noise scales: a single residual the size of a fall, which neither the count
    nor the serial correlation sees and an estimated noise absorbs), or the same ones with serially correlated
    residuals over the record ("serial": lag-1 correlation above SERIAL/sqrt(n), the module docstring; by how much
    in units of 1/sqrt(n))."""
    out, col = [], 0
    for d in records:
        sl = slice(col, col + d.t.size)
        model = d.mu + residuals[sl] / weights[sl]
        changes = functools.cache(functools.partial(load_changes, d))  # (found only where a fall asks)
        stride, scale, rec = _record_finest(d, changes)
        t, mu, model = d.t[::stride], d.mu[::stride], model[::stride]
        mod = away_from_changes(t, slip_events(model, scale), changes()) if rec else []
        why = _missed(t, mu, model, rec, mod, scale, residuals[sl]) if rec else None
        if why is not None:
            out.append((d.name, [f for _, f in rec], [f for _, f in mod], *why))
        col += d.t.size
    return out
