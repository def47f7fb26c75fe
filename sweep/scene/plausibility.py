"""Warnings for inputs that are valid numbers but physically implausible, most often a unit mistake, given before
any work; and for results where a point did not end well.

The model holds for any positive K/M and V, so these are warnings, not errors (:class:`sweep.errors.InputError`):
a table-top slider (the paper's experiment: M ~ 0.1-10 kg, K ~ 1e3-1e6 N/m) slides at V of nm/s to mm/s, and its
K/M lies far inside 1e-2..1e12 s^-2. Above V = 1 cm/s the creep the model describes is negligible and the inertial
stop needs tiny steps (points end with status step_underflow or max_steps); the usual cause is V given in µm/s.

The friction parameters and slips likewise (:func:`implausible_params`, :func:`implausible_slips`): measured memory
lengths D0 lie within 1e-8..1e-3 m (:data:`D0_RANGE`; typically 0.1-10 µm), direct-effect coefficients A within
1e-4..0.1 (:data:`A_RANGE`; the paper's 0.007-0.012), the slopes |m1|, |m2| below 0.5 (:data:`SLOPE_MAX`), and the
slips after a stop (x, Dx_inf: a few D0) below 1 mm (:data:`SLIP_MAX`). A scene calls
:func:`warn_implausible_params` with its parameters and its extra axes, a fit (sweep.fit.checks) checks its start,
bounds and data; each gives ONE warning per call, however many samples or axes it names.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping

import numpy as np

__all__ = ["A_RANGE", "D0_RANGE", "K_OVER_M_RANGE", "NOT_FAILED", "PlausibilityWarning", "SLIP_MAX", "SLOPE_MAX",
           "V_MAX", "implausible", "implausible_lab_axes", "implausible_params", "implausible_slips", "not_ok_summary",
           "warn_implausible", "warn_implausible_params", "warn_not_ok"]

V_MAX = 1e-2
"""Largest plausible driving velocity [m s-1] (1 cm/s)."""
K_OVER_M_RANGE = (1e-2, 1e12)
"""Plausible stiffness over mass of a table-top slider [s-2]."""
D0_RANGE = (1e-8, 1e-3)
"""Plausible memory length D0 [m] (measured: ~0.1-10 µm)."""
A_RANGE = (1e-4, 0.1)
"""Plausible direct-effect coefficient A [1] (measured: ~1e-3..5e-2)."""
SLOPE_MAX = 0.5
"""Largest plausible |m1| and |m2| [1] (measured: ~1e-3..5e-2)."""
SLIP_MAX = 1e-3
"""Largest plausible slip after a stop, x(t) or Dx_inf [m] (a few D0: ~0.1-100 µm)."""


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


def _span(values) -> tuple[float, float] | None:
    v = np.asarray(values, dtype=float).reshape(-1)
    v = v[np.isfinite(v)]
    return (float(v.min()), float(v.max())) if v.size else None


def implausible_params(A=None, m1=None, m2=None, D0=None, *, names: Mapping[str, str] | None = None) -> list[str]:
    """One message per friction parameter with a value outside its plausible range (:data:`A_RANGE`,
    :data:`SLOPE_MAX`, :data:`D0_RANGE`), naming the field and the likely unit mistake; empty if all are plausible.
    Each argument: a value or values (a scene's parameter and its axis, a fit's start and bounds); None: not
    checked. ``A``, ``m1``, ``m2`` [1], ``D0`` [m]. ``names``: the spelling the user gave a parameter in, where it
    differs (the laboratory's {"A": "a", "D0": "Dc"}: a = A, Dc = D0), used in the messages."""
    shown = {"A": "A", "D0": "D0", **dict(names or {})}
    messages = []
    span = _span(D0) if D0 is not None else None
    if span and (span[0] < D0_RANGE[0] or span[1] > D0_RANGE[1]):
        lo, hi = span
        n = shown["D0"]
        guess = (f"did you give µm? {n} is in m, 1 µm = 1e-6 m" if hi > D0_RANGE[1] else
                 f"did you convert to m twice? {n} is in m, 1 µm = 1e-6 m")
        messages.append(f"{n} {_range_text(lo, hi)} m is outside {D0_RANGE[0]:g}..{D0_RANGE[1]:g} m of measured "
                        f"memory lengths (~0.1-10 µm): {guess}")
    span = _span(A) if A is not None else None
    if span and (span[0] < A_RANGE[0] or span[1] > A_RANGE[1]):
        lo, hi = span
        n = shown["A"]
        guess = (f"did you give it in percent, or give mu0 instead? {n} is a number, e.g. 0.01" if hi > A_RANGE[1]
                 else f"did you divide it by 100 twice? {n} is a number, e.g. 0.01")
        messages.append(f"{n} {_range_text(lo, hi)} is outside {A_RANGE[0]:g}..{A_RANGE[1]:g} of measured "
                        f"direct-effect coefficients (~1e-3..5e-2): {guess}")
    for name, values in (("m1", m1), ("m2", m2)):
        span = _span(values) if values is not None else None
        if span and max(abs(span[0]), abs(span[1])) > SLOPE_MAX:
            messages.append(f"{name} {_range_text(*span)}: |{name}| above {SLOPE_MAX:g} (measured ~1e-3..5e-2: the "
                            f"change of the dynamic friction per e-fold of V): did you give it in percent? {name} is "
                            f"a number, e.g. 0.01")
    return messages


def implausible_slips(field: str, values) -> list[str]:
    """A message if the slips ``values`` [m] (``field``: "x" or "dx_inf") exceed :data:`SLIP_MAX` (a unit
    mistake: µm given as m, most often); empty otherwise."""
    span = _span(np.abs(np.asarray(values, dtype=float)))
    if span is None or span[1] <= SLIP_MAX:
        return []
    return [f"{field} up to {span[1]:.3g} m is above {SLIP_MAX:g} m (a slip after a stop is a few D0, ~0.1-100 µm): "
            f"did you give µm? {field} is in m, 1 µm = 1e-6 m"]


def implausible_lab_axes(axes: Mapping[str, object] | None, g: float = 9.81) -> list[str]:
    """Messages for a scene's axes in the laboratory's parameters (docs/physics.md 7b) outside their plausible
    ranges, named as given: ``a`` as A and ``Dc`` [m] as D0 (:data:`A_RANGE`, :data:`D0_RANGE`), ``b`` [1] within
    :data:`SLOPE_MAX`, ``k`` [1/m] through K/M = k g [s-2] within :data:`K_OVER_M_RANGE`; empty if all are
    plausible or none is an axis."""
    axes = {n: v for n, v in dict(axes or {}).items() if v is not None}
    messages = implausible_params(A=axes.get("a"), D0=axes.get("Dc"), names={"A": "a", "D0": "Dc"})
    span = _span(axes["b"]) if "b" in axes else None
    if span and max(abs(span[0]), abs(span[1])) > SLOPE_MAX:
        messages.append(f"b {_range_text(*span)}: |b| above {SLOPE_MAX:g} (measured ~1e-3..5e-2: the evolution "
                        f"effect per e-fold of V): did you give it in percent? b is a number, e.g. 0.015")
    span = _span(axes["k"]) if "k" in axes else None
    if span and (span[0] * g < K_OVER_M_RANGE[0] or span[1] * g > K_OVER_M_RANGE[1]):
        messages.append(f"k {_range_text(*span)} 1/m (K/M = k g = {_range_text(span[0] * g, span[1] * g)} s^-2) is "
                        f"outside {K_OVER_M_RANGE[0] / g:.3g}..{K_OVER_M_RANGE[1] / g:.3g} 1/m of a table-top slider: "
                        "k is friction per metre of load-point displacement (K / (M g), 1/m): did you give it per "
                        "µm, or K in N/m?")
    return messages


def _range_text(lo: float, hi: float) -> str:
    return f"= {lo:g}" if lo == hi else f"{lo:g}..{hi:g}"


def warn_implausible_params(params, axes=None) -> list[str]:
    """ONE :class:`PlausibilityWarning` (once per process for the same text, as :func:`warn_implausible`) for the
    friction parameters of a scene that lie outside their plausible ranges (:func:`implausible_params`): ``params`` a
    :class:`sweep.FrictionParams` (or anything with attributes A, m1, m2, D0), ``axes`` the scene's extra axes
    {name: values} (those named A, m1, m2 or D0 are checked with their values, the laboratory's a, b, Dc, k by
    :func:`implausible_lab_axes`; the others are ignored). Returns the messages (empty: all plausible)."""
    axes = dict(axes or {})
    values = {}
    for name in ("A", "m1", "m2", "D0"):
        v = [float(getattr(params, name))] if params is not None and hasattr(params, name) else []
        if name in axes and axes[name] is not None:
            v += np.asarray(axes[name], dtype=float).reshape(-1).tolist()
        values[name] = v or None
    messages = implausible_params(**values) + implausible_lab_axes(axes, getattr(params, "g", 9.81))
    if messages:
        text = "; ".join(messages)
        if text not in _ISSUED:
            _ISSUED.add(text)
            warnings.warn(text, PlausibilityWarning, stacklevel=2)
    return messages


NOT_FAILED = ("ok", "no_finite_limit")
"""Statuses that are answers, not failures: no_finite_limit is the model's (no finite relaxed slip there)."""


def not_ok_summary(status: np.ndarray | Mapping[int, int], meanings: list[str], failed_only: bool = False
                   ) -> tuple[int, str]:
    """(number of points whose status is not ok, "name count, ..." of those statuses), from the status codes or their
    counts (code -> points); ``failed_only``: leave out the statuses of :data:`NOT_FAILED` (the computation did not
    fail there)."""
    if not isinstance(status, Mapping):
        codes, n = np.unique(np.asarray(status).reshape(-1), return_counts=True)
        status = dict(zip(codes.tolist(), n.tolist()))
    skip = [meanings.index(name) for name in (NOT_FAILED if failed_only else NOT_FAILED[:1]) if name in meanings]
    bad = {code: n for code, n in sorted(status.items()) if code not in skip and n}
    return sum(bad.values()), ", ".join(f"{meanings[c]} {n}" for c, n in bad.items())


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
