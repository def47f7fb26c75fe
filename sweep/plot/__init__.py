"""Pictures of sweep's files: maps, curves, slices of extra axes, the paper's figures."""

from __future__ import annotations

from .._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "file_kind": "files",
        "plot_file": "files",
        "plot_hopf": "files",
        "plot_landscape": "files",
        "plot_regimes": "files",
        "plot_trajectories": "files",
    },
    fallback="files",
)
__all__ = ["file_kind", "plot_file", "plot_hopf", "plot_landscape", "plot_regimes", "plot_trajectories"]
