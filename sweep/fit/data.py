"""Measured data a fit takes, validated before any work (SI units).

Two kinds, those of the paper (docs/fit.md):

* :class:`Curve`: a relaxation curve after a stop, slip x(t) [m] against time t [s] since the stop, at known K/M
  [s-2] and V [m s-1] (paper Figs. 2 and 4a);
* :class:`RelaxedSlips`: relaxed slips Dx_inf [m] at a set of (K/M, V) (paper Fig. 3).

``noise`` is the standard deviation of each sample [m]: a number, one per sample, or None (estimated from the
residuals of the fit). ``sample`` names the friction sample the data belong to: data sets with the same name share
one parameter set in a fit (unless the fit is per data set).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["Curve", "RelaxedSlips", "Data"]


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
        raise InputError(f"{field}[{bad[0]}] = {float(arr[bad[0]])!r}: every value must be finite (no NaN or inf)")
    return arr


def _positive(field: str, values, n: int | None = None, allow_zero: bool = False) -> np.ndarray:
    arr = _values(field, values, n)
    bad = np.flatnonzero(arr < 0 if allow_zero else arr <= 0)
    if bad.size:
        rel = ">= 0" if allow_zero else "> 0"
        raise InputError(f"{field}[{bad[0]}] = {float(arr[bad[0]])!r}: must be {rel}")
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
    x >= 0 (the slip since the stop); ``noise`` [m] per sample or None; ``name`` labels the curve in the output."""

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
        set_("x", _positive(where + "x", self.x, t.size, allow_zero=True))
        set_("K_over_M", _scalar(where + "K_over_M", self.K_over_M))
        set_("V", _scalar(where + "V", self.V))
        set_("noise", _noise(where + "noise", self.noise, t.size))
        set_("sample", str(self.sample))

    @property
    def n(self) -> int:
        return self.t.size


@dataclass(frozen=True, eq=False)
class RelaxedSlips:
    """Relaxed slips ``dx_inf`` [m] (> 0) measured at the stiffnesses ``K_over_M`` [s-2] and velocities ``V``
    [m s-1] (one of each per value; paper Fig. 3); ``noise`` [m] per value or None."""

    K_over_M: np.ndarray
    V: np.ndarray
    dx_inf: np.ndarray
    noise: np.ndarray | None = None
    sample: str = "sample"
    name: str = "relaxed"

    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 (frozen)
        where = f"relaxed slips {self.name!r}: "
        dx = _positive(where + "dx_inf", self.dx_inf)
        set_("dx_inf", dx)
        for field in ("K_over_M", "V"):
            set_(field, _positive(where + field, getattr(self, field), dx.size))
        set_("noise", _noise(where + "noise", self.noise, dx.size))
        set_("sample", str(self.sample))

    @property
    def n(self) -> int:
        return self.dx_inf.size


Data = Curve | RelaxedSlips
"""One data set of a fit."""
