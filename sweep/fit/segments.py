"""The load history of a record: segments of constant load-point velocity (velocity steps, holds), given or found
from the load-point displacement.

Detection (binary segmentation of a piecewise-linear displacement): a segment of samples is split at the sample
where a continuous two-piece line (hinge) lowers the residual sum of squares most, if that lowers it by more than
PENALTY x ln(n) x s^2 (s the noise of the displacement, the robust scatter about neighbouring samples,
sweep.fit.data.first_noise_estimate, at least the rounding noise of the column's resolution; n the samples of the
segment), recursively, no piece shorter than MIN_SAMPLES; then each cut moves to the best hinge between its
neighbouring cuts until none moves (a first split over several changes lands between them). Each piece's velocity
is its least-squares slope; a piece whose slope is within 3 standard errors of 0, or below HOLD_FRACTION of the
fastest, is a hold (velocity 0). A hold too short for a piece of its own (a 1 s hold at 10 Hz under 0.3 um of noise)
shows as a sliding piece whose line after it is behind: the best step in a piece's displacement, kept by the same
penalty, is a pause of (lag)/(velocity) (:func:`_pauses`). A commanded velocity column (runs of one value) gives
the steps directly, each change midway between its two samples; a measured one is integrated (trapezoids) to a
displacement first. Only the load point is looked at: a sawtooth or noise in friction cannot move a step.
"""

from __future__ import annotations

import numba
import numpy as np

from ..errors import InputError
from .data import first_noise_estimate
from .records import Record

__all__ = ["HOLD_FRACTION", "MIN_SAMPLES", "PENALTY", "detect_steps", "record_steps"]

PENALTY = 10.0
MIN_SAMPLES = 8
HOLD_FRACTION = 1e-3
SAME_VELOCITY = 0.02
TRIM = MIN_SAMPLES // 2
"""Samples left out at each end of a piece when its velocity is fitted."""
"""Neighbouring pieces whose velocities differ by less than this fraction (plus 3 standard errors) are one."""


def _best_column(t: np.ndarray, y: np.ndarray, jump: bool = False) -> tuple[int, float, float]:
    """(index k of the best candidate sample, the RSS reduction it gives over one line, its column's coefficient) for
    one piece, every candidate from cumulative sums (O(n)): basis 1, t and a hinge (t - t_k)+ or, with ``jump``, a
    step (t >= t_k) (a pause too short for a piece of its own: the line after it is behind by the coefficient)."""
    k, gain, coef = _best_kernel(np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(y, dtype=np.float64),
                                 bool(jump), MIN_SAMPLES)
    return int(k), float(gain), float(coef)


@numba.njit(cache=True, nogil=True)
def _best_kernel(t, y, jump, m):  # pragma: no cover (compiled)
    """:func:`_best_column`'s sums in one compiled pass from the last sample back (the numpy version's eleven
    cumulative sums and temporaries took 2/3 of segmenting a 1,000-sample record)."""
    n = t.size
    if n - 2 * m <= 0:
        return -1, 0.0, 0.0
    tmean, ymean, lo, hi = 0.0, 0.0, t[0], t[0]
    for i in range(n):
        tmean += t[i]
        ymean += y[i]
        lo, hi = min(lo, t[i]), max(hi, t[i])
    tmean, ymean = tmean / n, ymean / n
    scale = hi - lo if hi > lo else 1.0
    S_t = S_tt = S_y = S_ty = 0.0
    for i in range(n):
        tc, yc = (t[i] - tmean) / scale, y[i] - ymean
        S_t += tc
        S_tt += tc * tc
        S_y += yc
        S_ty += tc * yc
    # the column h_k beside the line's basis X = [1, t]: its fall of the RSS is (h.y - c G^-1 f)^2 / (h.h - c G^-1 c),
    # G = X'X, c = X'h_k, f = X'y (the part of h_k the line cannot carry: no 3x3 solve per k), its coefficient
    # (h.y - c G^-1 f) / (h.h - c G^-1 c); the sums over i >= k grow as k runs back
    det = n * S_tt - S_t * S_t
    N = T1 = T2 = Y1 = TY = 0.0
    best_k, best, best_coef = -1, -1.0, 0.0
    for i in range(n - 1, m - 1, -1):
        tc, yc = (t[i] - tmean) / scale, y[i] - ymean
        N += 1.0
        T1 += tc
        T2 += tc * tc
        Y1 += yc
        TY += tc * yc
        if i >= n - m:
            continue
        if jump:  # h_k = 1 for i >= k
            h1, h2, th, hy = N, N, T1, Y1
        else:  # h_k = (t - t_k) for i >= k
            h1 = T1 - tc * N
            h2 = T2 - 2 * tc * T1 + tc * tc * N
            th = T2 - tc * T1
            hy = TY - tc * Y1
        cgc = (S_tt * h1 * h1 - 2.0 * S_t * h1 * th + n * th * th) / det
        cgf = (S_tt * h1 * S_y - S_t * (h1 * S_ty + th * S_y) + n * th * S_ty) / det
        den = h2 - cgc
        gain, coef = 0.0, 0.0
        if den > 0:
            gain, coef = (hy - cgf) ** 2 / den, (hy - cgf) / den
        if gain >= best:  # the first of equal ones, as numpy's argmax
            best_k, best, best_coef = i, gain, coef
    return best_k, best, best_coef


