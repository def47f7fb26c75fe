"""The TOML file of ``sweep fit``: the data files, the free parameters, their bounds and starts.

    preset = "sample2"            # and/or a [params] table (fixed values and starts), as in a scene file
    free = ["A", "m1", "m2"]
    per_data_set = false          # true: each data file its own parameter set
    poor = 0.25                   # relative half-width of a 95 % interval above which "poorly constrained"
    rtol = 1e-6                   # engine accuracy of the least squares and profiles (global stage: global_rtol)
    search = "global"             # or "local": the least squares from the start, no global grid (sweep.fit)
    g = 1e4                       # records: the machine's g = N/M [m/s^2] (default: none, docs/fit.md)
    [bounds]
    A = [0.001, 0.05]
    [start]
    m2 = 0.002
    [[data]]
    file = "curve_1um.csv"        # relative to this TOML file; CSV or netCDF (sweep.fit.read)
    sample = "s2"                 # optional: data sets with the same sample share parameters
    [[data]]
    file = "p4966.txt"            # a laboratory record (sweep.fit.records.read_record) and its options:
    columns = {time = "Zeit"}     # columns, units, steps, k, noise, detrend, t_start, t_end, g
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..scene.scene import _params_from, _read_toml
from .read import RECORD_OPTIONS, read_data

__all__ = ["FIT_KEYS", "load_fit_config"]

FIT_KEYS = {"preset", "params", "free", "per_data_set", "poor", "rtol", "global_rtol", "profiles", "search", "bounds",
            "start", "data", "g"}


def load_fit_config(path: str | Path) -> dict[str, Any]:
    """Keyword arguments of :func:`sweep.fit` from a fit TOML file (data files read, units converted)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"fit file {str(path)!r} does not exist")
    cfg = _read_toml(str(path))
    unknown = set(cfg) - FIT_KEYS
    if unknown:
        raise InputError(f"unknown key(s) {sorted(unknown)} in fit file; allowed: {sorted(FIT_KEYS)}")
    entries = cfg.get("data")
    if not isinstance(entries, list) or not entries:
        raise InputError("fit file needs at least one [[data]] table with file = \"...\"")
    data = []
    for i, entry in enumerate(entries):
        if not isinstance(entry, Mapping) or "file" not in entry:
            raise InputError(f"[[data]] number {i + 1} needs file = \"...\"")
        extra = set(entry) - {"file", "sample", "name", *RECORD_OPTIONS}
        if extra:
            raise InputError(f"[[data]] number {i + 1} has unknown key(s) {sorted(extra)}; allowed: file, sample, "
                             f"name and a record's {', '.join(RECORD_OPTIONS)}")
        data.append(read_data(path.parent / entry["file"], sample=entry.get("sample"), name=entry.get("name"),
                              record={k: entry[k] for k in RECORD_OPTIONS if k in entry}))
    kwargs = {k: cfg[k] for k in ("free", "per_data_set", "poor", "rtol", "global_rtol", "profiles", "search",
                                  "bounds", "start", "g") if k in cfg}
    return {"data": data, "params": _params_from(cfg) if ("preset" in cfg or "params" in cfg) else "sample2",
            **kwargs}
