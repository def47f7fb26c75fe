"""Uncertainty of a fit: covariance from the Jacobian, profile likelihoods, 95 % intervals, labels.

With the noise given, the misfit is chi^2 = sum r^2 (r = weighted residuals) and the 95 % profile interval of a
parameter is where chi^2_profile - chi^2_min <= 3.84 (chi^2 with one degree of freedom). With the noise estimated,
s^2 = RSS/(n - p) (in units of the nominal noise of sweep.fit.problem, squared), the covariance is s^2 (J^T J)^-1
and the interval uses the F threshold t_{0.975, n-p}^2 on (RSS_profile - RSS_min)/s^2 (Bates & Watts, Nonlinear
Regression Analysis, 1988, ch. 6).

Labels: ``not identifiable`` where the profile stays below the threshold up to a bound on either side (a flat
profile, or an interval that runs into a bound); ``poorly constrained`` where the 95 % interval reaches further than
``poor`` x |best| from the best value on either side (default 0.25); ``well constrained`` otherwise.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

__all__ = ["LABELS", "NOT_COMPUTED", "Interval", "covariance", "interval", "label", "threshold"]

LABELS = ("well constrained", "poorly constrained", "not identifiable")
NOT_COMPUTED = "not computed"
"""The label (flag 3 of the output's ``<name>_label``) of a parameter of a sample whose fit failed its forward solves
(sweep.fit.verdict): no interval was computed."""
LEVEL = 0.95


@functools.lru_cache(maxsize=256)
def threshold(noise_given: bool, dof: int) -> float:
    """Critical increase of the misfit (in units of the noise variance) for a 95 % interval of one parameter: the
    chi^2(1) quantile, or the squared t quantile (scipy.special's chdtri and stdtrit, the functions behind
    scipy.stats' chi2.ppf and t.ppf, bit for bit: importing scipy.stats cost ~1 s of a new process's first fit;
    cached, a campaign asks once per sample with a few distinct arguments)."""
    from scipy import special

    if noise_given:
        return float(special.chdtri(1, 1.0 - LEVEL))
    return float(special.stdtrit(max(dof, 1), 0.5 + LEVEL / 2) ** 2)


def noise_variance(rss: float, n: int, p: int, noise_given: bool) -> float:
    """1 with the noise given (the residuals are already in its units), else s^2 = RSS/(n - p) (residuals in units
    of the nominal noise, Problem.noise)."""
    return 1.0 if noise_given else rss / max(n - p, 1)


def covariance(jac: np.ndarray, s2: float) -> np.ndarray:
    """s^2 (J^T J)^-1 by the SVD of J (singular directions get infinite variance, never a silent number)."""
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    tol = np.finfo(float).eps * max(jac.shape) * (sv[0] if sv.size else 0.0)
    with np.errstate(divide="ignore"):
        inv = np.where(sv > tol, 1.0 / sv**2, np.inf)
    cov = (vt.T * inv) @ vt if np.all(np.isfinite(inv)) else np.full((jac.shape[1],) * 2, np.inf)
    return s2 * cov


@dataclass
class Interval:
    """A 95 % profile interval [lower, upper]; ``open_lower`` / ``open_upper``: the profile stayed below the
    threshold up to the bound (or the last profile point) on that side."""

    lower: float
    upper: float
    open_lower: bool
    open_upper: bool


def _side(values: np.ndarray, z: np.ndarray, best: float, crit: float) -> tuple[float, bool]:
    """End of the interval on one side: ``values`` ordered outwards from ``best``, z = sqrt(delta misfit)."""
    prev_v, prev_z = best, 0.0
    for v, zz in zip(values, z):
        if zz >= crit:
            f = (crit - prev_z) / (zz - prev_z)
            return prev_v + f * (v - prev_v), False
        prev_v, prev_z = v, zz
    return prev_v, True


def interval(best: float, values: np.ndarray, delta: np.ndarray, crit: float) -> Interval:
    """The 95 % interval from a profile: ``delta`` the misfit increase over the minimum at ``values`` (noise-variance
    units), ``crit`` :func:`threshold`. The crossing is interpolated linearly in sqrt(delta), which is linear in the
    parameter where the misfit is quadratic."""
    values, z = np.asarray(values), np.sqrt(np.maximum(np.asarray(delta), 0.0))
    c = np.sqrt(crit)
    ok = np.isfinite(z)
    up, down = ok & (values > best), ok & (values < best)
    iu, idn = np.argsort(values[up]), np.argsort(values[down])[::-1]
    hi, open_hi = _side(values[up][iu], z[up][iu], best, c)
    lo, open_lo = _side(values[down][idn], z[down][idn], best, c)
    return Interval(lo, hi, open_lo, open_hi)


def label(best: float, iv: Interval, poor: float) -> str:
    """One of :data:`LABELS` (module docstring)."""
    if iv.open_lower or iv.open_upper:
        return LABELS[2]
    if max(best - iv.lower, iv.upper - best) > poor * abs(best):
        return LABELS[1]
    return LABELS[0]
