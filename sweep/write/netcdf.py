"""netCDF4 writing and reading of sweep Datasets."""

from __future__ import annotations

import contextlib
import errno
import os
import zlib
from pathlib import Path

import numpy as np
import xarray as xr

from .regions import Sink
from .targets import check_targets, free_bytes, remove_quietly, write_failed

__all__ = ["NetCDFRegions", "open_dataset", "save", "write"]

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
BLOCK_CACHE_CHUNKS = 1
"""HDF5 chunk cache of a variable written by region, in chunks: each block fills its own storage chunk whole, so one
suffices (the default cache, 64 MiB a variable, would hold chunks long written)."""
FLUSH_BYTES = 256 * 2**20
"""A run's file is flushed to disk every this many bytes written (NetCDFRegions): a 6.7 GB file flushed once, at the
end, kept its run waiting ~2 minutes for the disk after its chunks were done."""
FULL_DISK_BYTES = 16 * 2**20
"""A netCDF write that fails with less than this free is taken for a full disk (an HDF5 chunk is ~1 MiB)."""


def save(ds: xr.Dataset, path: str | os.PathLike, overwrite: bool = False) -> Path:
    """Write ``ds`` to ``path`` as netCDF4 (zlib-compressed, CF-1.11 attributes as built by the engine).

    ``path`` is checked first (sweep/write/targets.py): an existing file is replaced only with ``overwrite=True``; a
    folder
    or an unwritable place is an :class:`~sweep.errors.InputError`. The file is written beside its destination and
    renamed into place, so an interrupted write never leaves a truncated file under the final name; a write that
    fails (disk full...) is an :class:`~sweep.errors.OutputError` naming the file. Returns the path.
    """
    path = Path(path)
    check_targets({"data": path}, overwrite=overwrite)
    try:
        return write(ds, path)
    except OSError as exc:
        raise write_failed(exc, path) from None


def write(ds: xr.Dataset, path: str | os.PathLike) -> Path:
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
        with _library_errors(tmp):
            ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
        os.replace(tmp, path)
    except BaseException:
        remove_quietly([tmp])
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


class NetCDFRegions(Sink):
    """The netCDF file of a run, a sink of its blocks (sweep/write/regions.py): created under ``<path>.part`` with the
    grid's coordinates before the first block, each block written into its region of every variable (the variable
    created by the first block that has it: its dtype, trailing dims, attributes and filter; storage chunks the
    shape of a block, so each block fills its own), the global attributes added at the end, then closed, flushed to
    disk and renamed into place. The ``.part`` is not crash-safe (HDF5) and need not be: the run's journal holds the
    chunks, and a resumed run writes a new ``.part`` from them. Every FLUSH_BYTES written the file is flushed to disk
    (in the writer's thread, while the chunks compute), so that the final flush does not wait for gigabytes the
    system has buffered."""

    def __init__(self, path: str | os.PathLike, block: tuple[int, ...]) -> None:
        self.path = Path(path)
        self.part = self.path.with_name(self.path.name + ".part")
        self.block_shape = block
        self.nc = None
        self.unflushed = 0

    def start(self, scene, coords) -> None:
        import netCDF4

        self.dims = scene.dims
        self.path.parent.mkdir(parents=True, exist_ok=True)
        remove_quietly([self.part])
        template = xr.Dataset(coords=dict(coords))
        with _library_errors(self.part):
            template.to_netcdf(self.part, engine="netcdf4", format="NETCDF4",
                               encoding={name: {"_FillValue": None} for name in template.variables})
            self.nc = netCDF4.Dataset(self.part, "a")

    def put(self, block) -> None:
        with _library_errors(self.part):
            for name, var in block.variables.items():
                if name not in self.nc.variables:
                    self._create(name, var)
                self.nc.variables[name][block.slices] = var.values
                self.unflushed += var.nbytes
            if self.unflushed >= FLUSH_BYTES:
                self._flush()

    def _flush(self) -> None:
        """The file's buffers to the system, and the system's to disk."""
        self.nc.sync()
        fd = os.open(self.part, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        self.unflushed = 0

    def _create(self, name: str, var: xr.Variable) -> None:
        trailing = var.shape[len(self.dims):]
        chunks = self.block_shape + trailing
        fill = np.nan if var.dtype.kind == "f" else None
        created = self.nc.createVariable(name, var.dtype, var.dims, fill_value=fill, chunksizes=chunks,
                                         **compression(var))
        nbytes = int(np.prod(chunks)) * var.dtype.itemsize
        created.set_var_chunk_cache(size=BLOCK_CACHE_CHUNKS * nbytes, nelems=101,  # hash slots: a prime
                                    preemption=1.0)  # a block fills its chunks whole: evict them first
        created.setncatts(var.attrs)

    def close(self, attrs) -> None:
        with _library_errors(self.part):
            self.nc.setncatts({name: value for name, value in attrs.items()})
            self.nc.close()
            self.nc = None
            with open(self.part, "rb+") as f:
                os.fsync(f.fileno())
        os.replace(self.part, self.path)
        fd = os.open(self.path.parent, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)

    def abort(self) -> None:
        if self.nc is not None:
            try:
                self.nc.close()
            except Exception:  # noqa: BLE001 (a file already broken: it is removed below)
                pass
            self.nc = None
        remove_quietly([self.part])


@contextlib.contextmanager
def _library_errors(path: Path):
    """An error of the netCDF library while writing ``path`` as an OSError: ENOSPC where the disk is nearly full
    (HDF5 then says "HDF error", or EACCES), else EIO."""
    try:
        yield
    except (RuntimeError, PermissionError) as exc:
        full = free_bytes(path.parent) < FULL_DISK_BYTES if path.parent.is_dir() else False
        library = isinstance(exc, RuntimeError) and str(exc).startswith("NetCDF")
        if full and (library or isinstance(exc, PermissionError)):
            raise OSError(errno.ENOSPC, f"No space left on device; the netCDF library said: {exc}") from exc
        if library:
            raise OSError(errno.EIO, f"netCDF library: {exc}") from exc
        raise
