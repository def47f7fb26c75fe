"""Laboratory friction records: the :class:`Record` data kind and its reader :func:`read_record`.

A record is friction mu(t) [1] sampled at times t [s] while the load point is driven through a history of velocity
steps and holds (docs/fit.md, "Laboratory records"). The history is given as a list of (start time [s], load-point
velocity [m s-1]), or found from the record's load-point displacement or velocity (sweep.fit.segments). The model
starts from steady sliding at the first segment's velocity at the record's first time.

The reader takes text files as laboratories write them: columns separated by commas, semicolons, tabs or blanks
(trailing delimiters ignored); comment lines starting with ``#`` or ``%`` (``# k = 2e3 1/m`` there sets the
stiffness); a header naming the columns with their units in brackets or parentheses (``Time (s)``, ``mu [-]``) or
in a units row below the names; latin-1 files (µm); irregular sample times. Columns it knows by name (case, blanks
and units aside; ``columns={"time": "Zeit"}`` names others):

* time [s, ms, min];
* load-point displacement [m, mm, um, nm] or load-point velocity [m/s, mm/s, um/s];
* friction mu [1], or shear and normal stress [Pa, kPa, MPa] (mu = tau/sigma).

Anything else it refuses in one line naming the column and what was found.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

__all__ = ["ROLES", "Record", "is_record_file", "read_record"]

ROLES = ("time", "displacement", "velocity", "mu", "shear", "normal")
"""The columns a record may have (``columns`` maps these to the file's names)."""

_ALIASES = {
    "time": ("t", "time", "times", "elapsed_time", "time_s"),
    "displacement": ("lp_disp", "lpdisp", "load_point_displacement", "displacement", "lp_displacement", "x_lp",
                     "disp", "load_point", "lpd", "d_lp"),
    "velocity": ("v_lp", "lp_velocity", "load_point_velocity", "velocity", "vlp", "v"),
    "mu": ("mu", "µ", "μ", "friction", "friction_coefficient", "coefficient_of_friction", "cof", "mu_f"),
    "shear": ("tau", "shear", "shear_stress", "tau_s"),
    "normal": ("sigma", "normal", "normal_stress", "sigma_n", "sn"),
}
_PART = {"time": "time", "displacement": "disp", "velocity": "veloc", "mu": "fric", "shear": "shear",
         "normal": "normal"}
"""A part of a name that tells its role where no alias matches exactly ('Load point disp.', 'Friction coef.')."""
_UNITS = {
    "time": {"s": 1.0, "sec": 1.0, "ms": 1e-3, "min": 60.0},
    "displacement": {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "μm": 1e-6, "micron": 1e-6, "nm": 1e-9},
    "velocity": {"m/s": 1.0, "mm/s": 1e-3, "um/s": 1e-6, "µm/s": 1e-6, "μm/s": 1e-6, "nm/s": 1e-9},
    "mu": {"": 1.0, "-": 1.0, "1": 1.0},
    "shear": {"pa": 1.0, "kpa": 1e3, "mpa": 1e6},
    "normal": {"pa": 1.0, "kpa": 1e3, "mpa": 1e6},
}
_STIFFNESS = {"1/m": 1.0, "m-1": 1.0, "1/mm": 1e3, "mm-1": 1e3, "1/um": 1e6, "um-1": 1e6, "1/µm": 1e6}
_UNIT_IN_NAME = re.compile(r"^(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$")


def _key(name: str) -> str:
    """A column name compared to the aliases: lower case, blanks and punctuation as single underscores."""
    return re.sub(r"[^0-9a-zµμ/]+", "_", name.strip().lower()).strip("_")


def _unit_key(unit: str) -> str:
    """A unit compared to the tables: lower case, no blanks, s-1 and s^-1 as /s."""
    return unit.strip().replace(" ", "").replace("s^-1", "/s").replace("s-1", "/s").lower()


@dataclass(frozen=True, eq=False)
class Record:
    """A laboratory record (module docstring), SI units: ``t`` [s] strictly increasing, ``mu`` [1] (finite);
    ``displacement`` [m] or ``velocity`` [m s-1] of the load point per sample (either, or None where ``steps`` is
    given); ``steps``: the history as ((start time [s], velocity [m s-1]), ...) from the first time on, or None
    (found from the displacement, sweep.fit.segments); ``k`` [1/m] the stiffness k = K/(M g) (None: from the fit's
    parameters); ``noise`` [1] per sample, one number, or None (estimated); ``sample`` and ``name`` as for a Curve;
    ``detrend`` "time" or "displacement": the model carries a linear trend c (t - t[0]) or c (x - x[0]) of its own
    slope c [1/s or 1/m] per record, the one that fits best at each parameter set (projected out, not reported)."""

    t: np.ndarray
    mu: np.ndarray
    displacement: np.ndarray | None = None
    velocity: np.ndarray | None = None
    steps: tuple[tuple[float, float], ...] | None = None
    k: float | None = None
    noise: np.ndarray | None = None
    sample: str = "sample"
    name: str = "record"
    detrend: str | None = None

    def __post_init__(self) -> None:
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 (frozen)
        where = f"record {self.name!r}"
        if self.detrend not in (None, "time", "displacement"):
            raise InputError(f"{where}: detrend must be None, 'time' or 'displacement', got {self.detrend!r}")
        if self.detrend == "displacement" and self.displacement is None:
            raise InputError(f"{where}: detrend='displacement' needs the load-point displacement column")
        t = _column(where, "time", self.t)
        step = np.flatnonzero(np.diff(t) <= 0)
        if step.size:
            i = int(step[0]) + 1
            raise InputError(f"{where}: column time must be strictly increasing [s], but row {i} (t = {t[i]!r}) "
                             f"follows row {i - 1} (t = {t[i - 1]!r})")
        if t.size < 10:
            raise InputError(f"{where}: column time has {t.size} samples; a record needs at least 10")
        set_("t", t)
        set_("mu", _column(where, "mu", self.mu, t.size))
        for field in ("displacement", "velocity"):
            if getattr(self, field) is not None:
                set_(field, _column(where, field, getattr(self, field), t.size))
        if self.steps is None and self.displacement is None and self.velocity is None:
            raise InputError(f"{where}: no load-point displacement or velocity column and no steps; give one")
        if self.steps is not None:
            set_("steps", _steps(where, self.steps, t))
        if self.k is not None:
            k = float(self.k)
            if not (np.isfinite(k) and k > 0):
                raise InputError(f"{where}: k must be > 0 [1/m] (k = K/(M g)), got {self.k!r}")
            set_("k", k)
        if self.noise is not None:
            noise = np.broadcast_to(np.asarray(self.noise, dtype=float), t.shape).copy()
            if not np.all(np.isfinite(noise) & (noise > 0)):
                raise InputError(f"{where}: noise must be > 0 and finite (one number or one per sample)")
            set_("noise", noise)
        set_("sample", str(self.sample))

    @property
    def n(self) -> int:
        return self.t.size


def _column(where: str, role: str, values, n: int | None = None) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"{where}: column {role} must be numbers") from None
    if n is not None and arr.size != n:
        raise InputError(f"{where}: column {role} has {arr.size} values, time has {n}")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        rows = ", ".join(str(i) for i in bad[:5]) + (f" and {bad.size - 5} more" if bad.size > 5 else "")
        raise InputError(f"{where}: column {role} has {bad.size} NaN or infinite value(s) (rows {rows}); remove "
                         f"those rows")
    return arr


