"""netCDF4 writing and reading of sweep Datasets."""

from __future__ import annotations

import errno
import os
import threading
import zlib
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import xarray as xr

from .targets import check_targets, free_bytes, remove_quietly, write_failed
from .writer import FlatArrays

__all__ = ["NetCDFWriter", "open_dataset", "save", "write"]

COMPRESSION = {"zlib": True, "complevel": 1}
"""Filter of a variable that compresses (:func:`compresses`): level 1, because the variables that compress at all
(status codes, model flags, step counts, fill values) shrink 20-250x at level 1 already (measured on the 1e6-point
default grid: level 4 wrote the same 49 MB in 1.50 s against 1.22 s)."""
PROBE_BYTES = 2**18
"""Bytes of a variable compressed to decide whether it is stored compressed (~1 ms a variable)."""
WORTH_RATIO = 0.8
"""A variable is stored compressed where zlib shrinks its probe below this fraction. Full-precision float64 results
(xi_inf, the error estimates...) shrink to only ~0.95 at 240 ms a million values: on the 1e6-point default grid,
compressing them made the file 49 MB instead of 79 MB at 1.2 s instead of 0.16 s of writing."""
GRID = ("K_over_M", "V")
"""The first dims of a sweep's grid (then its extra axes, scene.EXTRA_AXES, where it has them); its points are
numbered flat in C order (i_K n_V + i_V in 2-D)."""
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

    ``path`` is checked first (sweep/write/targets.py): an existing file is replaced only with ``overwrite=True``; a
    folder
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
    encoding = {name: compression(var) for name, var in ds.data_vars.items()}
    encoding.update({name: {"_FillValue": None} for name in ds.coords})
    for name, var in ds.data_vars.items():
        if var.dtype.kind in "iu":
            encoding[name]["_FillValue"] = None
    tmp = path.with_name(path.name + ".part")
    try:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
        if blocks is not None:
            _append_blocks(tmp, blocks, _grid_dims(ds))
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


