"""Explicit Runge-Kutta methods as validated data (Butcher tableaux).

A method is (c, a, b, order). A tableau checks itself when built: the rows of ``a`` sum to ``c``
(consistency), the weights ``b`` sum to 1, ``a`` is strictly lower triangular (explicit), and the
order conditions up to ``order`` hold (Butcher's trees up to order 4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ButcherTableau", "RK4"]


@dataclass(frozen=True)
class ButcherTableau:
    name: str
    c: tuple[float, ...]
    a: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    order: int

    def __post_init__(self) -> None:
        c, a, b = np.array(self.c), np.array(self.a), np.array(self.b)
        s = len(b)
        if a.shape != (s, s) or c.shape != (s,):
            raise ValueError(f"{self.name}: inconsistent tableau shapes a{a.shape}, b({s}), c{c.shape}")
        if np.any(np.triu(a) != 0.0):
            raise ValueError(f"{self.name}: a must be strictly lower triangular (explicit method)")
        if not np.allclose(a.sum(axis=1), c, atol=1e-14):
            raise ValueError(f"{self.name}: row sums of a must equal c")
        for cond, value, exact in self._order_conditions(a, b, c):
            if abs(value - exact) > 1e-13:
                raise ValueError(f"{self.name}: order condition {cond} fails ({value} != {exact})")

    def _order_conditions(self, a: np.ndarray, b: np.ndarray, c: np.ndarray):
        """Order conditions up to min(order, 4): (name, value, exact value)."""
        conds = [("sum b = 1", b.sum(), 1.0)]
        if self.order >= 2:
            conds.append(("b.c = 1/2", b @ c, 1 / 2))
        if self.order >= 3:
            conds += [("b.c^2 = 1/3", b @ c**2, 1 / 3), ("b.A.c = 1/6", b @ a @ c, 1 / 6)]
        if self.order >= 4:
            conds += [
                ("b.c^3 = 1/4", b @ c**3, 1 / 4),
                ("b.(c*A.c) = 1/8", b @ (c * (a @ c)), 1 / 8),
                ("b.A.c^2 = 1/12", b @ a @ c**2, 1 / 12),
                ("b.A.A.c = 1/24", b @ a @ a @ c, 1 / 24),
            ]
        return conds


RK4 = ButcherTableau(
    name="rk4",
    c=(0.0, 0.5, 0.5, 1.0),
    a=((0.0, 0.0, 0.0, 0.0), (0.5, 0.0, 0.0, 0.0), (0.0, 0.5, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0)),
    b=(1 / 6, 1 / 3, 1 / 3, 1 / 6),
    order=4,
)
"""Classical fourth-order Runge-Kutta method (fixed step)."""
