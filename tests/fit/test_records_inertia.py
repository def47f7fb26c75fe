"""A laboratory record's machine inertia g = N/M (issue 34; docs/fit.md, "The machine's inertia"): given per record,
per fit, in the fit file or on the command line, refused outside its range naming it; without it a record is
quasi-static but where a slip runs away. Checked against the independent scipy references: the quasi-static Radau
reference of 10 -> 100 um/s steps (tests/lab_files.py) and Newton's law by Radau for a sawtooth
(tests/reference_history.inertial_reference_at, via tests/fit/test_records_stickslip.sawtooth)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from lab_files import TRUTH, K, make
from test_records_stickslip import MU0, SHORT_LOAD, A, B, sawtooth

import sweep
from sweep.errors import InputError
from sweep.fit.records import G_RANGE, Record, read_record
from sweep.scene.plausibility import PlausibilityWarning

LAB = sweep.FrictionParams.from_lab(*(TRUTH[n] for n in ("a", "b", "Dc", "mu0")))


def _settings(ds) -> dict:
    return json.loads(ds.attrs["fit_settings"])


def _fit_steps(seed: int, **kw):
    """The 10 -> 100 um/s steps of the quasi-static reference (gamma/A = v^2/(g Dc a) = 0.0102 at g = 9.81, above
    friction_at's 1e-2), noise 1e-4, drift detrended, a, b, Dc, mu0 free from the truth (search local)."""
    lab = make("steps", seed=seed, noise=1e-4)
    rec = Record(lab.t, lab.mu, displacement=lab.disp, k=K, detrend="time", name="p1")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = sweep.fit(rec, free=tuple(TRUTH), **{"params": LAB, "search": "local", **kw})
    z = {n: (float(ds[n][0]) - TRUTH[n]) / float(ds[f"{n}_stderr"][0]) for n in TRUTH}
    cover = sum(float(ds[f"{n}_lower"][0]) <= TRUTH[n] <= float(ds[f"{n}_upper"][0]) for n in TRUTH)
    return ds, z, cover, [str(w.message) for w in caught if issubclass(w.category, PlausibilityWarning)]


def test_fast_steps_without_g_fit_the_quasi_static_reference_without_bias():
    """Without g (the default: quasi-static) 4 draws fit ok without a warning, the truth on average within 1.5
    standard errors per parameter (measured: -0.24 .. 0.3) and at least 14 of 16 intervals covering (measured: 16);
    fit_settings say no g was given and the best fit ran quasi-statically. (The old default, inertia at g = 9.81:
    a, b -4.4, -5.3 standard errors off on average, 5 of 16 covering: see the next test.)"""
    zs, covered = [], 0
    for seed in range(4):
        ds, z, cover, lines = _fit_steps(seed)
        assert int(ds["fit_status"][0]) == 0 and not lines, lines
        settings = _settings(ds)
        assert settings["record_g"] == [None] and settings["record_inertial"] == [False]
        zs.append(z)
        covered += cover
    assert covered >= 14
    for n in TRUTH:
        assert abs(np.mean([z[n] for z in zs])) < 1.5, (n, [z[n] for z in zs])


def test_a_given_g_reaches_the_model():
    """g = 1e4 given (fit call, or the old way in params): gamma/A 1e-5, quasi-static, the same values as without
    g (within 1e-3 standard errors); g = 9.81 given: the fit models that inertia (record_inertial) and, the
    reference being quasi-static, puts a more than 2 standard errors low (measured -4.0 on this draw)."""
    base, z0, _, _ = _fit_steps(0)
    for kw in ({"g": 1e4}, {"params": sweep.FrictionParams.from_lab(*(TRUTH[n] for n in ("a", "b", "Dc", "mu0")),
                                                                      g=1e4)}):
        ds, z, _, lines = _fit_steps(0, **kw)
        assert _settings(ds)["record_g"] == [1e4] and _settings(ds)["record_inertial"] == [False] and not lines
        assert all(abs(z[n] - z0[n]) < 1e-3 for n in TRUTH), (z, z0)
    ds, z, _, lines = _fit_steps(0, g=9.81)
    assert _settings(ds)["record_g"] == [9.81] and _settings(ds)["record_inertial"] == [True] and not lines
    assert z["a"] < -2.0, z


@pytest.fixture(scope="module")
def one_event():
    """A one-event sawtooth of Newton's law at g = 9.81 (Dc = 10 um, k = 0.5 (b - a)/Dc, 600 samples over 25 s)."""
    t, mu, disp, k = sawtooth(1e-5, 9.81, 600, seed=3, load=SHORT_LOAD)
    return Record(t, mu + 2e-4 * np.random.default_rng(4).standard_normal(t.size), displacement=disp, k=k,
                  name="saw")


def test_a_sawtooth_without_g_slips_with_inertia_and_says_so(one_event):
    """The sawtooth fitted from the truth (search local) without g: its slips run with inertia at params' g, the fit
    is ok, fit_settings say the best fit ran inertial, and one PlausibilityWarning names the record and asks for the
    machine's g; with g = 9.81 given (the record's own inertia) the same fit and no such warning."""
    kw = {"free": ("a", "b", "Dc", "mu0"), "params": sweep.FrictionParams.from_lab(A, B, 1e-5, MU0),
          "search": "local", "profiles": False}
    with pytest.warns(PlausibilityWarning, match=r"record 'saw' slips at the best fit .* no g = N/M was given"):
        ds = sweep.fit(one_event, **kw)
    assert int(ds["fit_status"][0]) == 0
    assert _settings(ds)["record_g"] == [None] and _settings(ds)["record_inertial"] == [True]
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        given = sweep.fit(one_event, g=9.81, **kw)
    assert int(given["fit_status"][0]) == 0 and _settings(given)["record_inertial"] == [True]
    assert float(given["a"][0]) == pytest.approx(float(ds["a"][0]), rel=1e-9)


@pytest.mark.parametrize("bad", [0.0, -9.81, float("nan"), float("inf"), 1e13, 1e-4, "fast", True])
def test_bad_g_is_refused_naming_it_and_its_range(bad):
    t = np.linspace(0.0, 10.0, 50)
    with pytest.raises(InputError, match=r"record 'p1': g must be a number in \[0\.001, 1e\+12\] m/s\^2"):
        Record(t, 0.6 + 0 * t, displacement=1e-6 * t, g=bad, name="p1")
    with pytest.raises(InputError, match=r"^g must be a number in \[0\.001, 1e\+12\] m/s\^2 \(g = N/M"):
        sweep.fit(Record(t, 0.6 + 0 * t, displacement=1e-6 * t, k=K, name="p1"), params=LAB, g=bad)
    assert G_RANGE == (1e-3, 1e12)


def test_g_of_stop_data_is_refused():
    from sweep.fit.data import Curve

    curve = Curve(np.linspace(0.0, 1.0, 20), np.linspace(0.0, 1e-6, 20), K_over_M=1e3, V=1e-6)
    with pytest.raises(InputError, match="g .* applies to laboratory records only"):
        sweep.fit(curve, g=1e4)


def test_g_from_the_file_the_reader_the_fit_file_and_the_command_line(tmp_path, capsys):
    """'# g = 2e4 m/s^2' in a record's comments, read_record(g=...) over it, a wrong unit refused naming it; the fit
    file's top-level g and a [[data]] table's g; sweep fit --g -1 refused (exit 2, one line naming g)."""
    from sweep.cli import main
    from sweep.fit.config import load_fit_config

    lab = make("steps", seed=0)
    rows = [f"{t:.6f}\t{x * 1e6:.4f}\t{m:.6f}" for t, x, m in zip(lab.t, lab.disp, lab.mu)]
    path = tmp_path / "r.txt"
    path.write_text("\n".join(["# g = 2e4 m/s^2", "# k = 2e3 1/m", "Time [s]\tLP_Disp [um]\tmu"] + rows) + "\n")
    assert read_record(path).g == 2e4 and read_record(path, g=5e3).g == 5e3
    (tmp_path / "bad.txt").write_text(path.read_text().replace("m/s^2", "kg"))
    with pytest.raises(InputError, match=r"'# g = 2e4 kg': g = N/M is in m/s\^2"):
        read_record(tmp_path / "bad.txt")
    toml = tmp_path / "fit.toml"
    toml.write_text('free = ["a", "b"]\ng = 3e4\n[params]\na = 0.01\nb = 0.015\nDc = 1e-5\nmu0 = 0.6\n'
                    '[[data]]\nfile = "r.txt"\ng = 7e3\n')
    kwargs = load_fit_config(toml)
    assert kwargs["g"] == 3e4 and kwargs["data"][0].g == 7e3
    assert main(["fit", str(toml), "-o", str(tmp_path / "f.nc"), "--g", "-1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "g must be a number in [0.001, 1e+12] m/s^2" in err[0], err
