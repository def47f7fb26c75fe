"""The load history of a record: segments of constant load-point velocity (velocity steps, holds), given or found
from the load-point displacement.

Detection (binary segmentation of a piecewise-linear displacement): a segment of samples is split at the sample
where a continuous two-piece line (hinge) lowers the residual sum of squares most, if that lowers it by more than
PENALTY x ln(n) x s^2 (s the noise of the displacement, the robust scatter about neighbouring samples,
sweep.fit.data.first_noise_estimate; n the samples of the segment), recursively, no piece shorter than MIN_SAMPLES.
Each piece's velocity is its least-squares slope; a piece whose slope is within 3 standard errors of 0, or below
HOLD_FRACTION of the fastest, is a hold (velocity 0). A velocity column is integrated (trapezoids) to a
displacement first.
"""

from __future__ import annotations

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


def _best_hinge(t: np.ndarray, y: np.ndarray) -> tuple[int, float]:
    """(index of the best hinge sample, the RSS reduction it gives over one line) for one piece; all candidates from
    cumulative sums (O(n)): basis 1, t, (t - t_k)+ for each candidate k."""
    n = t.size
    tc = (t - t.mean()) / (np.ptp(t) or 1.0)
    yc = y - y.mean()
    one, S_t, S_tt = float(n), tc.sum(), (tc * tc).sum()
    S_y, S_ty, S_yy = yc.sum(), (tc * yc).sum(), (yc * yc).sum()
    rev = lambda a: np.cumsum(a[::-1])[::-1]  # noqa: E731 (sums over i >= k)
    N, T1, T2, Y1, TY = rev(np.ones(n)), rev(tc), rev(tc * tc), rev(yc), rev(tc * yc)
    b = tc
    h1 = T1 - b * N
    h2 = T2 - 2 * b * T1 + b * b * N
    th = T2 - b * T1
    hy = TY - b * Y1
    k = np.arange(MIN_SAMPLES, n - MIN_SAMPLES)
    if k.size == 0:
        return -1, 0.0
    M = np.zeros((k.size, 3, 3))
    M[:, 0, 0], M[:, 0, 1], M[:, 1, 1] = one, S_t, S_tt
    M[:, 1, 0] = S_t
    M[:, 0, 2] = M[:, 2, 0] = h1[k]
    M[:, 1, 2] = M[:, 2, 1] = th[k]
    M[:, 2, 2] = h2[k]
    rhs = np.stack([np.full(k.size, S_y), np.full(k.size, S_ty), hy[k]], axis=1)
    beta = np.linalg.solve(M, rhs[..., None])[..., 0]
    rss2 = S_yy - np.sum(beta * rhs, axis=1)
    slope = S_ty / S_tt if S_tt > 0 else 0.0
    rss1 = S_yy - slope * S_ty - S_y * S_y / one  # one line (yc has mean 0 so S_y ~ 0)
    j = int(np.argmin(rss2))
    return int(k[j]), float(rss1 - rss2[j])


def detect_steps(t: np.ndarray, displacement: np.ndarray, noise: float | None = None
                 ) -> tuple[tuple[float, float], ...]:
    """((start time [s], velocity [m s-1]), ...) of the pieces of a load-point displacement [m] sampled at ``t``
    [s] (module docstring); ``noise`` [m] of the displacement (default: estimated)."""
    t, y = np.asarray(t, float), np.asarray(displacement, float)
    s = first_noise_estimate(t, y) if noise is None else float(noise)
    s = max(s or 0.0, 1e-7 * float(np.ptp(y)) or 1e-300)  # the sums round: floor
    cuts, todo = [], [(0, t.size)]
    while todo:
        i, j = todo.pop()
        if j - i < 2 * MIN_SAMPLES + 1:
            continue
        k, gain = _best_hinge(t[i:j], y[i:j])
        if k > 0 and gain > PENALTY * np.log(j - i) * s * s:
            cuts.append(i + k)
            todo += [(i, i + k), (i + k, j)]
    edges = [0, *sorted(cuts), t.size]
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
    last = len(pieces) - 1  # each velocity from its piece less TRIM samples at a change (a change between samples
    # bends the line through them: 0.6 % on the first velocity of a 1 -> 10 um/s step, shifting mu0 by 3e-5)
    fits = [_line(t[i + TRIM * (q > 0):j - TRIM * (q < last)], y[i + TRIM * (q > 0):j - TRIM * (q < last)], s)
            for q, (i, j) in enumerate(pieces)]
    fastest = max(abs(f[0]) for f in fits)
    steps = []
    for q, ((i, j), (v, c, e)) in enumerate(zip(pieces, fits)):
        start = float(t[0])
        if q > 0:  # where the two pieces' lines cross, if between their samples; else between the samples
            vp, cp, _ = fits[q - 1]
            cross = (c - cp) / (vp - v) if vp != v else np.nan
            start = float(cross) if t[pieces[q - 1][0]] < cross < t[j - 1] else 0.5 * float(t[i - 1] + t[i])
        hold = abs(v) < 3 * e or abs(v) < HOLD_FRACTION * fastest
        steps.append((start, 0.0 if hold else float(v)))
    merged = [steps[0]]
    for st in steps[1:]:  # two holds in a row are one hold
        if not (st[1] == 0.0 and merged[-1][1] == 0.0):
            merged.append(st)
    return tuple(merged)


def _line(t: np.ndarray, y: np.ndarray, s: float) -> tuple[float, float, float]:
    """(slope, intercept, standard error of the slope for noise ``s``) of the least-squares line through (t, y)."""
    slope, icpt = np.polyfit(t, y, 1)
    return float(slope), float(icpt), float(s / np.sqrt(np.sum((t - t.mean()) ** 2)))


def record_steps(record: Record) -> tuple[tuple[float, float], ...]:
    """The record's steps: as given, or found from its load-point displacement (or velocity, integrated); InputError
    where the record starts in a hold or the load point moves backwards."""
    if record.steps is not None:
        return record.steps
    x = record.displacement
    if x is None:
        v = record.velocity
        x = np.concatenate(([0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(record.t))))
    steps = detect_steps(record.t, x)
    if steps[0][1] <= 0:
        raise InputError(f"record {record.name!r}: the load point does not move at the start (found "
                         f"{steps[0][1]:g} m/s up to t = {steps[1][0] if len(steps) > 1 else record.t[-1]:g} s); "
                         f"the model starts from steady sliding: cut the record or give the steps")
    return steps


def load_history(record: Record):
    """The record's :class:`sweep.protocols.history.forward.LoadHistory` from its first time on."""
    from ..protocols.history.forward import LoadHistory

    steps = record_steps(record)
    starts = np.array([s[0] for s in steps] + [float(record.t[-1])])
    return LoadHistory(velocities=np.array([s[1] for s in steps]), durations=np.diff(starts))
