"""The loadings a sweep applies, one folder each, and the catalogue that dispatches to them.

A protocol (:class:`sweep.protocols.base.Protocol`) owns what only it uses: its scene fields and their validation,
its plan, how a chunk of its points is computed, its output schema, its bytes per point, the kernel families it
compiles, its dry-run text and its picture. Everything outside this folder asks :func:`get` for the scene's
protocol and calls it; nothing there compares a protocol's name (tests/test_structure.py walks the syntax tree).

The catalogue is light: a protocol's module is imported on first use, so that a scene can be validated without
loading its kernels. What a protocol's plan must offer the machinery: ``n_points``, ``chunk_size``, ``take(rows)`` (a
chunk's share, for a dask worker), ``hash()`` (what a resume compares) and ``describe()`` (the file's plan_*
attributes); :class:`sweep.plan.Plan` is the stop and driven protocols' plan.
"""

from __future__ import annotations

import importlib
from types import MappingProxyType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import xarray as xr

    from .base import Protocol

__all__ = ["CATALOGUE", "file_protocol", "get", "names", "register"]

_CATALOGUE = {
    "stop": "sweep.protocols.stop.protocol",
    "driven": "sweep.protocols.driven.protocol",
    "history": "sweep.protocols.history.protocol",
}
CATALOGUE = MappingProxyType(_CATALOGUE)
"""Protocol name -> the module whose ``PROTOCOL`` implements it. A new protocol is one folder and one line here (or
a :func:`register` call, for a protocol that lives outside the package)."""


def register(name: str, module: str) -> None:
    """Add the protocol ``name``, implemented by ``PROTOCOL`` of the importable ``module`` (e.g. a protocol that
    lives in a user's package). The built-in names cannot be replaced."""
    if name in _CATALOGUE and _CATALOGUE[name] != module:
        raise ValueError(f"protocol {name!r} is already {_CATALOGUE[name]}")
    _CATALOGUE[name] = module


def names() -> tuple[str, ...]:
    """The names of the protocols, in the catalogue's order."""
    return tuple(CATALOGUE)


def get(name: str) -> Protocol:
    """The protocol called ``name`` (KeyError for an unknown one: the scene refuses those before asking)."""
    return importlib.import_module(CATALOGUE[name]).PROTOCOL


def file_protocol(ds: xr.Dataset) -> Protocol | None:
    """The protocol whose file ``ds`` is (by the variable that marks its files), None for any other Dataset."""
    for name in CATALOGUE:
        protocol = get(name)
        if protocol.marker in ds.data_vars:
            return protocol
    return None
