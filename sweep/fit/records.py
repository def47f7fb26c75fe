"""Laboratory friction records: the :class:`Record` data kind and its reader :func:`read_record`.

A record is friction mu(t) [1] sampled at times t [s] while the load point is driven through a history of velocity
steps and holds (docs/fit.md, "Laboratory records"). The history is given as a list of (start time [s], load-point
velocity [m s-1]), or found from the record's load-point displacement or velocity (sweep.fit.segments). The model
starts from steady sliding at the first segment's velocity at the record's first time.

The reader takes text files as laboratories write them: columns separated by tabs, semicolons, commas or blanks
(the first data row decides; trailing delimiters ignored), decimal commas, CR LF, latin-1 (µm) or UTF-16; comment
lines starting with ``#`` or ``%`` (``# k = 2e3 1/m`` there sets the stiffness, ``# g = 1e4 m/s^2`` the machine's
inertia g = N/M); title lines and key-value lines
above the header; a header naming the columns with their units in brackets or parentheses (``Time (s)``, ``mu
[-]``), as the name's last part (PSU's ``time_s``, ``lpdisp_um``, ``shr_stress_mpa``) or in a units row below the
names (xlook's ``sec  mic  MPa  .``); quoted fields; time stamps (read as seconds); columns it does not use (a row
counter, a sync, a sampling rate, a status word); irregular sample times; 1e5 rows (numpy's reader; column by column
only to name a bad row or read time stamps). Columns it knows by name (case, blanks and units aside; ``columns={"time":
"Zeit"}`` names others, ``units={"displacement": "um"}`` gives a unit the file does not write):

* time [s, ms, min, h; sec];
* load-point displacement [m, mm, um, nm; mic, micron] or load-point velocity [length/time];
* friction mu [1], or shear and normal stress [Pa, kPa, MPa, GPa, bar, psi] or load [N, kN, lbf, kgf] (mu =
  shear/normal, both stresses or both loads); friction that is negative throughout (a sign convention) is taken as
  its magnitude, as is a load-point displacement that counts down (sweep.fit.segments).

Anything else it refuses in one line naming the column and what was found: a missing or unknown column or unit,
NaN or empty values, time that repeats or goes back, a row cut short, a step outside the data.
"""

from __future__ import annotations

import csv
import os
import re
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import InputError
from .units import FORCE, RECORD_UNITS

__all__ = ["G_RANGE", "ROLES", "Record", "check_g", "is_record_file", "read_record"]

ROLES = ("time", "displacement", "velocity", "mu", "shear", "normal")
"""The columns a record may have (``columns`` maps these to the file's names)."""

_ALIASES = {
    "time": ("t", "time", "times", "elapsed_time", "time_elapsed", "run_time", "test_time"),
    "displacement": ("lp_disp", "lpdisp", "load_point_displacement", "displacement", "lp_displacement", "x_lp",
                     "disp", "load_point", "lpd", "d_lp", "load_point_disp", "lp_position", "ram_disp",
                     "axial_disp", "shear_disp", "slip_lp"),
    "velocity": ("v_lp", "lp_velocity", "load_point_velocity", "velocity", "vlp", "v", "lp_vel", "lp_v",
                 "load_point_vel"),
    "mu": ("mu", "µ", "μ", "friction", "friction_coefficient", "coefficient_of_friction", "cof", "mu_f",
           "friction_coef", "fric_coef"),
    "shear": ("tau", "shear", "shear_stress", "tau_s", "shr_stress", "shear_load", "shear_force", "shr_load",
              "f_s", "fs", "tau_mpa"),
    "normal": ("sigma", "normal", "normal_stress", "sigma_n", "sn", "nor_stress", "normal_load", "normal_force",
               "nor_load", "f_n", "fn", "effns", "eff_ns", "effective_normal_stress", "sigma_eff", "sigma_n_eff"),
}
_PART = {"time": "time", "displacement": "disp", "velocity": "veloc", "mu": "fric", "shear": "shear",
         "normal": "normal"}
