"""One least-squares problem: the data sets of one sample and the parameter space they share.

For a parameter set theta the residuals are r = (model - data)/noise over every sample of every data set, in the
order of the data sets (curves: x(t_i); relaxed slips: Dx_inf at each (K/M, V)). With no noise given, ``noise`` is
a nominal NOMINAL_NOISE x the RMS of the sample's data [m], and the true noise is estimated from the residuals at
the best fit in its units (sweep.fit.uncertainty).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .data import Curve, Data, RelaxedSlips
from .records import Record
from .space import ParamSpace

__all__ = ["Problem", "make_problems"]

NOMINAL_NOISE = 1e-3
"""Where no noise is given, residuals are weighted by 1/(NOMINAL_NOISE x RMS of the data) [m-1] (not by 1 m-1):
least_squares' gradient tolerance is absolute, and residuals in metres (~1e-9) stopped it at its first point."""
MODEL_FAILED = 1e3
"""Residual [noise units] put where the engine returns no number (a parameter set the model cannot solve, e.g. no
finite relaxed slip): large enough that the Jacobian steers least squares away from it. It never decides which
parameter set wins: the global stage and the least squares rank sets by their number of failed residuals first
(sweep.fit.globalstage, sweep.fit.levenberg), since with the noise estimated (residuals in units of 1e-3 x the
data's RMS) or given small, a poor but solved set had a larger misfit than 1e3 a failure."""


@dataclass(frozen=True, eq=False)
class Problem:
    """The data sets ``data`` of sample ``name`` and the parameter ``space`` they share."""

    name: str
    data: tuple[Data, ...]
    space: ParamSpace

    @property
    def rows(self) -> int:
        """Forward points per parameter set: one per curve and one per relaxed-slip value."""
        return sum(1 if isinstance(d, Curve) else d.n for d in self.data)

    @property
    def n_t(self) -> int:
        """Sampled times of its longest curve."""
        return max([d.n for d in self.data if isinstance(d, Curve)], default=0)

    @property
    def n_residuals(self) -> int:
        return sum(d.n for d in self.data)

    @property
    def noise_given(self) -> bool:
        return self.data[0].noise is not None

    @property
    def observed(self) -> np.ndarray:
        """The data, concatenated in residual order [m]."""
        return np.concatenate([d.x if isinstance(d, Curve) else d.mu if isinstance(d, Record) else d.dx_inf
                               for d in self.data])

    @property
    def noise(self) -> np.ndarray:
        """Noise per residual [m]: as given, or (none given) the nominal NOMINAL_NOISE x RMS of the data, whose
        multiple sqrt(s^2) is the estimated noise (sweep.fit.uncertainty.noise_variance)."""
        if not self.noise_given:
            return np.full(self.n_residuals, NOMINAL_NOISE * float(np.sqrt(np.mean(self.observed ** 2))))
        return np.concatenate([d.noise for d in self.data])

    @property
    def weights(self) -> np.ndarray:
        """1/noise per residual [m-1]."""
        return 1.0 / self.noise

    def stiffness_velocity(self) -> tuple[np.ndarray, np.ndarray]:
        """Nominal (K/M [s-2], V [m s-1]) of each forward row."""
        km = [np.atleast_1d(d.K_over_M) for d in self.data]
        v = [np.atleast_1d(d.V) for d in self.data]
        return np.concatenate(km), np.concatenate(v)

    def layout(self, n_t: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Where the model values come from, for sweep.fit.stack: per forward row (one per curve, one per relaxed-slip
        value) its times padded to ``n_t`` columns with its last one (rows, n_t) and how many are its own (0: relaxed
        slip only); per residual, its forward row and its column among the sampled times (-1: the relaxed slip)."""
        times, lengths = np.zeros((self.rows, n_t)), np.zeros(self.rows, np.intp)
        res_row, res_col = np.empty(self.n_residuals, np.intp), np.full(self.n_residuals, -1, np.intp)
        r = i = 0
        for d in self.data:
            if isinstance(d, Curve):
                times[r], lengths[r] = d.t[-1], d.n  # padded beyond its length (never solved there)
                times[r, :d.n] = d.t
                res_row[i:i + d.n], res_col[i:i + d.n] = r, np.arange(d.n)
                r += 1
            else:
                res_row[i:i + d.n] = r + np.arange(d.n)
                r += d.n
            i += d.n
        return times, lengths, res_row, res_col


def make_problems(data: Sequence[Data], space: ParamSpace, per_data_set: bool) -> list[Problem]:
    """Group the data sets into problems: by their ``sample`` name (shared parameters), or one per data set."""
    if isinstance(data, (Curve, RelaxedSlips, Record)):
        data = [data]
    data = list(data)
    if not data:
        raise InputError("data is empty: give at least one Curve or RelaxedSlips")
    for i, d in enumerate(data):
        if not isinstance(d, (Curve, RelaxedSlips, Record)):
            raise InputError(f"data[{i}] must be a sweep.fit Curve, RelaxedSlips or Record, got {type(d).__name__}")
    if len({isinstance(d, Record) for d in data}) > 1:
        raise InputError("data mixes records with curves or relaxed slips: fit records in a call of their own")
    groups: dict[str, list[Data]] = {}
    for i, d in enumerate(data):
        groups.setdefault(f"{d.name}#{i}" if per_data_set else d.sample, []).append(d)
    problems = [Problem(name, tuple(ds), space) for name, ds in groups.items()]
    for pr in problems:
        given = {d.noise is not None for d in pr.data}
        if given == {False} and not np.any(pr.observed > 0):
            raise InputError(f"sample {pr.name!r}: every data value is 0 and no noise is given; nothing to fit")
        if len(given) > 1:
            raise InputError(f"sample {pr.name!r}: give noise for every data set or for none (it is then estimated "
                             f"from the residuals)")
        if pr.n_residuals <= space.p:
            raise InputError(f"sample {pr.name!r}: {pr.n_residuals} data values for {space.p} free parameters; "
                             f"need more values than parameters")
    return problems
