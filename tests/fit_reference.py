"""Synthetic data for the fit tests, made by the independent scipy reference (tests/reference.py), never by the
engine; and the Fisher information of noiseless data, by central differences of the reference.

No import from the ``sweep`` package here: this module is what the fit is tested against.

A stop at V on a spring K/M with parameters (A, m1, m2, D0) has (docs/physics.md 2, paper section 4)

    chi = (K/M) D0/g,   mu1 = m1 - 2 m2 ln(V/V0),   x(t) = D0 xi(tau = V t/D0),   Dx_inf = D0 xi_inf.
"""

from __future__ import annotations

import math

import numpy as np
from reference import reference_stop

G, V0 = 9.81, 1e-6
FD_REL = 1e-4
"""Relative step of the reference's central differences (its error ~1e-13/1e-4 = 1e-9 relative)."""


def _solution(A, m1, m2, D0, K_over_M, V):
    chi = K_over_M * D0 / G
    mu1 = m1 - 2.0 * m2 * math.log(V / V0)
    return reference_stop(chi, A, mu1, m2)


def slip_curve(params: dict, K_over_M: float, V: float, t: np.ndarray) -> np.ndarray:
    """x(t) [m] after a stop from V [m s-1] at K/M [s-2], t [s]; params: A, m1, m2, D0."""
    ref = _solution(params["A"], params["m1"], params["m2"], params["D0"], K_over_M, V)
    return params["D0"] * np.asarray(ref.xi(V * np.asarray(t) / params["D0"]))


def relaxed_slip(params: dict, K_over_M: float, V: float) -> float:
    """Dx_inf [m] (the reference's limit)."""
    ref = _solution(params["A"], params["m1"], params["m2"], params["D0"], K_over_M, V)
    return params["D0"] * ref.xi_inf


def fisher_widths(model, params: dict, free: tuple[str, ...], noise: np.ndarray, level_z: float = 1.959964
                  ) -> np.ndarray:
    """Width 2 z sqrt((F^-1)_jj) of the 95 % interval of each free parameter from the Fisher information
    F = J^T J of the noiseless data, J_ij = d model_i/d theta_j / noise_i (central differences of ``model(params)``,
    a function returning the data vector [m])."""
    cols = []
    for name in free:
        h = FD_REL * abs(params[name])
        up, down = dict(params), dict(params)
        up[name] += h
        down[name] -= h
        cols.append((model(up) - model(down)) / (2.0 * h) / noise)
    J = np.array(cols).T
    return 2.0 * level_z * np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
