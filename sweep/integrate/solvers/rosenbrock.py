"""Linearly implicit (Rosenbrock) methods as validated data, for the stiff points of a sweep.

A Rosenbrock method for y' = f(t, y) solves one linear system per stage with the same matrix, in the
transformed form of Hairer & Wanner (*Solving Ordinary Differential Equations II*, 2nd ed., Springer 1996,
Sec. IV.7, eq. 7.25'), which needs no matrix-vector product with the Jacobian J = df/dy:

    (I/(h gamma) - J) u_i = f(t0 + alpha_i h, y0 + sum_j a_ij u_j) + sum_j (c_ij/h) u_j + gamma_i h df/dt,
    y1 = y0 + sum_i m_i u_i,        error estimate sum_i e_i u_i.

For a scalar equation (the stop model in contact-age time, :mod:`sweep.integrate.lanes`) the "system" is one
division per step, so a stage costs the same as an explicit stage while the method stays stable at any step
(A-stable; Shampine's parameters have |R(inf)| = 1/3: not L-stable, but stiff modes are damped by 3x per step).

A :class:`RosenbrockTableau` checks itself when built: it maps the transformed coefficients back to the
standard ones (alpha_ij, gamma_ij, b_i; Gamma = (diag(1/gamma) - C)^-1, alpha = a Gamma, b = m Gamma) and
verifies the order conditions of HW Table IV.7.1 up to order 4 (8 conditions; beta_ij = alpha_ij + gamma_ij,
beta'_i = sum_j<i beta_ij, alpha_i = sum_j alpha_ij), for the weights m and for the embedded weights m - e.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .tableau import COEFFICIENT_TOL

__all__ = ["RODAS3", "ROS4", "RosenbrockTableau", "rosenbrock_conditions"]


def rosenbrock_conditions(alpha: np.ndarray, gam: np.ndarray, b: np.ndarray, gamma: float) -> list[tuple[str, float,
                                                                                                         float]]:
    """(name, sum, required value) of the order conditions 1..4 of HW Table IV.7.1 for standard coefficients
    alpha (strictly lower), gam (strictly lower part of Gamma), weights b and diagonal gamma."""
    beta = alpha + gam
    beta_p = beta.sum(axis=1)
    alpha_i = alpha.sum(axis=1)
    g = gamma
    return [
        ("b.1", b.sum(), 1.0),
        ("b.beta'", b @ beta_p, 0.5 - g),
        ("b.alpha^2", b @ alpha_i**2, 1.0 / 3.0),
        ("b.beta.beta'", b @ beta @ beta_p, 1.0 / 6.0 - g + g * g),
        ("b.alpha^3", b @ alpha_i**3, 0.25),
        ("b.alpha.alpha.beta'", b @ (alpha_i * (alpha @ beta_p)), 1.0 / 8.0 - g / 3.0),
        ("b.beta.alpha^2", b @ beta @ alpha_i**2, 1.0 / 12.0 - g / 3.0),
        ("b.beta.beta.beta'", b @ beta @ beta @ beta_p, 1.0 / 24.0 - g / 2.0 + 1.5 * g * g - g**3),
    ]


_CONDITIONS_UP_TO = {1: 1, 2: 2, 3: 4, 4: 8}
"""Number of conditions of HW Table IV.7.1 needed for each order."""


@dataclass(frozen=True)
class RosenbrockTableau:
    """A Rosenbrock method in transformed form (module docstring); validated on construction.

    gamma : the diagonal of Gamma (one value: one LU / division per step).
    a, c : strictly lower triangular transformed coefficients a_ij and c_ij.
    alpha_x, gamma_x : the nodes alpha_i = sum_j alpha_ij and gamma_i = sum_j gamma_ij (df/dt terms).
    m, e : weights of the solution and of the error estimate (embedded solution m - e of order ``order_hat``).
    same_f : stages whose f-evaluation equals the previous stage's (a_i. = a_{i-1}., alpha_i = alpha_{i-1}),
        evaluated once.
    """

    name: str
    gamma: float
    a: tuple[tuple[float, ...], ...]
    c: tuple[tuple[float, ...], ...]
    alpha_x: tuple[float, ...]
    gamma_x: tuple[float, ...]
    m: tuple[float, ...]
    e: tuple[float, ...]
    order: int
    order_hat: int

    def __post_init__(self) -> None:
        s = len(self.m)
        a, c = np.array(self.a, float), np.array(self.c, float)
        if a.shape != (s, s) or c.shape != (s, s) or np.any(np.triu(a) != 0) or np.any(np.triu(c) != 0):
            raise ValueError(f"{self.name}: a and c must be strictly lower triangular {s}x{s}")
        alpha, gam, b = self.standard_form()
        if not np.allclose(alpha.sum(axis=1), self.alpha_x, atol=COEFFICIENT_TOL):
            raise ValueError(f"{self.name}: alpha_x does not match the row sums of alpha")
        if not np.allclose(gam.sum(axis=1) + self.gamma, self.gamma_x, atol=COEFFICIENT_TOL):
            raise ValueError(f"{self.name}: gamma_x does not match the row sums of Gamma")
        b_hat = (np.array(self.m) - np.array(self.e)) @ self._gamma_matrix()
        for weights, order, label in ((b, self.order, "m"), (b_hat, self.order_hat, "m - e")):
            for name, value, want in rosenbrock_conditions(alpha, gam, weights, self.gamma)[
                    :_CONDITIONS_UP_TO[order]]:
                if abs(value - want) > COEFFICIENT_TOL * max(1.0, abs(want)):
                    raise ValueError(f"{self.name}: order condition {name} of the weights {label} fails "
                                     f"({value!r} != {want!r})")

    def _gamma_matrix(self) -> np.ndarray:
        s = len(self.m)
        return np.linalg.inv(np.eye(s) / self.gamma - np.array(self.c, float))

    def standard_form(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(alpha_ij, gamma_ij for j < i, b_i) of the standard form (HW eq. 7.4)."""
        G = self._gamma_matrix()
        alpha = np.array(self.a, float) @ G
        return alpha, np.tril(G, -1), np.array(self.m, float) @ G

    @property
    def stages(self) -> int:
        return len(self.m)

    @property
    def adaptive(self) -> bool:
        """Rosenbrock methods run with a step rule here (no controller)."""
        return False

    @property
    def implicit(self) -> bool:
        return True

    @property
    def error_order(self) -> int:
        return self.order_hat

    @property
    def fsal(self) -> bool:
        return False

    def stability_at_infinity(self) -> float:
        """R(inf) of the stability function R(z) = 1 + z b (I - z B)^-1 1, B = alpha + Gamma (HW IV.7.14)."""
        alpha, gam, b = self.standard_form()
        B = alpha + gam + self.gamma * np.eye(self.stages)
        return float(1.0 - b @ np.linalg.solve(B, np.ones(self.stages)))