"""A part of a name that tells its role where no alias matches exactly ('Load point disp.', 'Friction coef.')."""
_NOT_LOAD_POINT = ("nor", "hor", "dilat", "layer", "thick", "vert", "gap", "lvdt", "dcdt")
"""Parts of a displacement's name that say it is not the load point's (normal, horizontal, dilatancy, layer
thickness, a gauge): such a column is never taken as the load point by a part of its name."""
_UNITLESS = {".", "-", "", "1", "none", "bit", "bits", "hz", "v", "mv", "count", "counts", "#", "n/a", "na",
             "no_unit", "unitless", "%", "c", "°c", "deg", "ohm", "a.u.", "au"}
"""What a units row writes beside the units of the columns a record uses (a row counter's '.', a sync 'bit')."""
_STIFFNESS = {"1/m": 1.0, "m-1": 1.0, "1/mm": 1e3, "mm-1": 1e3, "1/um": 1e6, "um-1": 1e6, "1/µm": 1e6}
_UNIT_IN_NAME = re.compile(r"^(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$")
HEADER_LINES = 500
"""Lines of a file that :func:`is_record_file` reads for its header."""


def _key(name: str) -> str:
    """A column name compared to the aliases: lower case, blanks and punctuation as single underscores."""
    return re.sub(r"[^0-9a-zµμ/]+", "_", name.strip().lower()).strip("_")


def _unit_key(unit: str) -> str:
    """A unit compared to the tables: lower case, no blanks, s-1 and s^-1 as /s."""
    return unit.strip().replace(" ", "").replace("s^-1", "/s").replace("s-1", "/s").lower()


def _role_of(key: str, role: str) -> tuple[bool, str | None]:
    """Whether a column's name (:func:`_key`) names ``role`` and the unit written as its last part, if any
    (``time_s``, ``lp_disp_um``, ``shr_stress_mpa``, ``v_lp_um_s``: PSU's and xlook's style); an alias that ends as
    a unit does (``tau_s``, ``sigma_n``) is the alias."""
    if key in _ALIASES[role]:
        return True, None
    parts = key.split("_")
    for n in (2, 1):
        if len(parts) > n and "_".join(parts[:-n]) in _ALIASES[role]:
            unit = "/".join(parts[-n:])
            if _unit_key(unit) in RECORD_UNITS[role]:
                return True, unit
    return False, None


def _unit_like(field: str) -> bool:
    u = _unit_key(field.strip("[]() "))
    return u in _UNITLESS or any(u in table for table in RECORD_UNITS.values())


