"""The output contract: names, units, flags, attributes, netCDF round trip, CF-1.11 compliance."""

import json
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import sweep


@pytest.fixture(scope="module")
def small_ds():
    scene = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, 7),
                        V=np.logspace(-7, -4, 5), rtol=1e-5,
                        observables=("xi_inf", "trajectory", "slip_at", "t50", "t90"),
                        trajectory_tau=(1e-2, 1e4, 9), t_obs=(0.0, 0.5, 5.0))
    return sweep.run_sweep(scene)


def test_dims_coords_and_units(small_ds):
    ds = small_ds
    assert ds["xi_inf"].dims == ("K_over_M", "V")
    assert ds["xi"].dims == ("K_over_M", "V", "tau") and ds["slip_at"].dims == ("K_over_M", "V", "t_obs")
    expected_units = {"K_over_M": "s-2", "V": "m s-1", "chi": "1", "chi_c": "1", "gamma": "1", "xi_inf": "1",
                      "slip_inf": "m", "stress_relaxation": "1", "t50": "s", "t90": "s", "slip_at": "m",
                      "tau": "1", "t_obs": "s", "xi": "1", "psi": "1"}
    for name, units in expected_units.items():
        assert ds[name].attrs["units"] == units, name
    for name in list(ds.variables):
        assert ds[name].attrs.get("long_name"), f"{name} has no long_name"
    assert ds["chi"].dims == ("K_over_M",) and ds["chi_c"].dims == ("V",) and ds["gamma"].dims == ("V",)


def test_derived_variables_are_consistent(small_ds):
    ds, p = small_ds, sweep.presets["sample2"]
    np.testing.assert_allclose(ds["slip_inf"], p.D0 * ds["xi_inf"])
    np.testing.assert_allclose(ds["stress_relaxation"], ds["chi"] * ds["xi_inf"])
    # chi_c is mu1 where mu1 > 0 and NaN (no Hopf line) elsewhere; stable iff chi > chi_c
    mu1 = p.m1 - 2 * p.m2 * np.log(ds["V"].values / p.V0)
    np.testing.assert_allclose(ds["chi_c"].values, np.where(mu1 > 0, mu1, np.nan))
    stable = ds["chi"].values[:, None] > np.where(mu1 > 0, mu1, -np.inf)[None, :]
    np.testing.assert_array_equal(ds["stable"].values == 1, stable)
    assert (~stable).any() and stable.any(), "the grid should cross the Hopf line"
    # t50 < t90, slip at t=0 is zero, slip_at increases with time and stays below slip_inf
    assert np.all(ds["t50"] < ds["t90"])
    np.testing.assert_array_equal(ds["slip_at"].isel(t_obs=0), 0.0)
    assert np.all(ds["slip_at"].diff("t_obs") > 0)
    assert np.all(ds["slip_at"] < ds["slip_inf"])


def test_status_flags(small_ds):
    status = small_ds["status"]
    meanings = status.attrs["flag_meanings"].split()
    assert meanings[: len(sweep.Status)] == [s.name.lower() for s in sweep.Status]
    np.testing.assert_array_equal(status.attrs["flag_values"], [s.value for s in sweep.Status])
    assert np.all(status.values == sweep.Status.OK)
    assert np.all(np.isfinite(small_ds["xi_inf"]))


def test_global_attributes(small_ds):
    attrs = small_ds.attrs
    for key in ("Conventions", "title", "source", "history", "references", "scene", "plan_hash", "plan_step_rule"):
        assert attrs.get(key), key
    assert attrs["Conventions"] == "CF-1.11"
    assert "numba" in attrs["source"] and "doi:10.1051/jp1:1996113" in attrs["references"]
    scene = tomllib.loads(attrs["scene"])
    assert scene["params"]["A"] == sweep.presets["sample2"].A
    np.testing.assert_array_equal(scene["K_over_M"]["values"], small_ds["K_over_M"].values)


def test_netcdf_round_trip(small_ds, tmp_path):
    path = sweep.save(small_ds, tmp_path / "out.nc")
    back = sweep.open(path)
    xr.testing.assert_equal(back, small_ds)
    for name in small_ds.variables:
        for key in ("units", "long_name", "flag_meanings"):
            assert back[name].attrs.get(key) == small_ds[name].attrs.get(key), (name, key)
    for key, value in small_ds.attrs.items():
        assert back.attrs[key] == value, key
    assert back["status"].dtype == np.int8


def test_only_the_variables_that_compress_are_stored_compressed(tmp_path):
    """zlib where it pays (sweep/write/netcdf.py: a flag field of one value, a count field), none for full-precision
    float64
    (random mantissas shrink to ~0.95 at ~0.24 s a million values); the values come back either way."""
    import netCDF4

    rng = np.random.default_rng(5)
    grid = {"K_over_M": np.logspace(3, 6, 300), "V": np.logspace(-7, -4, 200)}
    ds = xr.Dataset({"flags": (("K_over_M", "V"), np.zeros((300, 200), np.int8)),
                     "steps": (("K_over_M", "V"), rng.integers(10, 40, (300, 200)).astype(np.int32)),
                     "value": (("K_over_M", "V"), rng.lognormal(size=(300, 200)))}, coords=grid)
    path = sweep.save(ds, tmp_path / "c.nc")
    with netCDF4.Dataset(path) as nc:
        zlib = {name: nc[name].filters()["zlib"] for name in ds.data_vars}
    assert zlib == {"flags": True, "steps": True, "value": False}
    xr.testing.assert_identical(xr.load_dataset(path), ds)


def test_cf_compliance(small_ds, tmp_path):
    beside_python = Path(sys.executable).with_name("compliance-checker")
    checker = str(beside_python) if beside_python.exists() else shutil.which("compliance-checker")
    assert checker, "compliance-checker is part of the test extras: pip install '.[test]'"
    path = sweep.save(small_ds, tmp_path / "cf.nc")
    report = tmp_path / "report.json"
    proc = subprocess.run([checker, "--test=cf:1.11", "--format=json", f"--output={report}", str(path)],
                          capture_output=True, text=True, timeout=300)
    results = json.loads(report.read_text())
    cf = next(iter(results.values()))
    checks = [c for level in ("high_priorities", "medium_priorities", "low_priorities") for c in cf.get(level, [])]
    failed = [c for c in checks if c["value"][0] < c["value"][1]]
    assert checks and not failed, failed
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
