"""``sweep fit``: a TOML naming CSV data files with units -> netCDF + PNG; user mistakes are one line, exit 2."""

from __future__ import annotations

import numpy as np
import xarray as xr
from fit_reference import relaxed_slip, slip_curve

from sweep.cli import main

SAMPLE2 = dict(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)


def _write_curve(path, V, seed, units=True):
    t = np.logspace(-1, 3, 24)
    x = slip_curve(SAMPLE2, 2.8e5, V, t)
    s = 0.005 * relaxed_slip(SAMPLE2, 2.8e5, V)
    x = np.abs(x + s * np.random.default_rng(seed).standard_normal(t.size))
    head = f"# K_over_M = 2.8e5 s-2\n# V = {V * 1e6:g} um/s\n" + ("# t: s\n# x: um\n# noise: um\n" if units else "")
    rows = "".join(f"{float(a)!r},{float(b) * 1e6!r},{float(s) * 1e6!r}\n" for a, b in zip(t, x))
    path.write_text(head + "t,x,noise\n" + rows)


def test_fit_command_writes_netcdf_and_png(tmp_path, capsys):
    _write_curve(tmp_path / "c1.csv", 1e-6, 1)
    _write_curve(tmp_path / "c5.csv", 5e-6, 2)
    (tmp_path / "fit.toml").write_text('preset = "sample2"\nfree = ["A", "m1", "m2"]\n'
                                       '[[data]]\nfile = "c1.csv"\n[[data]]\nfile = "c5.csv"\n')
    out = tmp_path / "fit.nc"
    assert main(["fit", str(tmp_path / "fit.toml"), "-o", str(out)]) == 0
    assert out.is_file() and out.with_suffix(".png").is_file()
    with xr.open_dataset(out) as ds:
        assert ds.attrs["Conventions"] == "CF-1.11" and ds.attrs["sweep_kind"] == "fit"
        for name in ("A", "m1", "m2"):
            assert float(ds[f"{name}_lower"][0]) <= SAMPLE2[name] <= float(ds[f"{name}_upper"][0])
        assert ds["observed"].attrs["units"] == "m" and ds.sizes["datum"] == 48
        assert abs(float(ds["observed"][0]) / (slip_curve(SAMPLE2, 2.8e5, 1e-6, [0.1])[0]) - 1) < 0.05  # um -> m
    assert "A = " in capsys.readouterr().out


def test_missing_units_are_one_line_and_exit_2(tmp_path, capsys):
    _write_curve(tmp_path / "c1.csv", 1e-6, 1, units=False)
    (tmp_path / "fit.toml").write_text('preset = "sample2"\nfree = ["A"]\n[[data]]\nfile = "c1.csv"\n')
    assert main(["fit", str(tmp_path / "fit.toml"), "-o", str(tmp_path / "f.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "sweep: error:" in err and "column 't' has no unit" in err


def test_unknown_free_parameter_in_the_toml_is_one_line(tmp_path, capsys):
    _write_curve(tmp_path / "c1.csv", 1e-6, 1)
    (tmp_path / "fit.toml").write_text('preset = "sample2"\nfree = ["A", "mu"]\n[[data]]\nfile = "c1.csv"\n')
    assert main(["fit", str(tmp_path / "fit.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "free parameter 'mu' does not exist" in err
