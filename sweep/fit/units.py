"""Units of measured data: the spellings a data file may use, and their factors to SI."""

from __future__ import annotations

from ..errors import InputError

__all__ = ["UNITS_OF", "to_si"]

_LENGTH = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "micron": 1e-6, "nm": 1e-9}
_TIME = {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0}
_VELOCITY = {f"{ln}{sep}{tn}{tail}": lf / tf for ln, lf in _LENGTH.items() for tn, tf in _TIME.items()
             for sep, tail in (("/", ""), (" ", "-1"))}
_STIFFNESS = {"s-2": 1.0, "s^-2": 1.0, "1/s^2": 1.0, "1/s2": 1.0, "N/(m kg)": 1.0, "N m-1 kg-1": 1.0}
UNITS_OF = {"t": _TIME, "x": _LENGTH, "noise": _LENGTH, "dx_inf": _LENGTH, "V": _VELOCITY, "K_over_M": _STIFFNESS}
"""Accepted units per quantity (SI factor)."""


def to_si(where: str, quantity: str, unit: str | None) -> float:
    """Factor from ``unit`` to SI for ``quantity``, or InputError naming the file/field and the unit."""
    table = UNITS_OF[quantity]
    if unit is None or not str(unit).strip():
        raise InputError(f"{where}: {quantity} has no unit; give one of {sorted(table)[:6]}...")
    u = " ".join(str(unit).strip().split())
    if u not in table:
        raise InputError(f"{where}: unit {unit!r} of {quantity} is not understood; use one of {sorted(table)}")
    return table[u]