def _steps(where: str, steps, t: np.ndarray) -> tuple[tuple[float, float], ...]:
    try:
        arr = np.asarray(steps, dtype=float).reshape(-1, 2)
    except (TypeError, ValueError):
        raise InputError(f"{where}: steps must be a list of (time [s], velocity [m/s]), got {steps!r}") from None
    if arr.shape[0] == 0 or not np.all(np.isfinite(arr)):
        raise InputError(f"{where}: steps must be a non-empty list of finite (time [s], velocity [m/s])")
    if np.any(np.diff(arr[:, 0]) <= 0):
        raise InputError(f"{where}: steps' times must be strictly increasing, got {arr[:, 0].tolist()}")
    outside = np.flatnonzero((arr[1:, 0] <= t[0]) | (arr[1:, 0] >= t[-1])) + 1
    if outside.size:
        i = int(outside[0])
        raise InputError(f"{where}: step {i} at t = {arr[i, 0]:g} s is not in the data (time runs from {t[0]:g} to "
                         f"{t[-1]:g} s)")
    if np.any(arr[:, 1] < 0) or arr[0, 1] <= 0:
        raise InputError(f"{where}: steps' velocities must be >= 0 [m/s] and the first > 0 (the record starts in "
                         f"steady sliding), got {arr[:, 1].tolist()}")
    arr[0, 0] = t[0]
    return tuple((float(a), float(b)) for a, b in arr)