@dataclass(frozen=True, eq=False)
class Record:
    """A laboratory record (module docstring), SI units: ``t`` [s] strictly increasing, ``mu`` [1] (finite);
    ``displacement`` [m] or ``velocity`` [m s-1] of the load point per sample (either, or None where ``steps`` is
    given); ``steps``: the history as ((start time [s], velocity [m s-1]), ...) from the first time on, or None
    (found from the displacement, sweep.fit.segments); ``k`` [1/m] the stiffness k = K/(M g) (None: from the fit's
    parameters); ``noise`` [1] per sample, one number, or None (estimated); ``sample`` and ``name`` as for a Curve;
    ``detrend`` "time" or "displacement": the model carries a linear trend c (t - t[0]) or c (x - x[0]) of its own
    slope c [1/s or 1/m] per record, the one that fits best at each parameter set (projected out; fitted as one
    more parameter: sweep.fit.result reports it, ``detrend_slope_time`` / ``_displacement``); ``g`` [m s-2] the
    machine's inertia g = N/M, its normal load over its moving mass (None: the fit's ``g``, else its default:
    quasi-static, inertia only where the model's slip runs away; docs/fit.md, "The machine's inertia").
    :meth:`window` cuts a record to a time range."""

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
    g: float | None = None

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
        if self.g is not None:
            set_("g", check_g(f"{where}: g", self.g))
        if self.noise is not None:
            noise = np.broadcast_to(np.asarray(self.noise, dtype=float), t.shape).copy()
            if not np.all(np.isfinite(noise) & (noise > 0)):
                raise InputError(f"{where}: noise must be > 0 and finite (one number or one per sample)")
            set_("noise", noise)
        set_("sample", str(self.sample))

    @property
    def n(self) -> int:
        return self.t.size

    def window(self, t_start: float | None = None, t_end: float | None = None) -> Record:
        """The record between ``t_start`` and ``t_end`` [s, its own clock] (default: its first and last time): the
        samples there, the steps from the one in force at the new first time. The model starts from steady sliding at
        the new first time: cut a record that starts in a hold (or right after a change) to where it slides steadily.
        """
        where = f"record {self.name!r}"
        lo, hi = (float(self.t[0]) if t_start is None else float(t_start),
                  float(self.t[-1]) if t_end is None else float(t_end))
        for label, value in (("t_start", lo), ("t_end", hi)):
            if not (np.isfinite(value) and self.t[0] <= value <= self.t[-1]):
                raise InputError(f"{where}: {label} = {value:g} s is not in the data (time runs from {self.t[0]:g} "
                                 f"to {self.t[-1]:g} s)")
        keep = (self.t >= lo) & (self.t <= hi)
        if keep.sum() < 10:
            raise InputError(f"{where}: {int(keep.sum())} samples between t_start = {lo:g} s and t_end = {hi:g} s; a "
                             f"record needs at least 10")
        t = self.t[keep]
        steps = None
        if self.steps is not None:
            first = int(np.searchsorted([s for s, _ in self.steps], t[0], side="right")) - 1
            steps = ((float(t[0]), self.steps[first][1]),) + tuple(s for s in self.steps[first + 1:] if s[0] < t[-1])
        cut = {f: None if getattr(self, f) is None else getattr(self, f)[keep]
               for f in ("mu", "displacement", "velocity", "noise")}
        return replace(self, t=t, steps=steps, **cut)


G_RANGE = (1e-3, 1e12)
"""Allowed range of a machine's g = N/M [m s-2] (the normal load over the moving mass; a block under its own weight
9.81, a laboratory machine ~1e3..1e6): beyond it a unit mistake."""


def check_g(name: str, value) -> float:
    """``value`` as a machine's g = N/M [m s-2] in :data:`G_RANGE` (InputError naming ``name`` otherwise)."""
    try:
        g = float(value)
    except (TypeError, ValueError):
        g = float("nan")
    if isinstance(value, bool) or not G_RANGE[0] <= g <= G_RANGE[1]:
        raise InputError(f"{name} must be a number in [{G_RANGE[0]:g}, {G_RANGE[1]:g}] m/s^2 (g = N/M, the normal "
                         f"load over the machine's moving mass; k = K/(M g) = K/N), got {value!r}")
    return g


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

def _lines(path: Path, limit: int | None = None) -> list[str]:
    """The file's lines (all, or about the first ``limit``): UTF-8 (a byte-order mark dropped), UTF-16 with its
    byte-order mark (a spreadsheet's "Unicode text") or latin-1 (a lab PC's µ as one byte); CR LF, CR or LF."""
    with open(path, "rb") as fh:
        raw = fh.read() if limit is None else b"".join(fh.readline() for _ in range(limit))
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return raw.decode("utf-16", errors="ignore" if limit else "strict").splitlines()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return text.splitlines()


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:  # blanks: a name followed by its unit in brackets stays one field
        fields = re.findall(r"[^\s\[(]+(?:\s*[\[(][^\])]*[\])])?|[\[(][^\])]*[\])]", line)
    elif '"' in line:  # a spreadsheet's quotes, which may hold the delimiter ("0,6" in a comma-separated file)
        fields = [f.strip() for f in next(csv.reader([line], delimiter=delimiter, skipinitialspace=True))]
    else:
        fields = [f.strip() for f in line.split(delimiter)]
    while fields and fields[-1] == "":  # a trailing delimiter
        fields.pop()
    return fields


_STAMP = re.compile(r"^(\d{4}-\d{2}-\d{2}[ T])?\d{1,2}:\d{2}(:\d{2}([.,]\d+)?)?$")
"""A date and clock time (ISO 8601, a blank or T between them) or a clock time: a DAQ's time stamp."""