def compresses(var: xr.Variable | xr.DataArray) -> bool:
    """Whether zlib pays for ``var``: its leading ~PROBE_BYTES (whole slices along its first dim; only those are
    read from a lazily opened file) shrink below WORTH_RATIO at COMPRESSION's level. So every variable gets the
    cheapest storage that keeps its bytes: flags and counts compress, full-precision float64 results barely do."""
    if var.size == 0:
        return False
    row = int(np.prod(var.shape[1:])) * var.dtype.itemsize if var.ndim else var.dtype.itemsize
    head = var[:max(1, PROBE_BYTES // max(1, row))] if var.ndim else var
    probe = np.ascontiguousarray(head.values).tobytes()
    return len(zlib.compress(probe, COMPRESSION["complevel"])) < WORTH_RATIO * len(probe)


def compression(var: xr.Variable | xr.DataArray) -> dict:
    """The netCDF encoding of ``var``'s filter: COMPRESSION where it :func:`compresses`, else none (each variable's
    filters in the file say which)."""
    return dict(COMPRESSION) if compresses(var) else {}


def _grid_dims(ds: xr.Dataset) -> tuple[str, ...]:
    """The grid dims of a sweep Dataset: (K_over_M, V) and its extra axes, in the order of its variables."""
    from ..scene.scene import EXTRA_AXES

    return GRID + tuple(d for d in EXTRA_AXES if d in ds.dims)


def _append_blocks(path: Path, blocks: Iterable[tuple[int, dict[str, xr.Variable]]], grid: tuple[str, ...]) -> None:
    """Write ``blocks`` (see :func:`save`) into the grid variables (dims ``grid``) of the netCDF file at ``path``."""
    import netCDF4

    with netCDF4.Dataset(path, "a") as nc:
        shape = tuple(nc.dimensions[d].size for d in grid)
        expected = 0
        for start, variables in blocks:
            if start != expected:
                raise ValueError(f"blocks must cover consecutive points: expected point {expected}, got {start}")
            for name, var in variables.items():
                if name not in nc.variables:
                    fill = np.nan if var.dtype.kind == "f" else None
                    chunks = _row_chunks(shape + var.shape[1:], var.dtype.itemsize, len(grid))
                    created = nc.createVariable(name, var.dtype, grid + var.dims[1:], fill_value=fill,
                                                chunksizes=chunks, **compression(var))
                    nbytes = int(np.prod(chunks)) * var.dtype.itemsize
                    created.set_var_chunk_cache(size=BLOCK_CACHE_CHUNKS * nbytes, nelems=101,  # hash slots: a prime
                                              preemption=1.0)  # evict the chunks a block has completed first
                    created.setncatts(var.attrs)
                _write_flat(nc.variables[name], start, np.asarray(var.values), shape)
            expected = start + next(iter(variables.values())).shape[0]


def _row_chunks(shape: tuple[int, ...], itemsize: int, n_grid: int = 2) -> tuple[int, ...]:
    """HDF5 chunk shape for a grid variable (the first ``n_grid`` dims of ``shape`` its grid) written in blocks of
    consecutive points: from the last grid dim outwards, whole extents (all trailing values) by the
    ~BLOCK_CHUNK_BYTES, then part of the next dim, 1 along the dims before it, so that a block completes its chunks
    one after the other (in 2-D: whole rows of all V, or part of one row where a row alone is larger)."""
    grid, trailing = shape[:n_grid], shape[n_grid:]
    size = int(np.prod(trailing)) * itemsize
    chunks = [1] * n_grid
    for d in range(n_grid - 1, -1, -1):
        chunks[d] = min(grid[d], max(1, BLOCK_CHUNK_BYTES // size))
        if chunks[d] < grid[d]:
            break
        size *= grid[d]
    return tuple(chunks) + tuple(trailing)


def _write_flat(var, start: int, values: np.ndarray, shape: tuple[int, ...]) -> None:
    """values[j] into the grid variable ``var`` (grid of ``shape``) at flat point start + j: whole rows of the grid
    (all points of the dims after the first) in one write, the partial rows at either end in one each (in 2-D) or
    through the sub-grid of the row."""
    _write_range(var, (), tuple(shape), start, values)


def _write_range(var, prefix: tuple[int, ...], shape: tuple[int, ...], start: int, values: np.ndarray) -> None:
    """:func:`_write_flat` into the sub-grid ``var[prefix]`` of shape ``shape``."""
    row = int(np.prod(shape[1:]))
    i, stop = start, start + values.shape[0]
    while i < stop:
        k, r = divmod(i, row)
        if r == 0 and stop - i >= row:
            rows = (stop - i) // row
            var[prefix + (slice(k, k + rows),)] = values[i - start:i - start + rows * row].reshape(
                (rows,) + shape[1:] + values.shape[1:])
            i += rows * row
        else:
            end = min(stop, (k + 1) * row)
            _write_range(var, prefix + (k,), shape[1:], r, values[i - start:end - start])
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


class NetCDFWriter(FlatArrays):
    """The netCDF file of a run, a writer of its chunk loop (sweep/write/writer.py): the chunks consolidated into
    per-point arrays as they are put (:class:`FlatArrays`; ``skip``: the arrays a journal keeps, written block by
    block), and the Dataset built from them written whole by :meth:`write` (to ``<path>.part``, renamed into
    place)."""

    def __init__(self, path: str | os.PathLike, n: int, skip: Iterable[str] = ()) -> None:
        super().__init__(n, skip)
        self.path = Path(path)

    def write(self, ds: xr.Dataset, blocks=None, during: Callable[[xr.Dataset], None] | None = None,
              written: Callable[[], None] = lambda: None) -> None:
        """The run's Dataset ``ds`` (its protocol's schema over the arrays put here) into the file, with the
        ``blocks`` kept elsewhere (:func:`save`), then ``written()`` once the file is in place; with ``during``, the
        write runs in a helper thread while during(ds) runs in this one. The write is waited for even when ``during``
        raises (Ctrl-C while drawing), so the file is whole or absent afterwards; the write's error is raised first
        (OSError: the caller's OutputError), then during's."""
        if during is None:
            write(ds, self.path, blocks=blocks)
            written()
            return
        failed: list[BaseException] = []

        def target() -> None:
            try:
                write(ds, self.path, blocks=blocks)  # (the module's function: a fault a test injects there applies)
            except BaseException as exc:  # noqa: BLE001 (raised in the caller's thread below)
                failed.append(exc)

        thread = threading.Thread(target=target, name="sweep-netcdf")
        thread.start()
        try:
            during(ds)
        finally:
            thread.join()
            if failed:
                raise failed[0]
            written()
