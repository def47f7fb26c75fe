"""Friction-parameter presets from Baumberger & Gauthier (1996), Table I (docs/physics.md section 5).

``presets`` is a read-only mapping name -> :class:`FrictionParams`; ``provenance`` says, per preset, where
the numbers come from, which figures of the paper use them and how uncertain they are. A name that is not a preset
raises a KeyError that lists the presets and the closest name (``presets["sampel2"]``: did you mean 'sample2'?).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator, Mapping

from .params import FrictionParams

__all__ = ["Presets", "presets", "provenance"]


class Presets(Mapping):
    """A read-only mapping name -> value (item assignment and deletion raise TypeError) whose KeyError for a missing
    name lists the names and suggests the closest (difflib)."""

    def __init__(self, items: Mapping, what: str = "preset"):
        self._items = dict(items)  # never handed out: read only through the Mapping methods
        self._what = what

    def __getitem__(self, name):
        try:
            return self._items[name]
        except (KeyError, TypeError):
            names = sorted(self._items)
            close = difflib.get_close_matches(str(name), names, n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise KeyError(f"no {self._what} {name!r}: the {self._what}s are {names}{hint}") from None

    def __iter__(self) -> Iterator:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, name) -> bool:
        try:
            return name in self._items
        except TypeError:
            return False

    def __repr__(self) -> str:
        return f"{type(self).__name__}({dict(self._items)!r})"

_SOURCE = ("T. Baumberger & L. Gauthier, J. Phys. I France 6 (1996) 1021, doi:10.1051/jp1:1996113, Table I. "
           "V0 = 1 um/s and g = 9.81 m/s^2 are our conventions.")
_CAVEAT = ("CAVEAT: the OCR of Table I is partly illegible. Trial values that also fit the text: sample1 "
           "A = 0.013, sample2 m1 = 0.013. Which m2 (0.0014 or 0.0033) belongs to which sample is our reading, "
           "not certain. The paper quotes ~20 % uncertainty on all values.")

presets: Presets = Presets({
    "sample1": FrictionParams(A=0.012, m1=0.010, m2=0.0014, D0=1.0e-6, V0=1e-6, m0=0.2, g=9.81),
    "sample2": FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6, V0=1e-6, m0=0.3, g=9.81),
})

provenance: Presets = Presets({
    "sample1": (
        f"{_SOURCE} Used in the paper for Fig. 3 (xi_inf vs K/M at V = 10 um/s; xi_inf vs V at "
        f"K/M = 7.4e4 s^-2, chi = 7.5e-3). {_CAVEAT} m2 = 0.0014 was chosen for sample1 because Fig. 3a draws "
        "eq. 10 at 10 um/s (needs mu1(10 um/s) > 0; m2 = 0.0033 gives mu1 < 0 above 4.5 um/s) and 0.0033 "
        "would put xi_inf ~ 6.4 at 100 um/s, off Fig. 3b's axis. Consequences: mu1(V) > 0, so eq. 10 exists, "
        "only below 35.7 um/s; at Fig. 3b's chi = 7.5e-3 steady sliding is unstable (stick-slip) below "
        "~2.4 um/s."
    ),
    "sample2": (
        f"{_SOURCE} Used in the paper for Figs. 2 and 4 (transients at K/M = 2.8e5 s^-2, V = 1 and 10 um/s; "
        f"Fig. 2: K = 1.1e5 N/m, M = 0.4 kg). {_CAVEAT} Consequence: mu1(V) = m1 - 2 m2 ln(V/V0) < 0 above "
        "6.6 um/s, i.e. no Hopf line and no eq. 10 over the top of the default V grid (0.1..100 um/s)."
    ),
})
