"""Friction parameters of the rate-and-state law (docs/physics.md section 1, paper eqs. 1, 6).

    mu(xdot, phi) = mu_d(D0/phi) + A ln(xdot phi / D0)
    mu_d(v)       = m0 - m1 ln(v/V0) + m2 [ln(v/V0)]^2
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ..errors import InputError

__all__ = ["FrictionParams"]


def require_finite(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise :class:`InputError` naming ``name``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(x):
        raise InputError(f"{name} must be finite, got {x!r}")
    return x


def require_positive(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise :class:`InputError` unless 0 < value < inf."""
    x = require_finite(name, value)
    if x <= 0.0:
        raise InputError(f"{name} must be > 0 (allowed range: 0 < {name} < inf), got {x!r}")
    return x


@dataclass(frozen=True)
class FrictionParams:
    """Parameters of the friction law, SI units.

    Attributes
    ----------
    A : float
        Direct-effect coefficient [1], A > 0 (paper eq. 1).
    m1 : float
        Linear velocity-weakening coefficient of mu_d [1] (paper eq. 6).
    m2 : float
        Quadratic coefficient of mu_d in ln(v/V0) [1] (paper eq. 6). m2 < 0 gives no finite relaxed slip.
    D0 : float
        Memory length [m], D0 > 0.
    V0 : float
        Reference velocity of the expansion of mu_d [m s-1] (default 1 um/s).
    m0 : float
        mu_d(V0) [1]; a force offset, irrelevant to the dynamics (kept for completeness).
    g : float
        Gravitational acceleration [m s-2].
    """

    A: float
    m1: float
    m2: float
    D0: float
    V0: float = 1e-6
    m0: float = 0.3
    g: float = 9.81

    def __post_init__(self) -> None:
        for name in ("A", "D0", "V0", "g"):
            object.__setattr__(self, name, require_positive(name, getattr(self, name)))
        for name in ("m1", "m2", "m0"):
            object.__setattr__(self, name, require_finite(name, getattr(self, name)))

    def replace(self, **changes: float) -> FrictionParams:
        """A copy with some fields changed (validated again)."""
        unknown = set(changes) - set(asdict(self))
        if unknown:
            raise InputError(f"unknown friction parameter(s) {sorted(unknown)}; allowed: {sorted(asdict(self))}")
        return FrictionParams(**{**asdict(self), **changes})

    def as_dict(self) -> dict[str, float]:
        return asdict(self)