_CELL_ERROR = re.compile(r"#(N/A|DIV/0!|VALUE!|REF!|NUM!|NAME\?|NULL!)")
"""A spreadsheet's error value (#N/A, #DIV/0!, ...): a row that starts with one is a data row, not a comment."""


def _number(text: str) -> float:
    """A value of a data row: a number (a decimal comma too), NaN for '' or 'nan'; ValueError otherwise."""
    if text.lower() in ("", "nan"):
        return float("nan")
    return float(text.replace(",", ".") if text.count(",") == 1 and "." not in text else text)


def _numeric(fields: list[str], strict: bool = False) -> bool:
    """Whether ``fields`` look like a row of data: one number at least, and numbers, empty fields or time stamps for
    at least half of them (the rest a status word), or (``strict``) for all."""
    numbers = values = 0
    for f in fields:
        try:
            numbers += bool(np.isfinite(_number(f)))
            values += 1
        except ValueError:
            values += bool(_STAMP.match(f))
    return numbers > 0 and (values == len(fields) if strict else 2 * values >= len(fields))


def _seconds(column: list[str]) -> np.ndarray:
    """Time stamps (:data:`_STAMP`) as seconds [s] (since 1970 with a date, since midnight without); ValueError where
    one is not a time stamp."""
    if not all(_STAMP.match(f) for f in column):
        raise ValueError
    if ":" in column[0] and "-" not in column[0]:  # a clock time only
        column = [f"1970-01-01 {f}" for f in column]
    stamps = np.array([f.replace(",", ".").replace(" ", "T") for f in column], dtype="datetime64[us]")
    return stamps.astype(np.int64) * 1e-6


@dataclass
class _Header:
    names: list[str]
    units: list[str | None]
    delimiter: str | None
    body: int
    """Index of the first data line."""
    meta: dict[str, tuple[str, str]]


def _data_line(line: str) -> str | bool | None:
    """The delimiter under which ``line`` is a row of data (tab, semicolon, comma, else blanks: None), or False: the
    first under which every field is a value, else the first under which most are (:func:`_numeric`)."""
    for strict in (True, False):
        for d in ("\t", ";", ",", None):
            if (d is None or d in line) and _numeric(_split(line, d), strict):
                return d
    return False


AGREE = 20
"""Lines after the first data row that must look like data rows with as many fields (fewer where the file ends)."""


def _next_agrees(lines: list[str], i: int, delimiter: str | None) -> bool:
    """Whether the :data:`AGREE` lines after data-like line ``i`` (blank and comment lines skipped) are data-like
    too, with as many fields: the first data row, not a block of 'Sampling rate,100' lines above the header."""
    n, seen = len(_split(lines[i].strip(), delimiter)), 0
    for k, line in enumerate(lines[i + 1:], start=i + 1):
        s = line.strip()
        if s and s[0] not in "#%":
            fields = _split(s, delimiter)
            if len(fields) != n or not _numeric(fields):
                return not any(x.strip() for x in lines[k + 1:])  # the last line, cut short: _rows names it
            seen += 1
            if seen == AGREE:
                break
    return True


def _meta_line(text: str, meta: dict[str, tuple[str, str]], keep: bool = True) -> None:
    """A ``key = value unit`` line (a comment's, or one above the header: also ``key: value unit``) into ``meta``
    (lower-case key: (value, unit)); ``keep``: a key already there is replaced."""
    key, eq, rest = text.partition("=")
    if not eq and not keep:
        key, eq, rest = text.partition(":")
    key = key.strip().lower()
    if eq and key and (keep or key not in meta):
        parts = rest.split(None, 1)
        meta[key] = (parts[0] if parts else "", parts[1].strip() if len(parts) > 1 else "")


