"""Per-point status codes: one fixed, append-only integer enum shared by every kernel and file.

A kernel never raises; each point gets one of these codes and the sweep goes on. Physical labels are not
statuses: a stop computed from unstable steady sliding is flagged by the ``stable`` variable, not here.
Never renumber or remove a code (files on disk depend on the values); append new ones at the end.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import IntEnum

import numpy as np

__all__ = ["Status", "flag_attrs"]


class Status(IntEnum):
    OK = 0
    """Converged within the plan's accuracy."""
    MAX_STEPS = 1
    """The step budget ran out before the stopping criterion (or the requested times) was reached."""
    STEP_UNDERFLOW = 2
    """An adaptive stepper's step fell below its floor (H_FLOOR of integrate/stop_point.py)."""
    NONFINITE = 3
    """A state or exponent left the finite range (caught before the overflow happened)."""
    NO_FINITE_LIMIT = 4
    """The model has no finite relaxed slip here (m2 < 0, or m2 = 0 with mu1 <= 0; docs/physics.md 6):
    xi_inf, slip_inf, stress_relaxation, t50 and t90 are NaN by definition; finite-time observables
    (slip_at, trajectory) are still computed."""
    ERROR_ABOVE_TOL = 5
    """Computed, but the error estimate of at least one observable (``<name>_error``) exceeds rtol abs(value) +
    atol: the value is kept for inspection and must not be trusted to rtol."""
    QUASISTATIC_BREAKDOWN = 6
    """Driven scene: the slip velocity passed the threshold in the file's attrs (regime runaway): the quasi-static
    model no longer describes the point (inertia is needed). History scene and friction_at: the quasi-static run
    ran away (slip velocity past 1e8 V) where no inertial model reran it (model "quasistatic", slip law), or the
    slip law where some segment needs inertia."""
    MODEL_ERROR_ABOVE_TOL = 7
    """Stop scene with model="auto" and time-resolved observables: the quasi-static model's estimated error
    (``model_error``) exceeds model_tol, and the inertial model computes the relaxed slip only: the quasi-static
    values are kept for inspection (ask for observables = ["xi_inf"] to get the inertial result)."""


def flag_attrs() -> dict[str, object]:
    """CF ``flag_values``/``flag_meanings`` attributes describing :class:`Status`."""
    return {
        "flag_values": np.array([s.value for s in Status], dtype=np.int8),
        "flag_meanings": " ".join(s.name.lower() for s in Status),
    }


MODEL_FLAG = {"flag_values": np.array([0, 1], np.int8), "flag_meanings": "quasistatic inertial"}
"""CF flag attributes of the per-point ``model`` variable (0: the quasi-static model, 1: the inertial one)."""


def flag_summary(ds, name: str, counts: Mapping[str, Mapping[int, int]] | None = None) -> str:
    """"name: meaning count, ..." of the flag variable ``name`` of a Dataset: counted in it, or taken from
    ``counts`` (name -> flag value -> points: a run's totals, sweep.write.regions.RunTotals.counts)."""
    attrs = ds[name].attrs
    meanings = dict(zip(np.asarray(attrs["flag_values"]).tolist(), attrs["flag_meanings"].split()))
    if counts is None:
        codes, n = np.unique(ds[name].values, return_counts=True)
        found = dict(zip(codes.tolist(), n.tolist()))
    else:
        found = counts.get(name, {})
    return f"{name}: " + ", ".join(f"{meanings.get(c, c)} {found[c]}" for c in sorted(found) if found[c])