def _lower(rows: Sequence[Sequence[float]], s: int) -> tuple[tuple[float, ...], ...]:
    out = [[0.0] * s for _ in range(s)]
    for i, row in enumerate(rows, start=1):
        out[i][: len(row)] = [float(x) for x in row]
    return tuple(tuple(r) for r in out)


ROS4 = RosenbrockTableau(
    # Shampine (1982), "Implementation of Rosenbrock methods", ACM TOMS 8, 93-113: the parameter set of
    # HW's code ROS4 (method 1); stage 4 reuses stage 3's f (a_4j = a_3j, alpha_4 = alpha_3).
    name="ros4",
    gamma=0.5,
    a=_lower([[2.0], [48.0 / 25.0, 6.0 / 25.0], [48.0 / 25.0, 6.0 / 25.0, 0.0]], 4),
    c=_lower([[-8.0], [372.0 / 25.0, 12.0 / 5.0], [-112.0 / 125.0, -54.0 / 125.0, -2.0 / 5.0]], 4),
    alpha_x=(0.0, 1.0, 3.0 / 5.0, 3.0 / 5.0),
    gamma_x=(0.5, -1.5, 121.0 / 50.0, 29.0 / 250.0),
    m=(19.0 / 9.0, 1.0 / 2.0, 25.0 / 108.0, 125.0 / 108.0),
    e=(17.0 / 54.0, 7.0 / 36.0, 0.0, 125.0 / 108.0),
    order=4,
    order_hat=3,
)


RODAS3 = RosenbrockTableau(
    # Sandu, Verwer, Blom, Spee, Carmichael & Potra (1997), "Benchmarking stiff ODE solvers for atmospheric
    # chemistry problems II: Rosenbrock solvers", Atmos. Environ. 31, 3459-3472: RODAS3, order 3 with an embedded
    # order-2 solution, L-stable (R(inf) = 0) and stiffly accurate (the solution is the last stage's input plus
    # its increment), so a stiff component is damped to its slow manifold in one step whatever h times its rate.
    # Stage 2 reuses stage 1's f (a_2j = 0, alpha_2 = 0).
    name="rodas3",
    gamma=0.5,
    a=_lower([[0.0], [2.0, 0.0], [2.0, 0.0, 1.0]], 4),
    c=_lower([[4.0], [1.0, -1.0], [1.0, -1.0, -8.0 / 3.0]], 4),
    alpha_x=(0.0, 0.0, 1.0, 1.0),
    gamma_x=(0.5, 1.5, 0.0, 0.0),
    m=(2.0, 0.0, 1.0, 1.0),
    e=(0.0, 0.0, 0.0, 1.0),
    order=3,
    order_hat=2,
)
