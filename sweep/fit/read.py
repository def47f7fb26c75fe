"""Read measured data with their units: CSV (units in a ``#`` header) or netCDF (units in attributes).

CSV, a relaxation curve (columns t, x and optionally noise; K/M and V in the header)::

    # K_over_M = 2.8e5 s-2
    # V = 1 um/s
    # t: s
    # x: um
    # noise: um
    t,x,noise
    0.1,0.083,0.0014
    ...

CSV, relaxed slips (columns K_over_M, V, dx_inf and optionally noise, each with its unit in the header)::

    # K_over_M: s-2
    # V: um/s
    # dx_inf: um
    K_over_M,V,dx_inf
    2e5,3,0.71

Laboratory files vary: the columns may be separated by commas, semicolons, tabs or blanks (the header line decides:
the first of ``,``, ``;``, tab found in it, else blanks), a semicolon-separated file may write decimal commas
(``0,083``), the file may start with a byte-order mark and end its lines with CR LF, and the header's names may carry
blanks around them. Rows may be irregular in time (any strictly increasing t) and slips noisy, a little below zero
(sweep.fit.data).

netCDF: the same names as variables with a ``units`` attribute (a curve: t and x along one dimension, K_over_M and
V scalar variables; relaxed slips: K_over_M, V, dx_inf along one dimension). Units: :mod:`sweep.fit.units`.

A text file whose header names a time and a friction column is a laboratory record (sweep.fit.records.read_record).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from .data import Curve, Data, RelaxedSlips
from .records import is_record_file, read_record
from .units import to_si

__all__ = ["read_data"]


RECORD_OPTIONS = ("columns", "units", "steps", "k", "noise", "detrend", "t_start", "t_end", "g")
"""Options of a laboratory record's file (sweep.fit.records.read_record), also keys of ``sweep fit``'s [[data]]."""


def read_data(path: str | os.PathLike, sample: str | None = None, name: str | None = None,
              record: Mapping[str, Any] | None = None) -> Data:
    """A :class:`Curve` or :class:`RelaxedSlips` from a CSV or netCDF file (module docstring), in SI units, or a
    laboratory record (sweep.fit.records.Record) from a text file whose header names a time and a friction column,
    or wherever ``record`` (options of read_record, :data:`RECORD_OPTIONS`) is given. ``sample`` and ``name`` label it
    (default: the header's ``sample``, else "sample"; the file's stem)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"data file {str(path)!r} does not exist")
    where = f"data file {str(path)!r}"
    record = dict(record or {})
    unknown = sorted(set(record) - set(RECORD_OPTIONS))
    if unknown:
        raise InputError(f"{where}: unknown record option(s) {unknown}; allowed: {list(RECORD_OPTIONS)}")
    if path.suffix.lower() in (".nc", ".nc4", ".netcdf"):
        if record:
            raise InputError(f"{where}: {sorted(record)} are options of a laboratory record (a text file), not of "
                             f"a netCDF file")
        columns, units, meta = _netcdf(path, where)
    elif record or is_record_file(path):  # a laboratory record: mu(t) and the load point (sweep.fit.records)
        return read_record(path, sample=sample, name=name, **record)
    else:
        columns, units, meta = _csv(path, where)
    sample = sample or meta.get("sample", (None, None))[0] or "sample"
    name = name or path.stem

    def si(key, values, unit):
        return np.asarray(values, dtype=float) * to_si(where, key, unit)

    noise = si("noise", columns["noise"], units.get("noise")) if "noise" in columns else None
    if "t" in columns or "x" in columns:
        for key in ("t", "x"):
            if key not in columns:
                raise InputError(f"{where}: a relaxation curve needs columns t and x; {key} is missing")
        for key in ("K_over_M", "V"):
            if key not in meta:
                raise InputError(f"{where}: a relaxation curve needs '# {key} = value unit' in its header")
        km, v = (si(k, float(meta[k][0]), meta[k][1]) for k in ("K_over_M", "V"))
        return Curve(si("t", columns["t"], units.get("t")), si("x", columns["x"], units.get("x")), float(km),
                     float(v), noise=noise, sample=sample, name=name)
    if "dx_inf" not in columns:
        raise InputError(f"{where}: found neither columns t, x (a relaxation curve) nor dx_inf (relaxed slips)")
    for key in ("K_over_M", "V"):
        if key not in columns:
            raise InputError(f"{where}: relaxed slips need a {key} column")
    return RelaxedSlips(si("K_over_M", columns["K_over_M"], units.get("K_over_M")),
                        si("V", columns["V"], units.get("V")), si("dx_inf", columns["dx_inf"], units.get("dx_inf")),
                        noise=noise, sample=sample, name=name)


