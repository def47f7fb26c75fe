"""Measured data a fit takes, validated before any work (SI units).

Two kinds, those of the paper (docs/fit.md):

* :class:`Curve`: a relaxation curve after a stop, slip x(t) [m] against time t [s] since the stop, at known K/M
  [s-2] and V [m s-1] (paper Figs. 2 and 4a);
* :class:`RelaxedSlips`: relaxed slips Dx_inf [m] at a set of (K/M, V) (paper Fig. 3).

``noise`` is the standard deviation of each sample [m]: a number, one per sample, or None (estimated from the
residuals of the fit). ``sample`` names the friction sample the data belong to: data sets with the same name share
one parameter set in a fit (unless the fit is per data set).

Slips are measured with noise, so values a little below zero (near the stop of a curve, a tiny relaxed slip) are
data, not mistakes: a slip may lie down to NEGATIVE_NOISE (5) times its noise below zero. With the noise not given,
down to NEGATIVE_FRACTION (5 %) of the data's range (max - min) below zero or, for a curve, 5 times a first estimate
of its noise, whichever reaches further: the scatter of each sample about the straight line through its neighbours
(robust: 1.4826 x the median absolute deviation, each deviation divided by its own factor sqrt(1 + w^2 + (1 - w)^2)
for the interpolation weight w at its time; a curve of 5 samples or more). A refusal lists every offending index.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["Curve", "RelaxedSlips", "Data", "NEGATIVE_FRACTION", "NEGATIVE_NOISE", "first_noise_estimate"]

NEGATIVE_NOISE = 5.0
"""How many times its noise a slip may lie below zero."""
NEGATIVE_FRACTION = 0.05
"""With no noise given and no first estimate of it (relaxed slips, a curve of < 5 samples): how far below zero a slip
may lie, as a fraction of the data's range (max - min)."""


def _indices(bad: np.ndarray) -> str:
    """Every index of ``bad`` (sorted ints), runs of consecutive ones as a..b: 3, 7, 10..15."""
    runs, start = [], None
    for k, i in enumerate(bad):
        if start is None:
            start = i
        if k + 1 == bad.size or bad[k + 1] != i + 1:
            runs.append(f"{start}" if start == i else f"{start}..{i}")
            start = None
    return ", ".join(runs)


def _which(field: str, arr: np.ndarray, bad: np.ndarray) -> str:
    """'x[3] = -3.46e-09' for one offending value; else 'x at indices 3, 7, 10..15 (4 values; x[3] = ...)'."""
    first = f"{field}[{bad[0]}] = {float(arr[bad[0]])!r}"
    if bad.size == 1:
        return first
    where, _, name = field.rpartition(": ")
    return (f"{where}: " if where else "") + \
        f"{name} at indices {_indices(bad)} ({bad.size} values; {name}[{bad[0]}] = {float(arr[bad[0]])!r})"


def _values(field: str, values, n: int | None = None) -> np.ndarray:
    """A finite 1-D float array (of length ``n`` when given), or InputError naming ``field`` and the bad value."""
    try:
        arr = np.array(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"{field} must be a sequence of numbers, got {values!r}") from None
    if arr.size == 0:
        raise InputError(f"{field} is empty: give at least one value")
    if n is not None and arr.size != n:
        raise InputError(f"{field} has {arr.size} values, expected {n} (one per sample)")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise InputError(f"{_which(field, arr, bad)}: every value must be finite (no NaN or inf)")
    return arr


def _positive(field: str, values, n: int | None = None, allow_zero: bool = False) -> np.ndarray:
    arr = _values(field, values, n)
    bad = np.flatnonzero(arr < 0 if allow_zero else arr <= 0)
    if bad.size:
        rel = ">= 0" if allow_zero else "> 0"
        raise InputError(f"{_which(field, arr, bad)}: must be {rel}")
    return arr


def first_noise_estimate(t: np.ndarray, x: np.ndarray) -> float | None:
    """A first estimate of a curve's noise [m] before any fit (module docstring): the robust scatter of each sample
    about the line through its two neighbours; None with fewer than 5 samples. The curve's own bending adds to it,
    so it errs on the large side (a lenient floor for negative slips)."""
    if t.size < 5:
        return None
    w = (t[1:-1] - t[:-2]) / (t[2:] - t[:-2])
    d = (x[1:-1] - (x[:-2] + w * (x[2:] - x[:-2]))) / np.sqrt(1.0 + w**2 + (1.0 - w) ** 2)
    return float(1.4826 * np.median(np.abs(d - np.median(d))))


