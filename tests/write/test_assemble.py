"""sweep/assemble/construct.py: a sweep's Dataset built without xarray's merge is the one the public constructor
builds, and
anything else falls back to the public constructor."""

import numpy as np
import pytest
import xarray as xr

import sweep
import sweep.assemble.construct as assemble_module
from sweep.assemble.construct import assemble


def public(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` built again by xarray's public constructor from its own variables."""
    return xr.Dataset({n: ds[n].variable for n in ds.data_vars}, coords={n: ds[n].variable for n in ds.coords},
                      attrs=ds.attrs)


def same(a: xr.Dataset, b: xr.Dataset) -> None:
    xr.testing.assert_identical(a, b)
    assert list(a.variables) == list(b.variables)  # the order of the variables in the file
    assert set(a.xindexes) == set(b.xindexes) and a.sizes == b.sizes
    for name in a.variables:
        assert type(a[name].variable) is type(b[name].variable), name  # IndexVariable for each axis


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["stop", "driven"])
def test_a_sweeps_dataset_is_the_public_constructors(kind):
    if kind == "stop":
        scene = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, 4),
                            V=np.logspace(-7, -4, 3), rtol=1e-4, observables=("xi_inf", "trajectory", "slip_at"),
                            trajectory_tau=(1e-2, 1e4, 5), t_obs=(0.5, 5.0))
    else:
        scene = sweep.Scene(protocol="driven", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 5, 3),
                            V=np.logspace(-6, -5, 2), rtol=1e-4)
    assert assemble_module._direct_is_identical()  # the fast path is the one under test here
    ds = sweep.run_sweep(scene, progress=False)
    same(ds, public(ds))
    ds.sel(K_over_M=scene.K_over_M[1], V=scene.V[0])  # the axes are indexed


def test_sizes_that_disagree_are_refused_as_by_xarray():
    coords = {"V": xr.Variable("V", [1.0, 2.0])}
    with pytest.raises(ValueError, match="conflicting sizes|dimension 'V'"):
        assemble({"x": xr.Variable("V", [1.0, 2.0, 3.0])}, coords, {})


def test_a_private_constructor_that_changed_is_not_used(monkeypatch):
    """The probe compares the two constructors: a direct constructor that gives another Dataset (here: without its
    attributes) is found out, and the public one builds every Dataset."""
    real = xr.Dataset._construct_direct

    def dropping_attrs(variables, coord_names, dims, attrs=None, indexes=None, *args, **kwargs):
        return real(variables, coord_names, dims, {}, indexes, *args, **kwargs)

    monkeypatch.setattr(xr.Dataset, "_construct_direct", dropping_attrs)
    monkeypatch.setattr(assemble_module, "_direct_is_identical", assemble_module._direct_is_identical.__wrapped__)
    assert not assemble_module._direct_is_identical()
    ds = assemble({"x": xr.Variable("V", [1.0, 2.0])}, {"V": xr.Variable("V", [1.0, 2.0])}, {"title": "t"})
    assert ds.attrs == {"title": "t"}
