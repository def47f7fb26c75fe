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


def test_fit_outputs_are_checked_before_any_work(tmp_path, capsys):
    """An existing output is replaced only with --overwrite, and the output may not be the fit file it reads: both
    refused in one line, exit 2, before the fit runs (the file on disk is untouched)."""
    _write_curve(tmp_path / "c1.csv", 1e-6, 1)
    config = tmp_path / "fit.toml"
    config.write_text('preset = "sample2"\nfree = ["A"]\n[[data]]\nfile = "c1.csv"\n')
    out = tmp_path / "fit.nc"
    out.write_text("not to be lost")
    assert main(["fit", str(config), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "exists" in err and "--overwrite" in err
    assert out.read_text() == "not to be lost"
    assert main(["fit", str(config), "-o", str(config)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "fit file" in err
    assert config.read_text().startswith("preset")


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


SAMPLE1 = dict(A=0.012, m1=0.010, m2=0.0014, D0=1.0e-6)


def test_fit_command_on_relaxed_slips_csv_and_a_netcdf_curve(tmp_path, capsys):
    """Fig. 3-style relaxed slips (CSV, nm and um/s) and a relaxation curve (netCDF, units in attributes) of one
    sample (sample1), fitted together: A, m1 and m2 covered by their intervals and well constrained."""
    rng = np.random.default_rng(31)
    km, v = np.repeat([2e5, 5e5, 1.2e6], 3), np.tile([3e-6, 1e-5, 3e-5], 3)
    dx = np.array([relaxed_slip(SAMPLE1, a, b) for a, b in zip(km, v)])
    obs = dx * (1 + 0.01 * rng.standard_normal(dx.size))
    rows = "".join(f"{float(a)!r},{float(b) * 1e6!r},{float(c) * 1e9!r},{0.01 * float(d) * 1e9!r}\n"
                   for a, b, c, d in zip(km, v, obs, dx))
    (tmp_path / "fig3.csv").write_text("# K_over_M: s-2\n# V: um/s\n# dx_inf: nm\n# noise: nm\n"
                                       "K_over_M,V,dx_inf,noise\n" + rows)
    t = np.logspace(-1, 3, 30)
    sigma = 0.005 * relaxed_slip(SAMPLE1, 3e5, 1e-6)
    x = np.abs(slip_curve(SAMPLE1, 3e5, 1e-6, t) + sigma * rng.standard_normal(t.size))
    xr.Dataset({"t": ("time", t, {"units": "s"}), "x": ("time", x, {"units": "m"}),
                "noise": ("time", np.full(t.size, sigma), {"units": "m"}),
                "K_over_M": ((), 3e5, {"units": "s-2"}), "V": ((), 1e-6, {"units": "m s-1"})}
               ).to_netcdf(tmp_path / "curve.nc")
    (tmp_path / "fit.toml").write_text('preset = "sample1"\nfree = ["A", "m1", "m2"]\n'
                                       '[[data]]\nfile = "fig3.csv"\n[[data]]\nfile = "curve.nc"\n')
    out = tmp_path / "fit.nc"
    assert main(["fit", str(tmp_path / "fit.toml"), "-o", str(out), "-q"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.sizes["sample"] == 1 and ds.sizes["datum"] == dx.size + t.size
        assert sorted(set(ds["datum_set"].values.tolist())) == ["curve", "fig3"]
        np.testing.assert_allclose(ds["observed"].values[:dx.size], obs, rtol=1e-12)  # nm -> m
        for name in ("A", "m1", "m2"):
            assert float(ds[f"{name}_lower"][0]) <= SAMPLE1[name] <= float(ds[f"{name}_upper"][0]), name
            assert int(ds[f"{name}_label"][0]) == 0, name
    assert out.with_suffix(".png").is_file()


def test_a_fit_file_is_opened_described_and_drawn(tmp_path, capsys):
    """A file of ``sweep fit`` is one of sweep's files: sweep.open reads it, ``sweep info`` describes it (its free
    parameters' ranges, no text variables), ``sweep plot`` draws it again (data, fit, residuals, profiles)."""
    import sweep

    _write_curve(tmp_path / "c1.csv", 1e-6, 1)
    (tmp_path / "fit.toml").write_text('preset = "sample2"\nfree = ["A", "m1"]\n[[data]]\nfile = "c1.csv"\n')
    out = tmp_path / "fit.nc"
    assert main(["fit", str(tmp_path / "fit.toml"), "-o", str(out)]) == 0
    ds = sweep.open(out)
    assert int(ds["fit_status"][0]) == 0 and "A_lower" in ds
    capsys.readouterr()
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "(fit file)" in text and "\n  A " in text and "fit_status" in text
    png = tmp_path / "again.png"
    assert main(["plot", str(out), "-o", str(png)]) == 0 and png.stat().st_size > 10_000
    assert main(["plot", str(out), "-o", str(tmp_path / "v.png"), "--variable", "A"]) == 2
    assert "--variable is for sweep files" in capsys.readouterr().err