# --- the reader -------------------------------------------------------------------------------------------------

def _lines(path: Path) -> list[str]:
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        text = path.read_text(encoding="latin-1")  # a lab PC's export (µ as one byte)
    return text.splitlines()


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:  # blanks: a name followed by its unit in brackets stays one field
        fields = re.findall(r"[^\s\[(]+(?:\s*[\[(][^\])]*[\])])?|[\[(][^\])]*[\])]", line)
    else:
        fields = [f.strip() for f in line.split(delimiter)]
    while fields and fields[-1] == "":  # a trailing delimiter
        fields.pop()
    return fields


def _numeric(fields: list[str]) -> bool:
    try:
        [float(f.replace(",", ".")) if f.count(",") == 1 and "." not in f else float(f) for f in fields]
    except ValueError:
        return False
    return bool(fields)


def _is_unit(text: str) -> bool:
    u = _unit_key(text.strip("[]() "))
    return any(u in table for table in _UNITS.values()) or text.strip() in ("", "-")


def _parse(lines: list[str], where: str):
    """(names, units per name (None: none), data rows (n, ncol), meta {key: (value, unit)})."""
    meta: dict[str, tuple[str, str]] = {}
    pre, body, delimiter = [], [], None
    for line in lines:
        s = line.strip()
        if not s:
            continue
        if s[0] in "#%":
            key, eq, rest = s[1:].partition("=")
            if eq:
                parts = rest.split(None, 1)
                meta[key.strip().lower()] = (parts[0] if parts else "", parts[1].strip() if len(parts) > 1 else "")
            continue
        if not body:
            if not pre:  # the first line that is not a comment decides how columns are separated
                delimiter = next((d for d in ("\t", ";", ",") if d in s), None)
            fields = _split(s, delimiter)
            if not _numeric(fields):
                pre.append(s)
                continue
        body.append(s)
    if not pre:
        raise InputError(f"{where}: no header naming the columns (time, load-point displacement, mu, ...)")
    if not body:
        raise InputError(f"{where}: a header but no data rows")
    names = _split(pre[-1], delimiter)
    units: list[str | None] = [None] * len(names)
    if len(pre) >= 2 and all(_is_unit(u) for u in _split(pre[-1], delimiter)):  # a units row below the names
        units = [u.strip("[]() ") for u in _split(pre[-1], delimiter)]
        names = _split(pre[-2], delimiter)
        units += [None] * (len(names) - len(units))
    for j, name in enumerate(names):
        m = _UNIT_IN_NAME.match(name)
        if m:
            names[j], units[j] = m.group(1).strip(), m.group(2)
    rows = []
    for i, s in enumerate(body):
        fields = _split(s, delimiter)
        if len(fields) != len(names):
            raise InputError(f"{where}: data row {i + 1} has {len(fields)} values, the header {len(names)} "
                             f"({', '.join(names)})")
        try:
            rows.append([_number(f, delimiter) for f in fields])
        except ValueError:
            raise InputError(f"{where}: data row {i + 1} has a value that is not a number: {s!r}") from None
    return names, units, np.array(rows, dtype=float), meta


def _number(text: str, delimiter: str | None) -> float:
    text = text.strip()
    if text.lower() in ("nan", ""):
        return float("nan")
    if delimiter != "," and text.count(",") == 1 and "." not in text:
        text = text.replace(",", ".")  # a decimal comma
    return float(text)