def _csv(path: Path, where: str):
    units: dict[str, str] = {}
    meta: dict[str, tuple[str, str | None]] = {}
    rows = []
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:  # -sig: a byte-order mark is not part of the header
            lines = fh.read().splitlines()
    except UnicodeDecodeError:
        with open(path, newline="", encoding="latin-1") as fh:  # a lab PC's export (µ in the units)
            lines = fh.read().splitlines()
    body = []
    for line in lines:
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            s = s[1:].strip()
            if "=" in s:
                key, _, rest = s.partition("=")
                parts = rest.split(None, 1)
                meta[key.strip()] = (parts[0] if parts else "", parts[1].strip() if len(parts) > 1 else None)
            elif ":" in s:
                key, _, unit = s.partition(":")
                units[key.strip()] = unit.strip()
            continue
        body.append(s)
    if not body:
        raise InputError(f"{where}: no column header and no data")
    delimiter = next((d for d in (",", ";", "\t") if d in body[0]), None)  # None: blanks
    reader = csv.reader(body, delimiter=delimiter) if delimiter else (line.split() for line in body)
    header = [h.strip() for h in next(reader)]
    for i, row in enumerate(reader, start=2):
        if len(row) != len(header):
            raise InputError(f"{where}: data row {i - 1} has {len(row)} values, the header {len(header)}")
        try:
            rows.append([_number(v, delimiter) for v in row])
        except ValueError:
            raise InputError(f"{where}: data row {i - 1} has a value that is not a number: {row!r}") from None
    data = np.array(rows, dtype=float).reshape(-1, len(header))
    columns = {h: data[:, j] for j, h in enumerate(header)}
    for key in columns:
        if key in ("t", "x", "noise", "dx_inf", "K_over_M", "V") and key not in units:
            raise InputError(f"{where}: column {key!r} has no unit; add a header line '# {key}: <unit>'")
    for key in ("K_over_M", "V"):
        if key in meta and not meta[key][1]:
            raise InputError(f"{where}: '# {key} = {meta[key][0]}' has no unit; write e.g. '# {key} = "
                             f"{meta[key][0]} {'s-2' if key == 'K_over_M' else 'm/s'}'")
    return columns, units, meta


def _number(text: str, delimiter: str | None) -> float:
    """A value of a data row; a decimal comma where the columns are not separated by commas (0,083 -> 0.083)."""
    text = text.strip()
    if delimiter != "," and text.count(",") == 1 and "." not in text:
        text = text.replace(",", ".")
    return float(text)


def _netcdf(path: Path, where: str):
    import xarray as xr

    try:
        ds = xr.open_dataset(path, decode_times=False)
    except (OSError, ValueError) as exc:
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0].split(". ")[0]
        raise InputError(f"{where} is not a readable netCDF file ({first})") from None
    with ds:
        columns, units, meta = {}, {}, {}
        curve = "t" in ds.variables
        for key in ("t", "x", "noise", "dx_inf", "K_over_M", "V"):
            if key not in ds.variables:
                continue
            var = ds[key]
            unit = var.attrs.get("units")
            if unit is None:
                raise InputError(f"{where}: variable {key!r} has no units attribute")
            if curve and key in ("K_over_M", "V"):
                meta[key] = (str(float(var.values)), unit)
            else:
                columns[key], units[key] = np.asarray(var.values, dtype=float).reshape(-1), unit
        if "sample" in ds.attrs:
            meta["sample"] = (str(ds.attrs["sample"]), None)
    return columns, units, meta
