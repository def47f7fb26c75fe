"""netCDF4 writing and reading of sweep Datasets."""

from __future__ import annotations

import errno
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import xarray as xr

from .outputs import check_targets, free_bytes, remove_quietly, write_failed

__all__ = ["save", "open_dataset", "write"]

COMPRESSION = {"zlib": True, "complevel": 4}
GRID = ("K_over_M", "V")
"""The dims of a sweep's grid; its points are numbered flat in C order (i_K n_V + i_V)."""
BLOCK_CHUNK_BYTES = 2**20
"""Target size of an HDF5 chunk of the variables written in blocks (HDF5 advises 10 KiB .. 1 MiB)."""
BLOCK_CACHE_CHUNKS = 4
"""HDF5 chunk cache of such a variable, in chunks: a block fills its chunks in order, so a few suffice (the default
cache, 64 MiB a variable, held every chunk being written: 166 MiB for a 2e5-point trajectory sweep)."""
FULL_DISK_BYTES = 16 * 2**20
"""A netCDF write that fails with less than this free is taken for a full disk (an HDF5 chunk is ~1 MiB)."""


def save(ds: xr.Dataset, path: str | os.PathLike,
         blocks: Iterable[tuple[int, dict[str, xr.Variable]]] | None = None, overwrite: bool = False) -> Path:
    """Write ``ds`` to ``path`` as netCDF4 (zlib-compressed, CF-1.11 attributes as built by the engine).

    ``blocks``: variables too large to hold whole (the trajectories of a large sweep), written after ``ds`` one
    block at a time: (first flat point, {name: Variable with dims ("point", ...)}) over consecutive points of the
    grid, in ascending order; the first block defines each variable (dtype, trailing dims, attributes).

    ``path`` is checked first (sweep/outputs.py): an existing file is replaced only with ``overwrite=True``; a folder
    or an unwritable place is an :class:`~sweep.errors.InputError`. The file is written beside its destination and
    renamed into place, so an interrupted write never leaves a truncated file under the final name; a write that
    fails (disk full...) is an :class:`~sweep.errors.OutputError` naming the file. Returns the path.
    """
    path = Path(path)
    check_targets({"data": path}, overwrite=overwrite)
    try:
        return write(ds, path, blocks)
    except OSError as exc:
        raise write_failed(exc, path) from None


def write(ds: xr.Dataset, path: str | os.PathLike,
          blocks: Iterable[tuple[int, dict[str, xr.Variable]]] | None = None) -> Path:
    """:func:`save` without its checks, for a caller that made them before its work (run_sweep): the file written
    under ``<path>.part`` and renamed into place; the ``.part`` removed if anything fails, and an error of the netCDF
    library turned into an OSError: ENOSPC where the disk is nearly full (HDF5 then says "HDF error", or EACCES)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    encoding = {name: dict(COMPRESSION) for name in ds.data_vars}
    encoding.update({name: {"_FillValue": None} for name in ds.coords})
    for name, var in ds.data_vars.items():
        if var.dtype.kind in "iu":
            encoding[name]["_FillValue"] = None
    tmp = path.with_name(path.name + ".part")
    try:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
        if blocks is not None:
            _append_blocks(tmp, blocks, ds.sizes[GRID[1]])
        os.replace(tmp, path)
    except BaseException as exc:
        full = free_bytes(path.parent) < FULL_DISK_BYTES if path.parent.is_dir() else False  # before .part goes
        remove_quietly([tmp])
        library = isinstance(exc, RuntimeError) and str(exc).startswith("NetCDF")
        if full and (library or isinstance(exc, PermissionError)):
            # on a full disk HDF5 says "HDF error", or fails to close the file with EACCES (measured on a tmpfs)
            raise OSError(errno.ENOSPC, f"No space left on device; the netCDF library said: {exc}") from exc
        if library:
            raise OSError(errno.EIO, f"netCDF library: {exc}") from exc
        raise
    return path


def _append_blocks(path: Path, blocks: Iterable[tuple[int, dict[str, xr.Variable]]], n_v: int) -> None:
    """Write ``blocks`` (see :func:`save`) into the grid variables of the netCDF file at ``path``."""
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:
        expected = 0
        for start, variables in blocks:
            if start != expected:
                raise ValueError(f"blocks must cover consecutive points: expected point {expected}, got {start}")
            for name, var in variables.items():
                if name not in nc.variables:
                    fill = np.nan if var.dtype.kind == "f" else None
                    chunks = _row_chunks((nc.dimensions[GRID[0]].size, n_v) + var.shape[1:], var.dtype.itemsize)
                    created = nc.createVariable(name, var.dtype, GRID + var.dims[1:], fill_value=fill,
                                                chunksizes=chunks, **COMPRESSION)
                    nbytes = int(np.prod(chunks)) * var.dtype.itemsize
                    created.set_var_chunk_cache(size=BLOCK_CACHE_CHUNKS * nbytes, nelems=101,  # hash slots: a prime
                                              preemption=1.0)  # evict the chunks a block has completed first
                    created.setncatts(var.attrs)
                _write_flat(nc.variables[name], start, np.asarray(var.values), n_v)
            expected = start + next(iter(variables.values())).shape[0]


def _row_chunks(shape: tuple[int, ...], itemsize: int) -> tuple[int, ...]:
    """HDF5 chunk shape for a grid variable written in blocks of consecutive points: whole rows of the grid (all V,
    all trailing values) by the ~BLOCK_CHUNK_BYTES, or part of one row where a row alone is larger, so that a block
    completes its chunks one after the other."""
    n_k, n_v, trailing = shape[0], shape[1], shape[2:]
    per_point = int(np.prod(trailing)) * itemsize
    along_v = min(n_v, max(1, BLOCK_CHUNK_BYTES // per_point))
    rows = min(n_k, max(1, BLOCK_CHUNK_BYTES // (along_v * per_point))) if along_v == n_v else 1
    return (rows, along_v) + tuple(trailing)


def _write_flat(var, start: int, values: np.ndarray, n_v: int) -> None:
    """values[j] into the grid variable ``var`` at flat point start + j: whole rows of the grid in one write, the
    partial rows at either end in one each."""
    i, stop = start, start + values.shape[0]
    while i < stop:
        k, v = divmod(i, n_v)
        if v == 0 and stop - i >= n_v:
            rows = (stop - i) // n_v
            var[k:k + rows] = values[i - start:i - start + rows * n_v].reshape((rows, n_v) + values.shape[1:])
            i += rows * n_v
        else:
            end = min(stop, (k + 1) * n_v)
            var[k, v:v + end - i] = values[i - start:end - start]
            i = end


def open_dataset(path: str | os.PathLike, load: bool = True) -> xr.Dataset:
    """Read a file written by :func:`save`: fully loaded into memory and the file closed, or with ``load=False``
    opened lazily (each variable read when used; for files too large to hold whole)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no sweep file at {str(path)!r}")
    if not load:
        return xr.open_dataset(path, engine="netcdf4")
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()
