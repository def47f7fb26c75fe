"""Checks of a fit's data against its parameter space, before any work.

* A stop needs steady sliding before it: chi > mu1(V) (quasi-static Hopf line, eq. 3). chi - mu1 =
  f (K/M) D0/g - m1 + 2 m2 ln(V/V0) is monotonic in each parameter (f the K/M factor), so its largest value over
  the bound box lies at a corner: a data set whose (K/M, V) is on the stick-slip side at every corner cannot be
  fitted by any parameter set inside the bounds.
* The fit uses the quasi-static model: inertia changes the relaxed slip by about gamma/A (docs/physics.md 3a,
  gamma = V^2/(g D0)); where gamma/A exceeds INERTIA_TOL at the starting values a PlausibilityWarning says so.
"""

from __future__ import annotations

import warnings

import numpy as np

from .. import physics
from ..errors import InputError
from ..scene.plausibility import PlausibilityWarning
from .data import Curve
from .problem import Problem

__all__ = ["INERTIA_TOL", "check_problems"]

INERTIA_TOL = 1e-2


def check_problems(problems: list[Problem]) -> None:
    """InputError naming the data set, K/M and V of a stop that is on the stick-slip side of the Hopf line for every
    parameter set inside the bounds; PlausibilityWarning where inertia may matter."""
    for pr in problems:
        sp = pr.space
        full = sp.full(sp.corners())
        for d in pr.data:
            km, v = np.atleast_1d(d.K_over_M), np.atleast_1d(d.V)
            chi = full["K_over_M_factor"][:, None] * km[None, :] * full["D0"][:, None] / sp.g
            mu1 = physics.mu1(v[None, :], full["m1"][:, None], full["m2"][:, None], sp.V0)
            never = np.flatnonzero(np.max(chi - mu1, axis=0) <= 0)
            what = f"curve {d.name!r}" if isinstance(d, Curve) else f"relaxed slips {d.name!r}"
            if never.size:
                i = int(never[0])
                raise InputError(f"{what}: K_over_M = {km[i]:g} s-2, V = {v[i]:g} m/s lies on the stick-slip side of "
                                 f"the Hopf line (chi <= mu1, eq. 3) for every parameter set inside the bounds: no "
                                 f"steady sliding before the stop; check K_over_M and V, or widen the bounds")
            gamma_over_A = float(np.max(physics.inertia_number(v, sp.values["D0"], sp.g))) / sp.values["A"]
            if gamma_over_A > INERTIA_TOL:
                warnings.warn(f"{what}: gamma/A = {gamma_over_A:.3g} at the starting values (V up to {v.max():g} "
                              f"m/s): the fit's quasi-static model may be off by about that much",
                              PlausibilityWarning, stacklevel=3)