def _header(lines: list[str], where: str) -> _Header:
    """The header of a record file: comment lines (``#``, ``%``: ``# key = value unit`` kept as metadata), then lines
    that are not numbers (a title, the names, a units row), then the data, whose first row decides how columns are
    separated (tab, semicolon, comma, else blanks). The last non-number line names the columns, or the one before it
    where the last is a units row (as many fields, each a unit or a unit-less mark such as a row counter's '.', at
    least one a unit a record column takes)."""
    meta: dict[str, tuple[str, str]] = {}
    pre, comments, delimiter, body_at = [], [], None, len(lines)
    for i, line in enumerate(lines):
        s = line.strip()
        if not s:
            continue
        if s[0] in "#%":
            _meta_line(s[1:], meta)
            comments.append(s.lstrip("#% "))
            continue
        d = _data_line(s)
        if d is not False and _next_agrees(lines, i, d):
            body_at, delimiter = i, d
            break
        pre.append(s)
    for s in pre[:-1]:  # 'Normal stress = 12.5 MPa' above the header, as a test program writes its settings
        _meta_line(s, meta, keep=False)
    if body_at == len(lines) and pre:
        raise InputError(f"{where}: a header but no data rows")
    width = len(_split(lines[body_at].strip(), delimiter)) if body_at < len(lines) else 0
    if not pre and comments and width and len(_split(comments[-1], delimiter)) == width:
        pre = comments[-1:]  # the names as a comment line ('# Time (s)  LP_Disp (um)  mu', a gnuplot-ready export)
    if not pre:
        raise InputError(f"{where}: no header naming the columns (time, load-point displacement, mu, ...)")

    def fields(line: str) -> list[str]:
        """The header's fields: as the rows are separated, else by blanks (above tab-separated rows), else by runs of
        two or more blanks (names with a blank inside: 'LP Disp (um)  Shear stress (MPa)'), as many as the rows'."""
        for f in (_split(line, delimiter), _split(line, None), [x for x in re.split(r"\s{2,}|\t", line) if x]):
            if len(f) == width:
                return f
        return _split(line, delimiter)

    names = fields(pre[-1])
    units: list[str | None] = [None] * len(names)
    if len(pre) >= 2:
        above = fields(pre[-2])
        if len(above) == len(names) and all(_unit_like(u) for u in names) and \
                any(_unit_key(u.strip("[]() ")) not in _UNITLESS for u in names):  # a units row below the names
            names, units = above, [u.strip("[]() ") or None for u in names]
    for j, name in enumerate(names):
        m = _UNIT_IN_NAME.match(name)
        if m:
            names[j], units[j] = m.group(1).strip(), m.group(2)
    return _Header(names, units, delimiter, body_at, meta)


def _rows(lines: list[str], h: _Header, where: str) -> tuple[np.ndarray, dict[int, str]]:
    """The data rows (n, columns): numpy's reader, or column by column where it fails (to name a bad row, to read
    time stamps as seconds, to skip lines of words only: a marker, the header again); and the columns that are not
    numbers ({index: (the first such value, its data row)}: NaN in the data, refused only where the record uses
    them)."""
    body = [s for s in (line.strip() for line in lines[h.body:]) if s and (s[0] not in "#%" or _CELL_ERROR.match(s))]
    d = h.delimiter
    if d is not None and body and body[0].endswith(d):  # a trailing delimiter on every row
        body = [s.rstrip(d + " ") for s in body]
    fast = [s.replace('"', "") for s in body] if body and '"' in body[0] else body
    if d != "," and any("," in s for s in fast[:20]):  # decimal commas
        fast = [s.replace(",", ".") for s in fast]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # an empty line numpy would skip with a warning: row by row
            data = np.loadtxt(fast, delimiter=d, ndmin=2, dtype=float, comments=None)
        if data.shape[1] == len(h.names):
            return data, {}
    except ValueError:
        pass
    rows, at, header = [], [], [_key(n) for n in h.names]
    for i, s in enumerate(body):
        fields = _split(s, d)
        if not any(_is_number(f) or _STAMP.match(f) or _CELL_ERROR.match(f) for f in fields):  # words only:
            names = [_key(_UNIT_IN_NAME.sub(r"\1", f)) for f in fields]  # a marker line, a header again
            if len(fields) == len(h.names) and names != header and not all(_unit_like(f) for f in fields):
                raise InputError(f"{where}: data row {i + 1} is a header that differs from the first ({s!r}, first: "
                                 f"{', '.join(h.names)}); split the file there")
            continue  # 'Logger restarted', 'END', the same names or units again
        if len(fields) != len(h.names):
            last = " (the last line, cut short: remove it)" if i == len(body) - 1 else ""
            raise InputError(f"{where}: data row {i + 1} has {len(fields)} values, the header {len(h.names)} "
                             f"({', '.join(h.names)}){last}")
        rows.append(fields)
        at.append(len(rows))
    data, text = np.full((len(rows), len(h.names)), np.nan), {}
    for j, column in enumerate(zip(*rows)):
        try:
            try:
                data[:, j] = np.array(column, dtype=float)  # numpy's own parse first (10x the loop's speed)
            except ValueError:
                data[:, j] = [_number(f) for f in column]
        except ValueError:
            try:
                data[:, j] = _seconds(list(column))
            except ValueError:
                r = next(r for r, f in enumerate(column) if not _STAMP.match(f) and not _is_number(f))
                text[j] = (column[r], at[r])
    return data, text


