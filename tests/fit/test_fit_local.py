"""sweep.fit(search="local"): the least squares from the given start without the global stage (issue 34's "same
starting point"), on data from the independent scipy references (tests/reference_records.py: Radau rtol 1e-10;
tests/fit_reference.py for stop curves): it reaches the truth from a start near it with covering intervals, gives
the global fit's answer on a well-posed record, says so where a start in a wrong basin leaves it in a poor local
minimum, refuses bad values of the option, and the option reaches run_fit from the TOML file and the command line."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from fit_reference import relaxed_slip, slip_curve
from reference_records import record_reference

import sweep
from sweep.cli import main
from sweep.errors import InputError
from sweep.fit import Curve
from sweep.fit.records import Record
from sweep.fit.result import save_fit
from sweep.scene.plausibility import PlausibilityWarning

TRUE = {"a": 0.01, "b": 0.015, "Dc": 1e-5, "mu0": 0.6}
K, NOISE, V, DUR = 2e3, 2e-4, [1e-6, 1e-5], [20.0, 40.0]
START = sweep.FrictionParams.from_lab(0.008, 0.012, 2e-5, 0.6)  # a, b 20 % low, Dc 2x high
FREE = tuple(TRUE)


@pytest.fixture(scope="module")
def step():
    """A 600-sample velocity step (1 -> 10 um/s) at irregular times with a noise draw, and its displacement."""
    rng = np.random.default_rng(61)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 599))))
    mu, disp = record_reference(*TRUE.values(), K, V, DUR, t)
    return t, mu + NOISE * rng.standard_normal(t.size), disp


@pytest.fixture(scope="module")
def both(step):
    """The step fitted from START with the noise estimated: (local fit, global fit)."""
    t, mu, disp = step
    rec = Record(t, mu, displacement=disp, k=K)
    return (sweep.fit(rec, free=FREE, params=START, search="local"),
            sweep.fit(rec, free=FREE, params=START, search="global"))


def _interval(ds, n):
    return float(ds[f"{n}_lower"][0]), float(ds[f"{n}_upper"][0])


def test_local_fit_reaches_the_truth_with_covering_intervals(both):
    """From START the local fit is ok, the truth inside every 95 % interval; the Dataset says which search ran and
    has no global stage's landscape or best point."""
    ds = both[0]
    assert int(ds["fit_status"][0]) == 0
    for n, v in TRUE.items():
        lo, hi = _interval(ds, n)
        assert lo <= v <= hi, (n, lo, hi)
    settings = json.loads(ds.attrs["fit_settings"])
    assert settings["search"] == "local"
    assert settings["start"] == pytest.approx({"a": 0.008, "b": 0.012, "Dc": 2e-5, "mu0": 0.6})
    assert "misfit_landscape" not in ds and "a_global" not in ds and not any(d.startswith("grid_") for d in ds.dims)
    assert "global" not in json.loads(ds.attrs["fit_rounds"])
    assert json.loads(both[1].attrs["fit_settings"])["search"] == "global" and "misfit_landscape" in both[1]


def test_local_and_global_fits_agree_on_a_well_posed_record(both):
    """The same minimum: best values within 0.02 standard errors, interval ends within 1 % of the half-width."""
    local, glob = both
    for n in TRUE:
        se = float(glob[f"{n}_stderr"][0])
        assert abs(float(local[n][0]) - float(glob[n][0])) < 0.02 * se, n
        lo_l, hi_l = _interval(local, n)
        lo_g, hi_g = _interval(glob, n)
        half = (hi_g - lo_g) / 2
        assert abs(lo_l - lo_g) < 0.01 * half and abs(hi_l - hi_g) < 0.01 * half, n


