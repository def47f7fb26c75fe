"""The parameter space of a fit: which parameters are free, their bounds and starting values, checked before any
work.

Free parameters may be any of :data:`FREE`: the friction parameters A, m1, m2 [1] and D0 [m] of
:class:`sweep.FrictionParams` (eqs. 1, 2, 6), and ``K_over_M_factor`` [1], a factor on every nominal K/M of a
sample (the spring's calibration). m0 never enters the dynamics (docs/physics.md 1). The others stay at the values
of ``params`` (a preset or your own :class:`sweep.FrictionParams`), which are also the starting values unless
``start`` overrides them.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..scene.params import FrictionParams, require_finite

__all__ = ["FREE", "UNITS", "ParamSpace", "bounded_space", "default_bounds", "make_space"]

FREE = ("A", "m1", "m2", "D0", "K_over_M_factor")
"""Parameters a fit may free, in the order they are reported."""
UNITS = {"A": "1", "m1": "1", "m2": "1", "D0": "m", "K_over_M_factor": "1",
         "a": "1", "b": "1", "Dc": "m", "mu0": "1", "k": "m-1"}  # the last five: a record fit's
POSITIVE = {"A", "D0", "K_over_M_factor", "a", "Dc", "k"}
"""Parameters that must stay > 0 (gridded in log by the global stage)."""


def default_bounds(name: str, start: Mapping[str, float]) -> tuple[float, float]:
    """Default bounds of a free parameter around the starting values ``start``: A and D0 within a factor 10,
    m1 within 5 max(|m1|, A), m2 in [0, 10 max(m2, A/10)] (m2 < 0 has no finite relaxed slip, docs/physics.md 6),
    the K/M factor in [0.5, 2]."""
    v = start[name]
    if name in ("A", "D0"):
        return v / 10.0, v * 10.0
    if name == "m1":
        w = 5.0 * max(abs(v), start["A"])
        return v - w, v + w
    if name == "m2":
        return 0.0, 10.0 * max(v, start["A"] / 10.0)
    return 0.5, 2.0


@dataclass(frozen=True, eq=False)
class ParamSpace:
    """Free parameters ``names`` with ``start``, ``lower`` and ``upper`` (arrays in the order of names) and the
    values of every parameter (free ones at their start) in ``values``; ``V0`` [m s-1] and ``g`` [m s-2] as in
    :class:`sweep.FrictionParams`."""

    names: tuple[str, ...]
    start: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    values: Mapping[str, float]
    V0: float
    g: float

    @property
    def p(self) -> int:
        return len(self.names)

    @property
    def log(self) -> np.ndarray:
        """Per free parameter: gridded in log (positive parameters with a positive lower bound)."""
        return np.array([n in POSITIVE for n in self.names]) & (self.lower > 0)

    @property
    def scale(self) -> np.ndarray:
        """Typical size of each free parameter (least squares' x_scale and the finite-difference steps): its
        starting magnitude, or a tenth of its bound interval where the start is 0."""
        s = np.abs(self.start)
        return np.where(s > 0, s, (self.upper - self.lower) / 10.0)

    def full(self, theta: np.ndarray) -> dict[str, np.ndarray]:
        """Every parameter of :data:`FREE` for the rows of ``theta`` (m x p): free ones from theta, others fixed."""
        theta = np.atleast_2d(theta)
        out = {n: np.full(theta.shape[0], float(v)) for n, v in self.values.items()}  # FREE, or a record fit's
        for j, n in enumerate(self.names):
            out[n] = theta[:, j].astype(float)
        return out

    def corners(self) -> np.ndarray:
        """The 2^p corners of the bound box (rows)."""
        return np.array(list(itertools.product(*zip(self.lower, self.upper)))).reshape(-1, self.p)


def make_space(free: Sequence[str], params: FrictionParams, bounds: Mapping[str, Sequence[float]] | None = None,
               start: Mapping[str, float] | None = None) -> ParamSpace:
    """Validate the free parameters, their bounds and starts (InputError naming the field and value otherwise)."""
    if isinstance(free, str):
        free = (free,)
    free = tuple(free)
    if not free:
        raise InputError(f"free is empty: name at least one parameter to fit, from {list(FREE)}")
    for name in free:
        if name not in FREE:
            raise InputError(f"free parameter {name!r} does not exist; allowed: {list(FREE)} (m0 never enters the "
                             f"dynamics)")
    if len(set(free)) != len(free):
        raise InputError(f"free names a parameter twice: {list(free)}")
    if not isinstance(params, FrictionParams):
        raise InputError(f"params must be a sweep.FrictionParams or a preset, got {type(params).__name__}")
    values = {"A": params.A, "m1": params.m1, "m2": params.m2, "D0": params.D0, "K_over_M_factor": 1.0}
    for name, value in dict(start or {}).items():
        if name not in FREE:
            raise InputError(f"start names {name!r}, which does not exist; allowed: {list(FREE)}")
        values[name] = require_finite(f"start {name}", value)
    return bounded_space(free, values, bounds, default_bounds, params)


def bounded_space(free: tuple[str, ...], values: dict[str, float], bounds: Mapping[str, Sequence[float]] | None,
                  defaults: Callable[[str, dict[str, float]], tuple[float, float]],
                  params: FrictionParams) -> ParamSpace:
    """The ParamSpace of ``free`` started at ``values``: each free parameter's bounds from ``bounds`` or
    ``defaults(name, values)``; InputError for bounds of a parameter that is not free, a lower bound <= 0 of a
    POSITIVE one, or a start outside its bounds."""
    for name in dict(bounds or {}):
        if name not in free:
            raise InputError(f"bounds name {name!r}, which is not free; free: {list(free)}")
    lo, hi = [], []
    for name in free:
        spec = dict(bounds or {}).get(name)
        b = defaults(name, values) if spec is None else _pair(name, spec)
        if name in POSITIVE and b[0] <= 0:
            raise InputError(f"bounds {name} = [{b[0]!r}, {b[1]!r}]: {name} must stay > 0, so the lower bound must "
                             f"be > 0")
        if not b[0] <= values[name] <= b[1]:
            raise InputError(f"start {name} = {values[name]!r} lies outside its bounds [{b[0]!r}, {b[1]!r}]")
        lo.append(b[0])
        hi.append(b[1])
    return ParamSpace(names=free, start=np.array([values[n] for n in free]), lower=np.array(lo), upper=np.array(hi),
                      values=values, V0=params.V0, g=params.g)


def _pair(name: str, spec) -> tuple[float, float]:
    try:
        lo, hi = spec
    except (TypeError, ValueError):
        raise InputError(f"bounds {name} must be [lower, upper], got {spec!r}") from None
    lo, hi = require_finite(f"bounds {name} lower", lo), require_finite(f"bounds {name} upper", hi)
    if not lo < hi:
        raise InputError(f"bounds {name} = [{lo!r}, {hi!r}]: the lower bound must be below the upper one")
    return lo, hi