def _is_number(text: str) -> bool:
    try:
        _number(text)
    except ValueError:
        return False
    return True


def _find(names: list[str], columns: Mapping[str, str] | None, where: str) -> dict[str, tuple[int, str | None]]:
    """Column index of each role found, with the unit its name ends in (``time_s``) if any: first the ``columns``
    mapping, then the aliases (exact, or with a unit as their last part), then a part of the name."""
    found: dict[str, tuple[int, str | None]] = {}
    keys = [_key(_UNIT_IN_NAME.sub(r"\1", n)) for n in names]
    for role, name in dict(columns or {}).items():
        if role not in ROLES:
            raise InputError(f"columns: {role!r} is not a record column; use one of {list(ROLES)}")
        if name in names:
            j = names.index(name)
        elif _key(_UNIT_IN_NAME.sub(r"\1", str(name))) in keys:
            j = keys.index(_key(_UNIT_IN_NAME.sub(r"\1", str(name))))
        else:
            raise InputError(f"{where}: columns[{role!r}] = {name!r} is not a column of the file; found {names}")
        found[role] = (j, _role_of(keys[j], role)[1])

    def free(j: int) -> bool:
        return all(j != i for i, _ in found.values())

    for j, key in enumerate(keys):  # exact names first
        for role in ROLES:
            hit, unit = _role_of(key, role)
            if hit and role not in found and free(j):
                found[role] = (j, unit)
    for j, key in enumerate(keys):
        for role in ROLES:
            if role not in found and free(j) and _PART[role] in key and \
                    not (role == "displacement" and any(p in key for p in _NOT_LOAD_POINT)):
                found[role] = (j, None)
    return found


def _si(where: str, role: str, name: str, unit: str | None) -> float:
    table = RECORD_UNITS[role]
    if unit is None or (role == "mu" and _key(unit) in _ALIASES["mu"]):  # 'Friction (μ)': the symbol as its unit
        if role == "mu":
            return 1.0
        raise InputError(f"{where}: column {name!r} ({role}) has no unit; write it as '{name} [unit]' or give "
                         f"units={{{role!r}: '<unit>'}}, a unit from {sorted(table)}")
    u = _unit_key(unit)
    if u not in table:
        raise InputError(f"{where}: column {name!r} ({role}) has unit {unit!r}; use one of {sorted(table)} (or give "
                         f"units={{{role!r}: '<unit>'}})")
    return table[u]