def test_a_local_fit_from_a_wrong_basin_is_not_ok(step):
    """A start at the critical stiffness (k = (b - a)/Dc = 2e3 1/m = K: the model's slider oscillates) holds the
    least squares in a poor local minimum (chi^2 ~ 1e6 on 600 samples): with the noise given the local fit says
    poor_fit, never ok; the global fit from the same start finds the truth."""
    t, mu, disp = step
    rec = Record(t, mu, displacement=disp, k=K, noise=NOISE)
    start = {"a": 0.012, "b": 0.014, "Dc": 1e-6, "mu0": 0.6}
    bounds = {"a": (1e-3, 0.1), "b": (-0.05, 0.1), "Dc": (1e-7, 1e-3), "mu0": (0.3, 0.9)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        local = sweep.fit(rec, free=FREE, params=START, start=start, bounds=bounds, search="local", profiles=False)
    flags = local["fit_status"].attrs["flag_meanings"].split()
    assert flags[int(local["fit_status"][0])] == "poor_fit", float(local["misfit"][0])
    glob = sweep.fit(rec, free=FREE, params=START, start=start, bounds=bounds, profiles=False)
    assert int(glob["fit_status"][0]) == 0
    assert float(glob["Dc"][0]) == pytest.approx(TRUE["Dc"], rel=0.05)


SAMPLE2 = dict(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)


def test_local_fit_of_stop_curves():
    """Stop data too: two relaxation curves (1 and 5 um/s, 0.5 % noise given) from a start 10 % off the truth:
    ok, the truth covered, the global fit's minimum (best values within 0.02 standard errors)."""
    t = np.logspace(-1, 3.5, 40)
    curves = []
    for V_, seed in ((1e-6, 1), (5e-6, 2)):
        s = 0.005 * relaxed_slip(SAMPLE2, 2.8e5, V_)
        x = slip_curve(SAMPLE2, 2.8e5, V_, t) + s * np.random.default_rng(seed).standard_normal(t.size)
        curves.append(Curve(t, np.abs(x), K_over_M=2.8e5, V=V_, noise=s, name=f"{V_ * 1e6:g} um/s"))
    start = {"A": 0.0077, "m1": 0.0113, "m2": 0.0036}
    local = sweep.fit(curves, free=("A", "m1", "m2"), params=sweep.FrictionParams(**SAMPLE2), start=start,
                      search="local")
    glob = sweep.fit(curves, free=("A", "m1", "m2"), params=sweep.FrictionParams(**SAMPLE2), start=start)
    assert int(local["fit_status"][0]) == 0 and "misfit_landscape" not in local
    for n in ("A", "m1", "m2"):
        assert _interval(local, n)[0] <= SAMPLE2[n] <= _interval(local, n)[1], n
        assert abs(float(local[n][0]) - float(glob[n][0])) < 0.02 * float(glob[f"{n}_stderr"][0]), n


@pytest.mark.parametrize("bad", ["Local", "grid", "", None, 1])
def test_bad_search_is_refused_naming_the_option(step, bad):
    t, mu, disp = step
    with pytest.raises(InputError, match=r"search must be one of 'global', 'local'") as err:
        sweep.fit(Record(t, mu, displacement=disp, k=K), free=FREE, params=START, search=bad)
    assert repr(bad) in str(err.value)


def test_file_of_a_local_fit_opens_prints_and_draws(tmp_path, both):
    """sweep.open, sweep info and sweep plot of a local fit's file (no landscape) work."""
    path = save_fit(both[0], tmp_path / "local.nc")
    ds = sweep.open(path)
    assert json.loads(ds.attrs["fit_settings"])["search"] == "local"
    assert main(["info", str(path)]) == 0
    png = tmp_path / "local.png"
    assert main(["plot", str(path), "-o", str(png)]) == 0 and png.stat().st_size > 10_000


class _Reached(Exception):
    pass


def test_toml_key_and_cli_flag_reach_run_fit(tmp_path, monkeypatch, capsys, step):
    """search = "local" in the fit file reaches run_fit; --search overrides the file; a bad value in the file is
    refused in one line (exit 2)."""
    import sweep.fit.core as core

    t, mu, disp = step
    rows = "".join(f"{float(a)!r},{float(d) * 1e6!r},{float(m)!r}\n" for a, d, m in zip(t, disp, mu))
    (tmp_path / "rec.csv").write_text("time_s,lpdisp_um,mu\n" + rows)
    seen = []

    def fake(*args, **kwargs):
        seen.append(kwargs.get("search"))
        raise _Reached

    monkeypatch.setattr(core, "run_fit", fake)
    config = tmp_path / "fit.toml"
    config.write_text('free = ["a", "b", "Dc", "mu0"]\nsearch = "local"\n[params]\nA = 0.008\nm1 = 0.004\n'
                      'm2 = 0.0\nD0 = 2e-5\nm0 = 0.6\n[[data]]\nfile = "rec.csv"\nk = 2e3\n')
    for extra, expect in (([], "local"), (["--search", "global"], "global"), (["--search", "local"], "local")):
        with pytest.raises(_Reached):
            main(["fit", str(config), "-o", str(tmp_path / "out.nc"), *extra])
        assert seen[-1] == expect
    monkeypatch.undo()
    config.write_text(config.read_text().replace('search = "local"', 'search = "grid"'))
    capsys.readouterr()
    assert main(["fit", str(config), "-o", str(tmp_path / "out.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "search must be one of 'global', 'local'" in err and "'grid'" in err
