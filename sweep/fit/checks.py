"""Checks of a fit's data against its parameter space, before any work.

* A stop needs steady sliding before it: chi > mu1(V) (quasi-static Hopf line, eq. 3). chi - mu1 =
  f (K/M) D0/g - m1 + 2 m2 ln(V/V0) is monotonic in each parameter (f the K/M factor), so its largest value over
  the bound box lies at a corner: a data set whose (K/M, V) is on the stick-slip side at every corner cannot be
  fitted by any parameter set inside the bounds.
* The fit uses the quasi-static model: inertia changes the relaxed slip by about gamma/A (docs/physics.md 3a,
  gamma = V^2/(g D0)); where gamma/A exceeds INERTIA_TOL at the starting values a PlausibilityWarning says so.
* Likely unit mistakes (sweep.scene.plausibility): starting or fixed values of A, m1, m2, D0 outside their plausible
  ranges, slips x or Dx_inf above 1 mm (µm given as m: a fit of such data ran 524 s into a bound).

Every such warning of a call is ONE PlausibilityWarning, whatever the number of samples: its messages joined, each
naming the samples it concerns.
"""

from __future__ import annotations

import warnings

import numpy as np

from .. import physics
from ..errors import InputError
from ..scene.plausibility import PlausibilityWarning, implausible_params, implausible_slips
from .data import Curve
from .problem import Problem
from .verdict import user_stacklevel

__all__ = ["INERTIA_TOL", "check_problems", "plausibility_messages"]

INERTIA_TOL = 1e-2


def _samples(names: list[str]) -> str:
    names = list(dict.fromkeys(names))
    return ("sample " if len(names) == 1 else "samples ") + ", ".join(names[:10]) + \
        (f" and {len(names) - 10} more" if len(names) > 10 else "")


def plausibility_messages(problems: list[Problem]) -> list[str]:
    """The messages of the fit's plausibility checks (module docstring), each naming the samples it concerns."""
    sp = problems[0].space
    messages = [f"{m} (start or fixed value)" for m in
                implausible_params(**{n: [sp.values[n]] for n in ("A", "m1", "m2", "D0")})]
    slips: dict[str, tuple[list[str], float]] = {}
    inertia: tuple[list[str], float, float] = ([], 0.0, 0.0)
    for pr in problems:
        for d in pr.data:
            field = "x" if isinstance(d, Curve) else "dx_inf"
            values = d.x if isinstance(d, Curve) else d.dx_inf
            if implausible_slips(field, values):
                names, top = slips.get(field, ([], 0.0))
                slips[field] = (names + [pr.name], max(top, float(np.max(np.abs(values)))))
            v = np.atleast_1d(d.V)
            gamma_over_A = float(np.max(physics.inertia_number(v, sp.values["D0"], sp.g))) / sp.values["A"]
            if gamma_over_A > INERTIA_TOL:
                inertia = (inertia[0] + [pr.name], max(inertia[1], gamma_over_A), max(inertia[2], float(v.max())))
    for field, (names, top) in slips.items():
        messages += [f"{m} ({_samples(names)})" for m in implausible_slips(field, [top])]
    if inertia[0]:
        messages.append(f"gamma/A up to {inertia[1]:.3g} at the starting values (V up to {inertia[2]:g} m/s; "
                        f"{_samples(inertia[0])}): the fit's quasi-static model may be off by about that much")
    return messages


def check_problems(problems: list[Problem]) -> None:
    """InputError naming the data set, K/M and V of a stop that is on the stick-slip side of the Hopf line for every
    parameter set inside the bounds; ONE PlausibilityWarning for everything implausible (:func:`plausibility_messages`:
    likely unit mistakes, inertia that may matter), given first."""
    messages = plausibility_messages(problems)
    if messages:
        warnings.warn("; ".join(messages), PlausibilityWarning, stacklevel=user_stacklevel())
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
