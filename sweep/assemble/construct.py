"""A Dataset from variables that agree by construction, without xarray's merge.

``xr.Dataset(data, coords=coords, attrs=attrs)`` checks that the variables' sizes agree, aligns them, copies each one
and builds an index for each dimension coordinate: ~0.3 ms for the ~20 variables of a sweep's Dataset, up to
~0.7 ms right after the kernels (the caches are cold then), a tenth of ``run_sweep`` on a grid of a few thousand
points. The sweep's variables are made for one grid (sweep/assemble/dataset.py), so only the indexes are needed:
:func:`assemble` builds those and hands the variables to xarray's own direct constructor.

That constructor is private (``Dataset._construct_direct``), so it is used only where it gives what the public one
gives: once per process, on a small example, the two results are compared (``identical``); anything else (an
xarray without it, another signature, another result) and every Dataset is built by the public constructor.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

import numpy as np
import xarray as xr

__all__ = ["assemble"]


def assemble(data: Mapping[str, xr.Variable], coords: Mapping[str, xr.Variable], attrs: Mapping[str, object]
             ) -> xr.Dataset:
    """``xr.Dataset(data, coords=coords, attrs=attrs)`` for variables whose sizes agree (each dimension has one
    size across them; the caller builds them so), faster (module docstring)."""
    if _direct_is_identical():
        try:
            return _direct(data, coords, attrs)
        except (TypeError, ValueError):  # sizes that disagree: the public constructor says where
            pass
    return xr.Dataset(dict(data), coords=dict(coords), attrs=dict(attrs))


def _direct(data: Mapping[str, xr.Variable], coords: Mapping[str, xr.Variable], attrs: Mapping[str, object]
            ) -> xr.Dataset:
    variables = {**data, **coords}  # the public constructor's order (the file's order of variables)
    if len(variables) != len(coords) + len(data):
        raise ValueError("a name is both a coordinate and a data variable")
    sizes: dict[str, int] = {}
    for var in variables.values():
        for dim, n in zip(var.dims, var.shape):
            if sizes.setdefault(dim, n) != n:
                raise ValueError(f"dimension {dim!r} has sizes {sizes[dim]} and {n}")
    indexes = {}
    for name, var in coords.items():
        if var.dims == (name,):  # a dimension coordinate: indexed, as the public constructor does
            index = xr.indexes.PandasIndex.from_variables({name: var}, options={})
            indexes[name] = index
            variables[name] = index.create_variables({name: var})[name]
    return xr.Dataset._construct_direct(variables, set(coords), sizes, dict(attrs), indexes)


@functools.cache
def _direct_is_identical() -> bool:
    """Whether :func:`_direct` gives what the public constructor gives, on an example with the kinds of variable a
    sweep's Dataset has (two indexed axes, a 1-D coordinate on one of them, a 2-D and a 3-D variable, attributes)."""
    km, v, tau = np.array([1e3, 1e4]), np.array([1e-6, 1e-5, 1e-4]), np.array([0.5])
    coords = {"K_over_M": xr.Variable("K_over_M", km, {"units": "s-2"}), "V": xr.Variable("V", v, {"units": "m s-1"}),
              "chi": xr.Variable("K_over_M", km * 2.0, {"units": "1"}), "tau": xr.Variable("tau", tau)}
    data = {"xi_inf": xr.Variable(("K_over_M", "V"), np.arange(6.0).reshape(2, 3), {"units": "1"}),
            "status": xr.Variable(("K_over_M", "V"), np.zeros((2, 3), np.int8), {"flag_values": np.arange(2)}),
            "xi": xr.Variable(("K_over_M", "V", "tau"), np.ones((2, 3, 1)))}
    attrs = {"title": "probe", "n": 1.0}
    try:
        fast = _direct(data, coords, attrs)
    except Exception:  # noqa: BLE001 (any failure of a private API: the public constructor is used instead)
        return False
    public = xr.Dataset(data, coords=coords, attrs=attrs)
    return (fast.identical(public) and list(fast.variables) == list(public.variables)
            and set(fast.xindexes) == set(public.xindexes) and fast.sizes == public.sizes)
