"""Warnings for inputs that are valid numbers but physically implausible, most often a unit mistake, given before
any work; and for results where a point did not end well.

The model holds for any positive K/M and V, so these are warnings, not errors (:class:`sweep.errors.InputError`):
a table-top slider (the paper's experiment: M ~ 0.1-10 kg, K ~ 1e3-1e6 N/m) slides at V of nm/s to mm/s, and its
K/M lies far inside 1e-2..1e12 s^-2. Above V = 1 cm/s the creep the model describes is negligible and the inertial
stop needs tiny steps (points end with status step_underflow or max_steps); the usual cause is V given in µm/s.
"""

from __future__ import annotations

import warnings

import numpy as np

__all__ = ["K_OVER_M_RANGE", "NOT_FAILED", "PlausibilityWarning", "V_MAX", "implausible", "not_ok_summary",
           "warn_implausible", "warn_not_ok"]

V_MAX = 1e-2
"""Largest plausible driving velocity [m s-1] (1 cm/s)."""
K_OVER_M_RANGE = (1e-2, 1e12)
"""Plausible stiffness over mass of a table-top slider [s-2]."""


class PlausibilityWarning(UserWarning):
    """An input far outside the physically meaningful range (likely a unit mistake), or a result that failed."""


def implausible(K_over_M: np.ndarray | None = None, V: np.ndarray | None = None) -> list[str]:
    """One message per axis far outside the plausible range (:data:`V_MAX`, :data:`K_OVER_M_RANGE`), naming the
    likely unit mistake; empty if both are plausible. ``K_over_M`` [s-2], ``V`` [m s-1]."""
    messages = []
    if V is not None and np.size(V) and float(np.max(V)) > V_MAX:
        top = float(np.max(V))
        guess = ("did you give µm/s? " if top * 1e-6 <= V_MAX else "") + "V is in m/s"
        messages.append(f"V up to {top:g} m/s: {guess} (a table-top slider creeps at V <= {V_MAX:g} m/s; "
                        f"1 µm/s = 1e-6 m/s)")
    if K_over_M is not None and np.size(K_over_M):
        lo, hi = float(np.min(K_over_M)), float(np.max(K_over_M))
        if lo < K_OVER_M_RANGE[0] or hi > K_OVER_M_RANGE[1]:
            messages.append(f"K/M {lo:g}..{hi:g} s^-2 is outside {K_OVER_M_RANGE[0]:g}..{K_OVER_M_RANGE[1]:g} "
                            "s^-2 of a table-top slider: K_over_M is K [N/m] divided by M [kg] (did you give K "
                            "alone, or M in g?)")
    return messages


def warn_implausible(K_over_M: np.ndarray | None = None, V: np.ndarray | None = None) -> list[str]:
    """Issue a :class:`PlausibilityWarning` for each message of :func:`implausible` not issued before in this
    process (a scene checked by the CLI, then by run_sweep and by its Hopf line, warns once); returns the
    messages."""
    messages = implausible(K_over_M, V)
    for text in messages:
        if text not in _ISSUED:
            _ISSUED.add(text)
            warnings.warn(text, PlausibilityWarning, stacklevel=3)
    return messages


_ISSUED: set[str] = set()


NOT_FAILED = ("ok", "no_finite_limit")
"""Statuses that are answers, not failures: no_finite_limit is the model's (no finite relaxed slip there)."""


def not_ok_summary(status: np.ndarray, meanings: list[str], failed_only: bool = False) -> tuple[int, str]:
    """(number of points whose status is not ok, "name count, ..." of those statuses); ``failed_only``: leave out
    the statuses of :data:`NOT_FAILED` (the computation did not fail there)."""
    status = np.asarray(status).reshape(-1)
    skip = [meanings.index(name) for name in (NOT_FAILED if failed_only else NOT_FAILED[:1]) if name in meanings]
    codes, counts = np.unique(status[~np.isin(status, skip)], return_counts=True)
    return int(counts.sum()), ", ".join(f"{meanings[c]} {n}" for c, n in zip(codes, counts))


def warn_not_ok(ds, where: str) -> None:
    """A :class:`PlausibilityWarning` if any point of ``ds`` (a sweep or a point) ended with a status other than
    ok, saying which statuses (``where``: what was run, for the message)."""
    meanings = ds["status"].attrs["flag_meanings"].split()
    bad, text = not_ok_summary(ds["status"].values, meanings)
    if bad and ds["status"].size == 1:
        text = f"ended with status {meanings[int(ds['status'])]}"
    elif bad:
        text = f"{bad} of {ds['status'].size} points did not end ok: {text}"
    if bad:
        warnings.warn(f"{where} {text} (its values are NaN or not accurate to rtol; see sweep.Status)",
                      PlausibilityWarning, stacklevel=3)
