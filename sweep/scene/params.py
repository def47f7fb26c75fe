"""Friction parameters of the rate-and-state law (docs/physics.md section 1, paper eqs. 1, 6).

    mu(xdot, phi) = mu_d(D0/phi) + A ln(xdot phi / D0)
    mu_d(v)       = m0 - m1 ln(v/V0) + m2 [ln(v/V0)]^2

The laboratory's parameters (a, b, Dc, mu0, V0) of mu = mu0 + a ln(v/V0) + b ln(V0 theta/Dc) are the same law at
m2 = 0 (docs/physics.md 7b): a = A, b = A + m1, Dc = D0, mu0 = m0, theta = phi; the stiffness k [1/m] (friction per
metre of load-point displacement) is K/(M g).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import InputError

__all__ = ["LAB_NAMES", "FrictionParams", "K_over_M_from_k", "k_from_K_over_M"]

LAB_NAMES = ("a", "b", "Dc", "mu0", "V0")
"""The laboratory's names of the friction parameters (:meth:`FrictionParams.from_lab`)."""


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

    @classmethod
    def from_lab(cls, a: float, b: float, Dc: float, mu0: float = 0.6, V0: float = 1e-6,
                 g: float = 9.81) -> FrictionParams:
        """The law mu = mu0 + a ln(v/V0) + b ln(V0 theta/Dc) of the laboratory's parameters (a, b dimensionless,
        Dc [m], V0 [m/s]) in the paper's: A = a, m1 = b - a, m2 = 0, D0 = Dc, m0 = mu0 (docs/physics.md 7b)."""
        a = require_positive("a", a)
        b = require_finite("b", b)
        return cls(A=a, m1=b - a, m2=0.0, D0=require_positive("Dc", Dc), V0=V0, m0=require_finite("mu0", mu0), g=g)

    def to_lab(self) -> dict[str, float]:
        """{a, b, Dc, mu0, V0} of this law; InputError where m2 != 0 (a quadratic mu_d has no (a, b) equivalent)."""
        if self.m2 != 0.0:
            raise InputError(f"m2 = {self.m2!r}: the laboratory's (a, b, Dc) describe m2 = 0 only (mu_d linear in "
                             "ln v); keep the paper's parameters A, m1, m2, D0")
        return {"a": self.A, "b": self.A + self.m1, "Dc": self.D0, "mu0": self.m0, "V0": self.V0}


def K_over_M_from_k(k: float | np.ndarray, g: float = 9.81) -> float | np.ndarray:
    """K/M [s^-2] of the laboratory's stiffness k [1/m] (friction per metre of load-point displacement): k g."""
    return np.multiply(k, g)


def k_from_K_over_M(K_over_M: float | np.ndarray, g: float = 9.81) -> float | np.ndarray:
    """The laboratory's stiffness k = K/(M g) [1/m] of K/M [s^-2]."""
    return np.divide(K_over_M, g)
