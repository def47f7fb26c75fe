"""Fitting the friction parameters to measured stop transients and relaxed slips (docs/fit.md).

``sweep.fit(data, free=..., ...)`` runs a fit (:func:`sweep.fit.core.fit`); the package itself is callable so that
``sweep.fit`` is both that function and the home of its parts: :class:`Curve` and :class:`RelaxedSlips` (the data),
:func:`read_data` (CSV / netCDF files with units), :func:`save_fit`. The forward model is the sweep engine
(:mod:`sweep.fit.forward`): every parameter set a fit needs at one moment (all curves, all finite-difference
perturbations, all profile points) is one flat batch of points.
"""

from __future__ import annotations

import sys
import types

from .core import fit
from .data import Curve, RelaxedSlips
from .result import save_fit

__all__ = ["Curve", "RelaxedSlips", "fit", "save_fit"]


class _CallableModule(types.ModuleType):
    """``sweep.fit(...)`` calls :func:`sweep.fit.core.fit` (same arguments)."""

    def __call__(self, *args, **kwargs):
        return fit(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
