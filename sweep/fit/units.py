"""Units of measured data: the spellings a data file may use, and their factors to SI.

Two sets of tables: :data:`UNITS_OF` for relaxation curves and relaxed slips (exact spellings, sweep.fit.read), and
:data:`RECORD_UNITS` for laboratory records (sweep.fit.records), compared in lower case without blanks (``MPa``,
``µm``, ``um s-1`` and ``um/s`` are one unit there), with the spellings laboratory software writes (``sec``,
``mic``, ``micron``).
"""

from __future__ import annotations

from ..errors import InputError

__all__ = ["FORCE", "RECORD_UNITS", "STRESS", "UNITS_OF", "to_si"]

_LENGTH = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "micron": 1e-6, "nm": 1e-9}
_TIME = {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0}
_VELOCITY = {f"{ln}{sep}{tn}{tail}": lf / tf for ln, lf in _LENGTH.items() for tn, tf in _TIME.items()
             for sep, tail in (("/", ""), (" ", "-1"))}
_STIFFNESS = {"s-2": 1.0, "s^-2": 1.0, "1/s^2": 1.0, "1/s2": 1.0, "N/(m kg)": 1.0, "N m-1 kg-1": 1.0}
UNITS_OF = {"t": _TIME, "x": _LENGTH, "noise": _LENGTH, "dx_inf": _LENGTH, "V": _VELOCITY, "K_over_M": _STIFFNESS}
"""Accepted units per quantity (SI factor)."""

_REC_LENGTH = {**_LENGTH, "μm": 1e-6, "mic": 1e-6, "microns": 1e-6, "micrometer": 1e-6, "µ": 1e-6, "μ": 1e-6}
_REC_TIME = {**_TIME, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0, "msec": 1e-3, "hr": 3600.0}
STRESS = {"pa": 1.0, "kpa": 1e3, "mpa": 1e6, "gpa": 1e9, "bar": 1e5, "psi": 6894.757293168}
"""Stress units [Pa] (lower case)."""
FORCE = {"n": 1.0, "kn": 1e3, "lbf": 4.4482216152605, "kgf": 9.80665}
"""Force units [N] (lower case): shear and normal loads, whose ratio is the friction."""
RECORD_UNITS = {
    "time": {k.lower(): v for k, v in _REC_TIME.items()},
    "displacement": {k.lower(): v for k, v in _REC_LENGTH.items()},
    "velocity": {f"{ln.lower()}/{tn}": lf / tf for ln, lf in _REC_LENGTH.items() for tn, tf in _REC_TIME.items()},
    "mu": {"": 1.0, "-": 1.0, "1": 1.0, ".": 1.0, "none": 1.0, "-/-": 1.0},
    "shear": {**STRESS, **FORCE},
    "normal": {**STRESS, **FORCE},
}
"""Accepted units of a record's columns per role (SI factor; lower case, no blanks, ``s-1`` written ``/s``)."""


def to_si(where: str, quantity: str, unit: str | None) -> float:
    """Factor from ``unit`` to SI for ``quantity``, or InputError naming the file/field and the unit."""
    table = UNITS_OF[quantity]
    if unit is None or not str(unit).strip():
        raise InputError(f"{where}: {quantity} has no unit; give one of {sorted(table)[:6]}...")
    u = " ".join(str(unit).strip().split())
    if u not in table:
        raise InputError(f"{where}: unit {unit!r} of {quantity} is not understood; use one of {sorted(table)}")
    return table[u]
