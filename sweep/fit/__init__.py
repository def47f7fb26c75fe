"""Fitting the friction parameters to measured stop transients and relaxed slips (docs/fit.md).

``sweep.fit(data, free=..., ...)`` runs a fit (:func:`sweep.fit.core.fit`); the package itself is callable so that
``sweep.fit`` is both that function and the home of its parts: :class:`Curve` and :class:`RelaxedSlips` (the data),
:func:`read_data` (CSV / netCDF files with units), :func:`save_fit`. The forward model is the sweep engine
(:mod:`sweep.fit.forward`): every parameter set a fit needs at one moment (all curves, all finite-difference
perturbations, all profile points) is one flat batch of points.

The names are imported on first use (as in :mod:`sweep`), so that ``sweep fit --help`` starts without numba.
"""

from __future__ import annotations

import importlib
import sys
import types

__all__ = ["Curve", "Record", "RelaxedSlips", "fit", "read_data", "read_record", "save_fit"]

_WHERE = {"fit": "core", "Curve": "data", "RelaxedSlips": "data", "read_data": "read", "save_fit": "result",
          "Record": "records", "read_record": "records"}


_SUBMODULES = ("checks", "cli", "config", "core", "data", "event_fit", "events", "forward", "globalstage", "levenberg",
               "local", "outcome", "plot", "problem", "profiles", "read", "record_forward", "records", "result",
               "segments", "space", "stack", "uncertainty", "units", "verdict")
"""The parts of the package, importable as attributes (``sweep.fit.core``) without an explicit import first."""


def __getattr__(name: str):
    if name in _SUBMODULES:  # the import binds the submodule as an attribute of this package
        return importlib.import_module(f".{name}", __name__)
    if name not in _WHERE:
        raise AttributeError(f"module 'sweep.fit' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    globals()[name] = value
    return value


class _CallableModule(types.ModuleType):
    """``sweep.fit(...)`` calls :func:`sweep.fit.core.fit` (same arguments)."""

    def __call__(self, *args, **kwargs):
        from .core import fit

        return fit(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