def read_record(path: str | os.PathLike, columns: Mapping[str, str] | None = None,
                units: Mapping[str, str] | None = None, steps: Sequence[tuple[float, float]] | None = None,
                k: float | None = None, noise: float | None = None, sample: str | None = None,
                name: str | None = None, detrend: str | None = None, t_start: float | None = None,
                t_end: float | None = None, g: float | None = None) -> Record:
    """A :class:`Record` from a laboratory text file (module docstring), in SI units.

    ``columns`` maps roles (:data:`ROLES`) to the file's column names where the reader does not know them;
    ``units`` roles to units where the file gives none (or a wrong one), e.g. ``{"displacement": "um"}``;
    ``steps`` the history as (start time [s], velocity [m/s]) (default: found from the load point); ``k`` [1/m]
    (default: ``# k = value unit`` in the file's comments, else the fit's); ``noise`` [1] of mu (default: estimated);
    ``sample`` (default: ``# sample = name`` in the comments, else "sample") and ``name`` (the file's stem);
    ``detrend`` as :class:`Record`'s; ``g`` [m/s^2] the machine's g = N/M (default: ``# g = value m/s^2`` in the
    file's comments, else the fit's); ``t_start``, ``t_end`` [s, the file's clock]: keep only the samples between
    them (:meth:`Record.window`: a record that starts in a hold is cut to a time in steady sliding)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"record file {str(path)!r} does not exist")
    where = f"record file {str(path)!r}"
    lines = _lines(path)
    h = _header(lines, where)
    names, (data, text) = h.names, _rows(lines, h, where)
    same = np.all((data[1:] == data[:-1]) | (np.isnan(data[1:]) & np.isnan(data[:-1])), axis=1)
    rowno = np.flatnonzero(np.concatenate(([True], ~same))) + 1  # data row numbers of the rows kept
    if same.any():  # a row written twice (a logger switching its rate): the same information, dropped
        data = data[rowno - 1]
    found = _find(names, columns, where)
    for role in dict(units or {}):
        if role not in ROLES:
            raise InputError(f"units: {role!r} is not a record column; use one of {list(ROLES)}")
    if "time" not in found:
        raise InputError(f"{where}: no time column among {names}; name it with columns={{'time': '<name>'}}")
    normal = None if "mu" in found or "normal" in found or "shear" not in found else _header_normal(h.meta, where)
    if "mu" not in found and not ({"shear", "normal"} <= found.keys() or normal):
        raise InputError(f"{where}: no friction column (mu, or shear and normal stress) among {names}; name it with "
                         f"columns={{'mu': '<name>'}}")
    if steps is None and "displacement" not in found and "velocity" not in found:
        raise InputError(f"{where}: no load-point displacement or velocity column among {names}; name it with "
                         f"columns={{'displacement': '<name>'}} or give the steps")

    def col(role):
        j, unit = found[role]
        if j in text:
            raise InputError(f"{where}: column {names[j]!r} ({role}) is not numbers (e.g. {text[j][0]!r}, data row "
                             f"{text[j][1]}); remove such rows, or name the right column with columns={{{role!r}: "
                             f"'<name>'}}")
        unit = dict(units or {}).get(role, h.units[j] if h.units[j] is not None else unit)
        if role == "time" and unit is None and _STAMP.match(_split(lines[h.body].strip(), h.delimiter)[j]):
            unit = "s"  # time stamps, read as seconds
        values = data[:, j] * _si(where, role, names[j], unit)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise InputError(f"{where}: column {names[j]!r} ({role}) has {bad.size} NaN or empty value(s), first at "
                             f"data row {rowno[bad[0]]}; remove those rows")
        return values

    t = col("time")
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        what = "repeats a time" if t[i] == t[i - 1] else "is not strictly increasing"
        step = np.diff(t)
        fix = "sort the rows or remove the repeats"
        if np.all(step[back] == 0) and back.size > 0.01 * t.size and np.any(np.diff(back) > 1):  # repeats all
            # through (not a clock stuck once): the time written to fewer digits than it samples
            fix = (f"the time is written to {np.min(step[step > 0]):.3g} s (its smallest step) while sampled "
                   f"finer: export it with more digits") if np.any(step > 0) else fix
        elif t[i] <= t[0] < t[i - 1]:
            fix = "the clock starts again there (a restarted logger?): split the file at that row"
        raise InputError(f"{where}: column {names[found['time'][0]]!r} (time) {what}: data row {rowno[i]} "
                         f"({t[i]:.9g} s) follows {t[i - 1]:.9g} s ({back.size} such row(s)); {fix}")
    if "mu" in found:
        mu = col("mu")
    else:
        kind = lambda unit: "force" if _unit_key(unit or "") in FORCE else "stress"  # noqa: E731
        shear = kind(dict(units or {}).get("shear") or h.units[found["shear"][0]] or found["shear"][1])
        if normal is not None:
            other, value = f"the header's {normal[0]!r}", normal[1]
            kind_n = kind(normal[2])
        else:
            other, value = f"{names[found['normal'][0]]!r} (normal)", None
            kind_n = kind(dict(units or {}).get("normal") or h.units[found["normal"][0]] or found["normal"][1])
        if shear != kind_n:
            raise InputError(f"{where}: column {names[found['shear'][0]]!r} (shear) is a {shear} and {other} a "
                             f"{kind_n}: friction is their ratio; give both as stresses or both as forces")
        mu = col("shear") / (col("normal") if value is None else value)
    if np.all(mu < 0):  # a shear load counted negative (a sign convention): friction is its magnitude
        mu = -mu
    if k is None and "k" in h.meta:
        value, unit = h.meta["k"]
        if _unit_key(unit) not in _STIFFNESS:
            raise InputError(f"{where}: '# k = {value} {unit}': unit must be one of {sorted(_STIFFNESS)}")
        k = float(value) * _STIFFNESS[_unit_key(unit)]
    if g is None and "g" in h.meta:
        value, unit = h.meta["g"]
        if _unit_key(unit) not in ("", "m/s^2", "m/s2", "ms-2", "m/s/s", "m/s²"):
            raise InputError(f"{where}: '# g = {value} {unit}': g = N/M is in m/s^2 (write '# g = {value} m/s^2')")
        g = check_g(f"{where}: '# g = {value} {unit}'", value)
    rec = Record(t, mu, displacement=col("displacement") if "displacement" in found else None,
                 velocity=col("velocity") if "velocity" in found else None, steps=steps, k=k, noise=noise,
                 sample=sample or h.meta.get("sample", ("sample", ""))[0], name=name or path.stem, detrend=detrend,
                 g=g)
    return rec if t_start is None and t_end is None else rec.window(t_start, t_end)


def _header_normal(meta: Mapping[str, tuple[str, str]], where: str) -> tuple[str, float, str] | None:
    """(key, value [Pa or N], unit) of a constant normal stress or load given in the header (``Normal stress = 12.5
    MPa``, ``# sigma_n = 10 MPa``; the unit after the value or in brackets after the key), None where none is."""
    for key, (value, unit) in meta.items():
        m = _UNIT_IN_NAME.match(key)
        name, unit = (m.group(1), unit or m.group(2)) if m else (key, unit)
        if _role_of(_key(name), "normal")[0] or ("normal" in _key(name) and "disp" not in _key(name)):
            unit = unit.split()[0] if unit else ""
            try:
                number = float(value.replace(",", ".") if value.count(",") == 1 else value)
            except ValueError:
                raise InputError(f"{where}: the header's {key!r} = {value!r} is not a number; the normal stress must "
                                 f"be one (e.g. '{name} = 10 MPa')") from None
            table = RECORD_UNITS["normal"]
            if _unit_key(unit) not in table:
                raise InputError(f"{where}: the header's {key!r} = {value} has unit {unit!r}; write it as '{name} = "
                                 f"{value} <unit>', a unit from {sorted(table)}")
            if not (np.isfinite(number) and number > 0):
                raise InputError(f"{where}: the header's {key!r} = {value} must be > 0 (the normal stress)")
            return key, number * table[_unit_key(unit)], unit
    return None


def is_record_file(path: str | os.PathLike) -> bool:
    """Whether a text file's header names a time and a friction column (mu, or shear and normal stress, the normal
    stress a column or a constant in the header): a record,
    not a relaxation curve or relaxed slips (sweep.fit.read.read_data hands it to :func:`read_record`). Reads the
    first :data:`HEADER_LINES` lines only."""
    try:
        h = _header(_lines(Path(path), HEADER_LINES), "")
        found = _find(h.names, None, "")
        normal = "normal" in found or ("shear" in found and _header_normal(h.meta, "") is not None)
    except (InputError, OSError, ValueError):
        return False
    return "time" in found and ("mu" in found or ("shear" in found and normal))