def detect_steps(t: np.ndarray, displacement: np.ndarray, noise: float | None = None
                 ) -> tuple[tuple[float, float], ...]:
    """((start time [s], velocity [m s-1]), ...) of the pieces of a load-point displacement [m] sampled at ``t``
    [s] (module docstring); ``noise`` [m] of the displacement (default: estimated)."""
    t, y = np.asarray(t, float), np.asarray(displacement, float)
    s = _noise_floor(t, y) if noise is None else float(noise)
    cuts, todo = [], [(0, t.size)]
    while todo:
        i, j = todo.pop()
        if j - i < 2 * MIN_SAMPLES + 1:
            continue
        k, gain, _ = _best_column(t[i:j], y[i:j])
        if k > 0 and gain > PENALTY * np.log(j - i) * s * s:
            cuts.append(i + k)
            todo += [(i, i + k), (i + k, j)]
    edges = [0, *_refine(t, y, sorted(cuts)), t.size]
    pieces = [[i, j] for i, j in zip(edges[:-1], edges[1:])]
    changed = True
    while changed and len(pieces) > 1:  # merge neighbours of one velocity; drop short transition pieces
        changed = False
        fits = [_line(t[i:j], y[i:j], s) for i, j in pieces]
        for q in range(len(pieces) - 1):
            (v1, _, e1), (v2, _, e2) = fits[q][:3], fits[q + 1][:3]
            between = 0 < q + 1 < len(pieces) - 1 and min(fits[q][0], fits[q + 2][0]) <= v2 <= \
                max(fits[q][0], fits[q + 2][0]) and pieces[q + 1][1] - pieces[q + 1][0] < 2 * MIN_SAMPLES + 2
            if abs(v1 - v2) <= SAME_VELOCITY * max(abs(v1), abs(v2)) + 3 * np.hypot(e1, e2):
                pieces[q:q + 2] = [[pieces[q][0], pieces[q + 1][1]]]
                changed = True
                break
            if between:  # the samples around a change that falls between samples: split them between the two
                mid = (pieces[q + 1][0] + pieces[q + 1][1]) // 2
                pieces[q:q + 3] = [[pieces[q][0], mid], [mid, pieces[q + 2][1]]]
                changed = True
                break
    edges = [0, *_refine(t, y, [p[0] for p in pieces[1:]]), t.size]  # the merges moved the neighbours' best cuts
    pieces = [[i, j] for i, j in zip(edges[:-1], edges[1:])]
    while True:
        fits = _trimmed_lines(t, y, pieces, s)
        q = _same_slide(pieces, fits)
        if q is None:
            break
        pieces[q[0]:q[1] + 1] = [[pieces[q[0]][0], pieces[q[1]][1]]]
    fastest = max(abs(f[0]) for f in fits)
    moving = [abs(v) >= 3 * e and abs(v) >= HOLD_FRACTION * fastest for v, _, e in fits]
    # a hold too short for a piece of its own: the slide after it behind (positive velocities only)
    pauses = [_pauses(t[i:j], y[i:j], fits[q][0], s) if moving[q] and fits[q][0] > 0 else []
              for q, (i, j) in enumerate(pieces)]
    head, tail = list(fits), list(fits)  # the lines that meet the previous and the next piece: a piece's line
    for q, found in enumerate(pauses):  # through its pauses is offset by their lag (0.4 s on the next hold's start)
        if found:  # the samples before the first pause and after the last, trimmed at the changes as the lines are
            i, j = pieces[q]
            trim = min(TRIM, (j - i) // 4)
            i, j = i + trim * (q > 0), j - trim * (q < len(pieces) - 1)
            before, after = t[i:j] < found[0][0], t[i:j] >= found[-1][0]
            if before.sum() >= 2:
                head[q] = _line(t[i:j][before], y[i:j][before], s)
            if after.sum() >= 2:
                tail[q] = _line(t[i:j][after], y[i:j][after], s)
    steps = []
    for q, ((i, j), (v, _, _)) in enumerate(zip(pieces, fits)):
        start = float(t[0])
        if q > 0:  # where the two pieces' lines cross, if between their samples; else between the samples
            (vp, cp, _), (vh, ch, _) = tail[q - 1], head[q]
            cross = (ch - cp) / (vp - vh) if vp != vh else np.nan
            start = float(cross) if t[pieces[q - 1][0]] < cross < t[j - 1] else 0.5 * float(t[i - 1] + t[i])
        steps.append((start, float(v) if moving[q] else 0.0))
    for q in reversed(range(len(pieces))):
        if pauses[q]:  # the piece's velocity without the pauses' lag in its line
            v = pauses[q][1][1]
            steps[q:q + 1] = [(steps[q][0], v)] + [(a, v if b else 0.0) for a, b in pauses[q]]
    merged = [steps[0]]
    for st in steps[1:]:  # two holds in a row are one hold
        if not (st[1] == 0.0 and merged[-1][1] == 0.0):
            merged.append(st)
    return tuple(merged)


def _trimmed_lines(t: np.ndarray, y: np.ndarray, pieces: list[list[int]], s: float
                   ) -> list[tuple[float, float, float]]:
    """Each piece's line (:func:`_line`) less up to TRIM samples at a change (a change between samples bends the line
    through them: 0.6 % on the first velocity of a 1 -> 10 um/s step, shifting mu0 by 3e-5); a short piece (a 1 s
    hold at 10 Hz) keeps at least half its samples."""
    last = len(pieces) - 1
    cut = [min(TRIM, (j - i) // 4) for i, j in pieces]
    return [_line(t[i + cut[q] * (q > 0):j - cut[q] * (q < last)], y[i + cut[q] * (q > 0):j - cut[q] * (q < last)], s)
            for q, (i, j) in enumerate(pieces)]


def _same_slide(pieces: list[list[int]], fits: list[tuple[float, float, float]]) -> tuple[int, int] | None:
    """(first, last) of pieces to join into one: two neighbours whose trimmed velocities agree (SAME_VELOCITY plus 3
    standard errors; the merge before compares untrimmed lines, which a sample across the change bends: a 10 um/s
    slide after 2 s at 100 um/s sampled at 10 Hz came out as two pieces 0.5 % apart), or a piece of fewer than
    2 MIN_SAMPLES samples between two slides of one velocity (a hold of 3 samples at 1 Hz between slides at 10 Hz came
    out as a slide at 17 % of theirs): one slide, whose pause :func:`_pauses` then finds. None where none is."""
    def same(p, q):
        (v1, _, e1), (v2, _, e2) = fits[p], fits[q]
        return abs(v1 - v2) <= SAME_VELOCITY * max(abs(v1), abs(v2)) + 3 * np.hypot(e1, e2)

    for q in range(len(pieces) - 1):
        if same(q, q + 1):
            return q, q + 1
    for q in range(1, len(pieces) - 1):
        slides = min(fits[q - 1][0], fits[q + 1][0]) > 3 * max(fits[q - 1][2], fits[q + 1][2])
        if pieces[q][1] - pieces[q][0] < 2 * MIN_SAMPLES and slides and same(q - 1, q + 1) and \
                fits[q][0] < min(fits[q - 1][0], fits[q + 1][0]):
            return q - 1, q + 1
    return None


def _pauses(t: np.ndarray, y: np.ndarray, v: float, s: float) -> list[tuple[float, float]]:
    """The pauses inside a sliding piece (samples ``t``, ``y``, its velocity ``v`` [m/s], noise ``s`` [m]) as steps
    ((start, 0), (end, v)): where a step in the displacement (the line after it behind by d, sweep.fit.segments'
    split test on its fall of the RSS) lasts d/v longer than the sample spacing; the start where the line, flat for
    d/v, fits best (a grid over 3 pauses either side); the pieces before and after searched again."""
    n = t.size
    if n < 2 * MIN_SAMPLES + 1:
        return []
    k, gain, d = _best_column(t, y, jump=True)
    if k <= 0 or d >= 0 or gain <= PENALTY * np.log(n) * s * s:
        return []
    c0, v, d = np.linalg.lstsq(np.column_stack([np.ones(n), t, np.arange(n) >= k]), y, rcond=None)[0]
    lag = float(-d / v) if v > 0 else 0.0
    if d >= 0 or lag <= t[k] - t[k - 1]:
        return []
    taus = np.linspace(max(t[0], t[k] - 3 * lag), min(t[-1] - lag, t[k] + 2 * lag), 301)
    near = (t >= taus[0]) & (t <= taus[-1] + lag)
    tn, yn = t[near], y[near]
    rss = _pause_rss(np.ascontiguousarray(tn), np.ascontiguousarray(yn), float(c0), float(v), lag, taus)
    tau = float(taus[int(np.argmin(rss))])
    return [*_pauses(t[:k], y[:k], v, s), (tau, 0.0), (tau + lag, float(v)), *_pauses(t[k:], y[k:], v, s)]



@numba.njit(cache=True, nogil=True)
def _pause_rss(t, y, c0, v, lag, taus):  # pragma: no cover (compiled)
    """The residual sum of squares of y about c0 + v (min(t, tau) + max(t - tau - lag, 0)) (a line flat for ``lag``
    from ``tau``) at each of ``taus``: :func:`_pauses`' grid, summed as numpy sums (:func:`_pairwise_sum`), so the
    same bits and the same best tau as numpy's expression per tau (301 of them took ~3 ms where a piece has a
    pause)."""
    out, e = np.empty(taus.size), np.empty(t.size)
    for q in range(taus.size):
        tau = taus[q]
        for i in range(t.size):
            d = t[i] - tau - lag
            r = y[i] - c0 - v * (min(t[i], tau) + (d if d > 0.0 else 0.0))
            e[i] = r * r
        out[q] = _pairwise_sum(e, 0, t.size)
    return out


@numba.njit(cache=True, nogil=True)
def _block_sum(a, lo, n):  # pragma: no cover (compiled)
    """numpy's sum of a block of n <= 128 contiguous float64 (eight running sums from n = 8 on)."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - n % 8:
        r0, r1, r2, r3 = r0 + a[lo + i], r1 + a[lo + i + 1], r2 + a[lo + i + 2], r3 + a[lo + i + 3]
        r4, r5, r6, r7 = r4 + a[lo + i + 4], r5 + a[lo + i + 5], r6 + a[lo + i + 6], r7 + a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@numba.njit(cache=True, nogil=True)
def _pairwise_sum(a, lo, n):  # pragma: no cover (compiled)
    """a[lo:lo + n].sum() as numpy sums a contiguous float64 array (pairwise: blocks of up to 128, :func:`_block_sum`,
    halves above that, split at a multiple of 8, left + right), the same bits (checked against np.sum for n = 0..300
    and beyond). A stack, not recursion: a cached kernel calling a recursive one crashed on loading (numba 0.6x)."""
    los, ns, stage = np.empty(64, np.intp), np.empty(64, np.intp), np.zeros(64, np.intp)
    left = np.empty(64)
    top = 0
    los[0], ns[0], stage[0] = lo, n, 0
    while True:
        if ns[top] <= 128:
            val = _block_sum(a, los[top], ns[top])
            top -= 1
            while top >= 0 and stage[top] == 1:  # both halves done: left + right
                val = left[top] + val
                top -= 1
            if top < 0:
                return val
            left[top], stage[top] = val, 1  # the left half done: the right next
            half = ns[top] // 2
            half -= half % 8
            los[top + 1], ns[top + 1], stage[top + 1] = los[top] + half, ns[top] - half, 0
            top += 1
        else:
            half = ns[top] // 2
            half -= half % 8
            los[top + 1], ns[top + 1], stage[top + 1] = los[top], half, 0
            top += 1

def _noise_floor(t: np.ndarray, y: np.ndarray) -> float:
    """The displacement's noise [m]: the robust neighbour scatter (sweep.fit.data.first_noise_estimate), at least the
    rounding noise q/sqrt(12) of its resolution q (the smallest step between samples: a column written to 0.1 um
    at 0.1 um/s is a staircase whose neighbour scatter is 0) and 1e-7 of its range (the sums round)."""
    d = np.abs(np.diff(y))
    q = float(d[d > 0].min()) if np.any(d > 0) else 0.0
    return max(first_noise_estimate(t, y) or 0.0, q / np.sqrt(12.0), 1e-7 * float(np.ptp(y)) or 1e-300)


def _refine(t: np.ndarray, y: np.ndarray, cuts: list[int], sweeps: int = 5) -> list[int]:
    """The cuts of a binary segmentation moved, one at a time, to the best continuous hinge between its neighbours
    (the first split of a stretch that holds several changes lands between them: a 1 s hold between two slides came
    out 0.9 s early at 0.1 um noise), until none moves (at most ``sweeps`` passes, O(n) each)."""
    cuts = list(cuts)
    for _ in range(sweeps):
        moved = False
        for q in range(len(cuts)):
            lo, hi = (cuts[q - 1] if q else 0), (cuts[q + 1] if q + 1 < len(cuts) else t.size)
            k, _, _ = _best_column(t[lo:hi], y[lo:hi])
            if k > 0 and lo + k != cuts[q]:
                cuts[q], moved = lo + k, True
        if not moved:
            break
    return cuts


def _line(t: np.ndarray, y: np.ndarray, s: float) -> tuple[float, float, float]:
    """(slope, intercept, standard error of the slope for noise ``s``) of the least-squares line through (t, y)."""
    slope, icpt, stt = _line_kernel(np.ascontiguousarray(t, dtype=np.float64),
                                    np.ascontiguousarray(y, dtype=np.float64))
    return float(slope), float(icpt), float(s / np.sqrt(stt))


@numba.njit(cache=True, nogil=True)
def _line_kernel(t, y):  # pragma: no cover (compiled)
    """(slope, intercept, sum of (t - mean t)^2) of the least-squares line, from centred sums (numpy's polyfit, a
    Vandermonde matrix and an SVD per piece, took a third of segmenting a 1,000-sample record)."""
    n = t.size
    tm, ym = 0.0, 0.0
    for i in range(n):
        tm += t[i]
        ym += y[i]
    tm, ym = tm / n, ym / n
    stt, sty = 0.0, 0.0
    for i in range(n):
        stt += (t[i] - tm) ** 2
        sty += (t[i] - tm) * (y[i] - ym)
    slope = sty / stt
    return slope, ym - slope * tm, stt


def record_steps(record: Record) -> tuple[tuple[float, float], ...]:
    """The record's steps: as given, or found from its load-point displacement (or velocity: its runs of one value,
    else integrated). A
    displacement that counts down (every piece's velocity <= 0: a gauge's sign) is taken as its magnitude; InputError
    where the load point moves both ways, or where the record starts in a hold (the model starts from steady sliding:
    the message says where the first slide begins, to cut the record with :meth:`Record.window`)."""
    if record.steps is not None:
        return record.steps
    found = record.__dict__.get("_found_steps")  # a record's data do not change: its steps are found once
    if found is None:
        found = _found_steps(record)
        object.__setattr__(record, "_found_steps", found)  # (Record is frozen; not one of its fields)
    return found


def _found_steps(record: Record) -> tuple[tuple[float, float], ...]:
    """:func:`record_steps` of a record without given steps (its checks included)."""
    x = record.displacement
    steps = None
    if x is None:
        v = record.velocity
        steps = _velocity_runs(record.t, v)
        if steps is None:
            x = np.concatenate(([0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(record.t))))
    if steps is None:
        steps = detect_steps(record.t, x)
    v = np.array([s[1] for s in steps])
    where = f"record {record.name!r}"
    if np.all(v <= 0) and np.any(v < 0):
        steps = tuple((a, abs(b)) for a, b in steps)
    elif np.any(v < 0):
        q = int(np.flatnonzero(v < 0)[0])
        raise InputError(f"{where}: the load point moves backwards from t = {steps[q][0]:g} s ({v[q]:.3g} m/s) and "
                         f"forwards elsewhere; the model drives it one way: cut the record (t_start, t_end) or give "
                         f"the steps")
    if steps[0][1] <= 0:
        column = "displacement" if record.displacement is not None else "velocity"
        if len(steps) == 1:
            raise InputError(f"{where}: the load point does not move (its {column} is flat); a record needs a "
                             f"sliding load point, or give the steps")
        raise InputError(f"{where}: the record starts in a hold (the load-point {column} is flat from t = "
                         f"{record.t[0]:g} to {steps[1][0]:g} s); the model starts from steady sliding at the "
                         f"first velocity: cut the record to start where it slides steadily, after the first slide "
                         f"(from {steps[1][0]:g} s) has reached steady friction (read_record(..., t_start=...), "
                         f"Record.window(t_start), [[data]] t_start = ...), or give the steps")
    return steps


RUNS = 0.05
"""A velocity column that changes value at fewer than this fraction of its samples is a commanded one (runs of one
value): its steps are read off it, not found by segmenting its integral."""


def _velocity_runs(t: np.ndarray, v: np.ndarray) -> tuple[tuple[float, float], ...] | None:
    """The steps of a commanded velocity column (piecewise constant, :data:`RUNS`): each change midway between the
    two samples around it (the integral's lines cross there too), a velocity below HOLD_FRACTION of the fastest a
    hold; None for a measured (noisy) velocity. Segmenting the integral of such a column found a spurious 55 ms pause
    where a 1 Hz hold ends (the sample before the change off the slide's line, the integral's noise floor ~1e-9 m)."""
    change = np.flatnonzero(v[1:] != v[:-1]) + 1
    if change.size >= RUNS * v.size:
        return None
    fastest = float(np.max(np.abs(v)))
    held = lambda u: 0.0 if abs(u) <= HOLD_FRACTION * fastest else float(u)  # noqa: E731
    steps = [(float(t[0]), held(v[0]))]
    for i in change:
        if held(v[i]) != steps[-1][1]:
            steps.append((0.5 * float(t[i - 1] + t[i]), held(v[i])))
    return tuple(steps)


def load_history(record: Record):
    """The record's :class:`sweep.protocols.history.forward.LoadHistory` from its first time on."""
    from ..protocols.history.forward import LoadHistory

    steps = record_steps(record)
    starts = np.array([s[0] for s in steps] + [float(record.t[-1])])
    return LoadHistory(velocities=np.array([s[1] for s in steps]), durations=np.diff(starts))
