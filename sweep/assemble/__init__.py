"""Flat per-point arrays -> a self-describing CF xarray.Dataset (numpy below, xarray here)."""

from __future__ import annotations

from .._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {"assemble": "construct"}, fallback="construct")
__all__ = ["assemble"]
