"""sweep.fit.read_data: netCDF (units in attributes) and CSV (units in a '#' header) in SI units; refusals in one
line naming the file and the variable. No engine run here (the fits from files are in tests/fit/test_fit_cli.py)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep.fit import Curve, RelaxedSlips, read_data

T_MS = np.array([100.0, 1e3, 1e4, 1e5])  # ms
X_UM = np.array([0.01, 0.05, 0.1, 0.12])  # um


def _curve_nc(path, drop_units=None):
    ds = xr.Dataset({"t": ("time", T_MS, {"units": "ms"}), "x": ("time", X_UM, {"units": "um"}),
                     "noise": ("time", np.full(4, 0.002), {"units": "um"}),
                     "K_over_M": ((), 2.8e5, {"units": "s-2"}), "V": ((), 1.0, {"units": "um/s"})},
                    attrs={"sample": "s2"})
    if drop_units:
        del ds[drop_units].attrs["units"]
    ds.to_netcdf(path)
    return path


def test_netcdf_curve_is_read_in_si_units(tmp_path):
    c = read_data(_curve_nc(tmp_path / "run7.nc"))
    assert isinstance(c, Curve)
    np.testing.assert_allclose(c.t, T_MS * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(c.x, X_UM * 1e-6, rtol=1e-15)
    np.testing.assert_allclose(c.noise, 2e-9, rtol=1e-15)
    assert (c.K_over_M, c.V, c.sample, c.name) == (2.8e5, 1e-6, "s2", "run7")


def test_netcdf_relaxed_slips_are_read_in_si_units(tmp_path):
    path = tmp_path / "fig3.nc"
    xr.Dataset({"K_over_M": ("point", [2e5, 4e5], {"units": "s-2"}), "V": ("point", [3.0, 10.0], {"units": "um/s"}),
                "dx_inf": ("point", [0.7, 0.4], {"units": "um"})}).to_netcdf(path)
    r = read_data(path, sample="s1", name="fig3a")
    assert isinstance(r, RelaxedSlips) and r.noise is None and (r.sample, r.name) == ("s1", "fig3a")
    np.testing.assert_allclose(r.K_over_M, [2e5, 4e5], rtol=1e-15)
    np.testing.assert_allclose(r.V, [3e-6, 1e-5], rtol=1e-15)
    np.testing.assert_allclose(r.dx_inf, [0.7e-6, 0.4e-6], rtol=1e-15)


def test_relaxed_slips_csv_is_read_in_si_units(tmp_path):
    path = tmp_path / "fig3.csv"
    path.write_text("# K_over_M: s-2\n# V: m s-1\n# dx_inf: nm\n# noise: nm\nK_over_M,V,dx_inf,noise\n"
                    "2e5,3e-6,700,7\n4e5,1e-5,400,4\n")
    r = read_data(path)
    assert isinstance(r, RelaxedSlips) and r.name == "fig3" and r.sample == "sample"
    np.testing.assert_allclose(r.dx_inf, [7e-7, 4e-7], rtol=1e-15)
    np.testing.assert_allclose(r.noise, [7e-9, 4e-9], rtol=1e-15)
    np.testing.assert_allclose(r.V, [3e-6, 1e-5], rtol=1e-15)


@pytest.mark.parametrize("variable", ["t", "x", "V"])
def test_netcdf_without_units_is_refused_naming_the_variable(tmp_path, variable):
    with pytest.raises(sweep.InputError) as exc:
        read_data(_curve_nc(tmp_path / "c.nc", drop_units=variable))
    msg = str(exc.value)
    assert "\n" not in msg and "c.nc" in msg and f"variable {variable!r} has no units" in msg


def test_a_netcdf_unit_that_is_not_understood_is_refused(tmp_path):
    path = tmp_path / "c.nc"
    xr.Dataset({"t": ("time", T_MS, {"units": "fortnights"}), "x": ("time", X_UM, {"units": "um"}),
                "K_over_M": ((), 2.8e5, {"units": "s-2"}), "V": ((), 1.0, {"units": "um/s"})}).to_netcdf(path)
    with pytest.raises(sweep.InputError, match="unit 'fortnights' of t is not understood"):
        read_data(path)


def test_a_file_that_is_not_netcdf_is_refused(tmp_path):
    path = tmp_path / "c.nc"
    path.write_text("t,x\n1,2\n")
    with pytest.raises(sweep.InputError, match="not a readable netCDF file") as exc:
        read_data(path)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("sep, decimal, bom, eol", [(";", ",", True, "\r\n"), ("\t", ".", False, "\n"),
                                                     (" ", ".", False, "\r\n"), ("  ", ",", True, "\n")])
def test_laboratory_csv_variants_are_read(tmp_path, sep, decimal, bom, eol):
    """Semicolons with decimal commas, tabs, blanks; a byte-order mark; CR LF; irregular times; a noisy slip a
    little below zero: the same curve in SI units."""
    t = np.array([0.1, 0.13, 0.9, 7.0, 7.5, 60.0])  # s, irregular
    x = np.array([-0.002, 0.004, 0.03, 0.08, 0.081, 0.11])  # um, the first noisy below zero
    fmt = (lambda v: repr(float(v)).replace(".", decimal))
    head = ["# K_over_M = 2.8e5 s-2", "# V = 1 um/s", "# t: s", "# x: um", "# noise: um", sep.join(["t", "x", "noise"])]
    rows = [sep.join([fmt(a), fmt(b), fmt(0.002)]) for a, b in zip(t, x)]
    path = tmp_path / "lab.csv"
    path.write_bytes(("\ufeff" if bom else "").encode() + eol.join(head + rows).encode() + eol.encode())
    c = read_data(path)
    np.testing.assert_allclose(c.t, t, rtol=1e-15)
    np.testing.assert_allclose(c.x, x * 1e-6, rtol=1e-15)
    np.testing.assert_allclose(c.noise, 2e-9, rtol=1e-15)
    assert (c.K_over_M, c.V) == (2.8e5, 1e-6)