def _find(names: list[str], columns: Mapping[str, str] | None, where: str) -> dict[str, int]:
    """Column index of each role found: first the ``columns`` mapping, then the aliases."""
    found: dict[str, int] = {}
    for role, name in dict(columns or {}).items():
        if role not in ROLES:
            raise InputError(f"columns: {role!r} is not a record column; use one of {list(ROLES)}")
        keys = [_key(n) for n in names]
        if name in names:
            found[role] = names.index(name)
        elif _key(_UNIT_IN_NAME.sub(r"\1", name)) in keys:
            found[role] = keys.index(_key(_UNIT_IN_NAME.sub(r"\1", name)))
        else:
            raise InputError(f"{where}: columns[{role!r}] = {name!r} is not a column of the file; found {names}")
    for match in (lambda k, role: k in _ALIASES[role], lambda k, role: _PART[role] in k):  # exact names first
        for j, name in enumerate(names):
            for role in ROLES:
                if role not in found and j not in found.values() and match(_key(name), role):
                    found[role] = j
    return found


def _si(where: str, role: str, name: str, unit: str | None) -> float:
    table = _UNITS[role]
    if unit is None:
        if role == "mu":
            return 1.0
        raise InputError(f"{where}: column {name!r} ({role}) has no unit; write it as '{name} [unit]' with a unit "
                         f"from {sorted(table)}")
    u = _unit_key(unit)
    if u not in table:
        raise InputError(f"{where}: column {name!r} ({role}) has unit {unit!r}; use one of {sorted(table)}")
    return table[u]


def read_record(path: str | os.PathLike, columns: Mapping[str, str] | None = None,
                steps: Sequence[tuple[float, float]] | None = None, k: float | None = None,
                noise: float | None = None, sample: str | None = None, name: str | None = None) -> Record:
    """A :class:`Record` from a laboratory text file (module docstring), in SI units.

    ``columns`` maps roles (:data:`ROLES`) to the file's column names where the reader does not know them;
    ``steps`` the history as (start time [s], velocity [m/s]) (default: found from the load point); ``k`` [1/m]
    (default: ``# k = value unit`` in the file's comments, else the fit's); ``noise`` [1] of mu (default: estimated);
    ``sample`` (default: ``# sample = name`` in the comments, else "sample") and ``name`` (the file's stem)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"record file {str(path)!r} does not exist")
    where = f"record file {str(path)!r}"
    names, units, data, meta = _parse(_lines(path), where)
    found = _find(names, columns, where)
    if "time" not in found:
        raise InputError(f"{where}: no time column among {names}; name it with columns={{'time': '<name>'}}")
    if "mu" not in found and not {"shear", "normal"} <= found.keys():
        raise InputError(f"{where}: no friction column (mu, or shear and normal stress) among {names}; name it with "
                         f"columns={{'mu': '<name>'}}")
    if steps is None and "displacement" not in found and "velocity" not in found:
        raise InputError(f"{where}: no load-point displacement or velocity column among {names}; name it with "
                         f"columns={{'displacement': '<name>'}} or give the steps")

    def col(role):
        j = found[role]
        values = data[:, j] * _si(where, role, names[j], units[j])
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise InputError(f"{where}: column {names[j]!r} ({role}) has {bad.size} NaN or empty value(s), first at "
                             f"data row {bad[0] + 1}; remove those rows")
        return values

    t = col("time")
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise InputError(f"{where}: column {names[found['time']]!r} (time) is not strictly increasing: data row "
                         f"{i + 1} ({t[i]:g} s) follows {t[i - 1]:g} s")
    mu = col("mu") if "mu" in found else col("shear") / col("normal")
    if k is None and "k" in meta:
        value, unit = meta["k"]
        if _unit_key(unit) not in _STIFFNESS:
            raise InputError(f"{where}: '# k = {value} {unit}': unit must be one of {sorted(_STIFFNESS)}")
        k = float(value) * _STIFFNESS[_unit_key(unit)]
    return Record(t, mu, displacement=col("displacement") if "displacement" in found else None,
                  velocity=col("velocity") if "velocity" in found else None, steps=steps, k=k, noise=noise,
                  sample=sample or meta.get("sample", ("sample", ""))[0], name=name or path.stem)


def is_record_file(path: str | os.PathLike) -> bool:
    """Whether a text file's header names a time and a friction column (mu, or shear and normal stress): a record,
    not a relaxation curve or relaxed slips (sweep.fit.read.read_data hands it to :func:`read_record`)."""
    try:
        names = _parse(_lines(Path(path)), "")[0]
        found = _find(names, None, "")
    except (InputError, OSError, ValueError):
        return False
    return "time" in found and ("mu" in found or {"shear", "normal"} <= found.keys())
