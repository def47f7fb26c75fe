"""Where results go: the writer interface, netCDF files, the checks of output paths, reading sweep's files."""

from __future__ import annotations

from .._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "save": "netcdf",
        "open_dataset": "netcdf",
        "read_sweep_file": "read",
        "open_sweep_file": "read",
        "file_kind": "read",
    },
)
__all__ = ["file_kind", "open_dataset", "open_sweep_file", "read_sweep_file", "save"]
