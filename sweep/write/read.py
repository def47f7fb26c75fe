"""Which of sweep's own files a path holds, read with a one-line error for anything else.

sweep writes these kinds of netCDF file: one per protocol (a stop sweep of ``sweep run``, ``sweep reproduce``:
variable ``xi_inf``; a driven sweep: ``regime``; a load history: ``mu_end``), a Hopf line (``sweep hopf``:
``K_over_M_c`` and ``bifurcation``) and a fit (``sweep fit``: attribute ``sweep_kind = "fit"``, ``fit_status``).
Every command that reads a file goes through :func:`read_sweep_file`, so a missing file, a file that is not netCDF
and a netCDF file of some other program are each refused with an :class:`~sweep.errors.InputError` naming the path.
"""

from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

from .. import protocols
from ..errors import InputError

__all__ = ["KINDS", "file_kind", "open_sweep_file", "read_sweep_file"]

KINDS = (*protocols.names(), "hopf", "fit")
"""The kinds of sweep's files: one per protocol (sweep/protocols/), the Hopf line of ``sweep hopf`` and the fit of
``sweep fit`` (sweep.fit)."""


def file_kind(ds: xr.Dataset) -> str:
    """"hopf" (sweep.locate_hopf), "fit" (sweep.fit) or the protocol's name (sweep.run_sweep: "stop", "driven",
    "history") from the variables of the file; :class:`InputError` for a Dataset that is none of them."""
    if "K_over_M_c" in ds.data_vars and "bifurcation" in ds:
        return "hopf"
    if ds.attrs.get("sweep_kind") == "fit" and "fit_status" in ds.data_vars:
        return "fit"
    protocol = protocols.file_protocol(ds)
    if protocol is not None:
        return protocol.name
    raise InputError("not a sweep file: expected xi_inf (stop sweep), regime (driven sweep), mu_end (load history), "
                     f"K_over_M_c (Hopf line) or fit_status (fit); found {sorted(ds.data_vars)}")


def open_sweep_file(path: str | os.PathLike, load: bool = True) -> xr.Dataset:
    """The Dataset of a file written by sweep (``sweep.open``): read whole into memory and the file closed
    (default), or opened lazily with ``load=False`` (each variable read when used; for files too large to hold
    whole). Raises FileNotFoundError for a missing path and :class:`InputError` (one line, naming the path) for a
    file that is not netCDF or a netCDF file that sweep did not write."""
    from .netcdf import open_dataset

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such file: {str(path)!r}" if not path.exists() else f"{str(path)!r} is not a file")
    try:
        ds = open_dataset(path, load=load)
    except (OSError, ValueError, TypeError) as exc:  # netCDF4's "Unknown file format", HDF errors, xarray decoding
        raise InputError(f"{str(path)!r} is not a netCDF file written by sweep ({_first_line(exc)})") from None
    try:
        file_kind(ds)
    except InputError as exc:
        ds.close()
        raise InputError(f"{str(path)!r} is {exc}") from None
    return ds


def read_sweep_file(path: str | os.PathLike, load: bool = True) -> tuple[xr.Dataset, str]:
    """(Dataset, kind) of a file written by sweep (kind as :func:`file_kind`; a single point saved as 0-d gets
    its two axes of length 1), opened as :func:`open_sweep_file`, a missing path an :class:`InputError` too (the
    command line's one-line message)."""
    try:
        ds = open_sweep_file(path, load=load)
    except FileNotFoundError as exc:
        raise InputError(str(exc)) from None
    kind = file_kind(ds)
    # one point (sweep.solve_point) saved as 0-d; a grid's first axis is K_over_M or the laboratory's k
    if kind not in ("hopf", "fit") and not any({first, "V"} <= set(ds.dims) for first in ("K_over_M", "k")):
        ds = ds.expand_dims(("K_over_M", "V"))
    return ds, kind


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}"
