"""Fitting laboratory records (sweep.fit with sweep.fit.records.Record): recovery and 95 % interval coverage on
noise draws about the independent scipy reference (tests/reference_records.py, Radau rtol 1e-10), a velocity step
and a slide-hold-slide record sharing one parameter set, the load history found from the displacement."""

from __future__ import annotations

import numpy as np
import pytest
from reference_records import record_reference

import sweep
from sweep.fit.records import Record

TRUE = {"a": 0.01, "b": 0.015, "Dc": 1e-5, "mu0": 0.6}
K = 2e3  # 1/m, stiff: k_c = (b - a)/Dc = 500 1/m
NOISE = 2e-4
START = sweep.FrictionParams.from_lab(0.008, 0.012, 2e-5, 0.6)


@pytest.fixture(scope="module")
def vstep():
    rng = np.random.default_rng(5)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 599))))
    mu, disp = record_reference(TRUE["a"], TRUE["b"], TRUE["Dc"], TRUE["mu0"], K, [1e-6, 1e-5], [20.0, 40.0], t)
    return t, mu, disp


def _covered(ds, names=tuple(TRUE)):
    return np.array([float(ds[f"{n}_lower"][0]) <= TRUE[n] <= float(ds[f"{n}_upper"][0]) for n in names])


def test_velocity_step_coverage_over_noise_draws(vstep):
    """25 draws x 4 parameters: the 95 % profile intervals cover the truth in [0.85, 1] of the cases, every fit ok."""
    t, mu, disp = vstep
    rng = np.random.default_rng(11)
    hits = []
    for _ in range(25):
        rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=K)
        ds = sweep.fit(rec, free=tuple(TRUE), params=START)
        assert int(ds["fit_status"][0]) == 0
        hits.append(_covered(ds))
    rate = np.mean(hits)
    assert 0.85 <= rate <= 1.0, rate


def test_slide_hold_slide_and_step_share_one_parameter_set(vstep):
    """A velocity step and an SHS record (1 um/s, a 30 s hold, reslide) of one sample fitted together, the noise
    estimated: the truth inside the intervals, the estimated noise within 15 % of the drawn one."""
    t, mu, disp = vstep
    rng = np.random.default_rng(12)
    t2 = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 80.0, 799))))
    mu2, disp2 = record_reference(TRUE["a"], TRUE["b"], TRUE["Dc"], TRUE["mu0"], K, [1e-6, 0.0, 1e-6],
                                  [20.0, 30.0, 30.0], t2)
    recs = [Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=K, name="step"),
            Record(t2, mu2 + NOISE * rng.standard_normal(t2.size),
                   displacement=disp2 + 1e-9 * rng.standard_normal(t2.size), k=K, name="shs")]
    ds = sweep.fit(recs, free=tuple(TRUE), params=START)
    assert ds.sizes["sample"] == 1 and int(ds["fit_status"][0]) == 0
    assert _covered(ds).all(), {n: (float(ds[f"{n}_lower"][0]), float(ds[f"{n}_upper"][0])) for n in TRUE}
    assert float(ds["datum_noise"][0]) == pytest.approx(NOISE, rel=0.15)


def test_picture_of_a_record_fit(tmp_path, vstep):
    """plot_fit draws a record fit (data, model, residuals against time, the profiles) into a PNG."""
    from sweep.fit.plot import plot_fit

    t, mu, disp = vstep
    rng = np.random.default_rng(13)
    ds = sweep.fit(Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=K),
                   free=("a", "b", "Dc"), params=START)
    plot_fit(ds, tmp_path / "rec.png")
    assert (tmp_path / "rec.png").stat().st_size > 10_000


def test_detrend_recovers_the_parameters_under_a_linear_drift(vstep):
    """A drift of 2e-5 per second added to a step record: fitted with detrend="time", the truth is inside the
    intervals; without, the fit is pulled off (mu0 or b outside its interval)."""
    t, mu, disp = vstep
    rng = np.random.default_rng(14)
    drifted = mu + NOISE * rng.standard_normal(t.size) + 2e-5 * t
    ok = sweep.fit(Record(t, drifted, displacement=disp, k=K, detrend="time"), free=tuple(TRUE), params=START)
    assert _covered(ok).all()
    off = sweep.fit(Record(t, drifted, displacement=disp, k=K), free=tuple(TRUE), params=START)
    assert not _covered(off).all()