def _slips(field: str, values, n: int | None, noise: np.ndarray | None, t: np.ndarray | None = None) -> np.ndarray:
    """Slips [m]: finite, and none below the floor of the module docstring (InputError listing every index below)."""
    arr = _values(field, values, n)
    if noise is not None:
        floor, why = -NEGATIVE_NOISE * noise, f"{NEGATIVE_NOISE:g} x its noise below 0"
    else:
        s1 = first_noise_estimate(t, arr) if t is not None and t.size == arr.size else None
        reach = NEGATIVE_FRACTION * float(np.ptp(arr))
        why = f"{NEGATIVE_FRACTION:g} x the data's range ({reach:.3g} m) below 0 (no noise given)"
        if s1 is not None and NEGATIVE_NOISE * s1 > reach:
            reach = NEGATIVE_NOISE * s1
            why = (f"{NEGATIVE_NOISE:g} x a first estimate of the noise ({s1:.3g} m, from the scatter about "
                   f"neighbouring samples) below 0 (no noise given)")
        floor = np.full(arr.size, -reach)
    bad = np.flatnonzero(arr < floor)
    if bad.size:
        raise InputError(f"{_which(field, arr, bad)}: a slip may lie at most {why}; check the sign and the zero of "
                         f"the slip, or give the noise")
    return arr


def _noise(field: str, noise, n: int) -> np.ndarray | None:
    if noise is None:
        return None
    arr = np.broadcast_to(_positive(field, np.atleast_1d(noise)), (n,)) if np.ndim(noise) == 0 else \
        _positive(field, noise, n)
    return np.array(arr, dtype=float)


def _scalar(field: str, value) -> float:
    arr = _positive(field, [value] if np.ndim(value) == 0 else value)
    if arr.size != 1:
        raise InputError(f"{field} must be one number, got {arr.size} values")
    return float(arr[0])


@dataclass(frozen=True, eq=False)
class Curve:
    """A relaxation curve after a stop (paper Fig. 2): slip ``x`` [m] at times ``t`` [s] after the stop, for a
    slider that slid steadily at ``V`` [m s-1] on a spring of ``K_over_M`` [s-2]. t strictly increasing and >= 0,
    x the slip since the stop (>= 0 but for noise: down to 5 x the noise below 0, module docstring); ``noise`` [m] per
    sample or None; ``name`` labels the curve in the output."""

    t: np.ndarray
    x: np.ndarray
    K_over_M: float
    V: float
    noise: np.ndarray | None = None
    sample: str = "sample"
    name: str = "curve"

    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 (frozen)
        where = f"curve {self.name!r}: "
        t = _positive(where + "t", self.t, allow_zero=True)
        step = np.flatnonzero(np.diff(t) <= 0)
        if step.size:
            i = int(step[0]) + 1
            raise InputError(f"{where}t must be strictly increasing [s], but t[{i}] = {float(t[i])!r} follows "
                             f"t[{i - 1}] = {float(t[i - 1])!r}")
        set_("t", t)
        set_("noise", _noise(where + "noise", self.noise, t.size))
        set_("x", _slips(where + "x", self.x, t.size, self.noise, t))
        set_("K_over_M", _scalar(where + "K_over_M", self.K_over_M))
        set_("V", _scalar(where + "V", self.V))
        set_("sample", str(self.sample))

    @property
    def n(self) -> int:
        return self.t.size


@dataclass(frozen=True, eq=False)
class RelaxedSlips:
    """Relaxed slips ``dx_inf`` [m] (> 0 but for noise: down to 5 x the noise below 0, module docstring) measured at
    the stiffnesses ``K_over_M`` [s-2] and velocities ``V`` [m s-1] (one of each per value; paper Fig. 3); ``noise``
    [m] per value or None."""

    K_over_M: np.ndarray
    V: np.ndarray
    dx_inf: np.ndarray
    noise: np.ndarray | None = None
    sample: str = "sample"
    name: str = "relaxed"

    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 (frozen)
        where = f"relaxed slips {self.name!r}: "
        n = _values(where + "dx_inf", self.dx_inf).size
        set_("noise", _noise(where + "noise", self.noise, n))
        set_("dx_inf", _slips(where + "dx_inf", self.dx_inf, None, self.noise))
        for field in ("K_over_M", "V"):
            set_(field, _positive(where + field, getattr(self, field), n))
        set_("sample", str(self.sample))

    @property
    def n(self) -> int:
        return self.dx_inf.size


Data = Curve | RelaxedSlips
"""One data set of a fit."""
