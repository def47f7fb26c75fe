"""netCDF4 writing and reading of sweep Datasets."""

from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

__all__ = ["save", "open_dataset"]


def save(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write ``ds`` to ``path`` as netCDF4 (zlib-compressed, CF-1.11 attributes as built by the engine).

    The file is written beside its destination and renamed into place, so an interrupted write never leaves
    a truncated file under the final name. Returns the path.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    encoding = {name: {"zlib": True, "complevel": 4} for name in ds.data_vars}
    encoding.update({name: {"_FillValue": None} for name in ds.coords})
    for name, var in ds.data_vars.items():
        if var.dtype.kind in "iu":
            encoding[name]["_FillValue"] = None
    tmp = path.with_name(path.name + ".part")
    ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
    os.replace(tmp, path)
    return path


def open_dataset(path: str | os.PathLike) -> xr.Dataset:
    """Read a file written by :func:`save` (fully loaded into memory, file closed)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no sweep file at {str(path)!r}")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()
