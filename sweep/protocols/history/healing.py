"""The healing rate of a slide-hold-slide series: beta = d Delta mu_peak / d log10 t_h (docs/physics.md 7b), per point
the least-squares slope of the peaks after its holds against the holds' log10 durations, with an error bound from
the peaks' error estimates."""

from __future__ import annotations

import numpy as np

__all__ = ["hold_before", "healing_rate", "is_series"]


def is_series(segments) -> bool:
    """Whether a history's segments (sweep.protocols.history.segments.check_segments) hold at least two reslides
    after a hold (V_ratio = 0 followed by V_ratio != 0): a slide-hold-slide series, of which beta is defined."""
    ratios = [seg.get("V_ratio", 0.0) for seg in segments]  # a hold given as {hold = t} has none
    return sum(1 for prev, r in zip(ratios, ratios[1:]) if prev == 0 and r != 0) >= 2


def hold_before(ratios: np.ndarray, durations: np.ndarray) -> np.ndarray:
    """(points, segments): the duration [s] of the hold just before each segment, NaN where the segment does not
    follow a hold. ``ratios`` (segments,) or (points, segments) V_ratio; ``durations`` (points, segments) [s]."""
    r = np.broadcast_to(ratios, durations.shape)
    prev_r = np.concatenate([np.full((r.shape[0], 1), np.nan), r[:, :-1]], axis=1)
    prev_t = np.concatenate([np.full((r.shape[0], 1), np.nan), durations[:, :-1]], axis=1)
    return np.where((prev_r == 0) & (r > 0), prev_t, np.nan)


def healing_rate(peak: np.ndarray, peak_error: np.ndarray, t_hold: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(beta, beta_error) per point from Delta mu_peak ``peak`` (points, segments) [1], its error estimate, and the
    preceding holds' durations ``t_hold`` [s] (NaN: no hold before; :func:`hold_before`).

    beta = sum_i c_i Delta mu_peak_i with c_i = (x_i - mean x)/sum_j (x_j - mean x)^2, x = log10 t_h over the
    point's reslides with a finite peak; its error sum_i |c_i| error_i (a bound, as the errors are). NaN where a
    point has fewer than two such holds of different durations."""
    use = np.isfinite(peak) & np.isfinite(t_hold) & (t_hold > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where(use, np.log10(np.where(use, t_hold, 1.0)), 0.0)
        n = use.sum(axis=1)
        mean = x.sum(axis=1) / n
        dx = np.where(use, x - mean[:, None], 0.0)
        sxx = (dx**2).sum(axis=1)
        c = dx / sxx[:, None]
        beta = (c * np.where(use, peak, 0.0)).sum(axis=1)
        error = (np.abs(c) * np.where(use, peak_error, 0.0)).sum(axis=1)
    fit = (n >= 2) & (sxx > 0)
    return np.where(fit, beta, np.nan), np.where(fit, error, np.nan)
