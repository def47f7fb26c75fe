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


# --- records as laboratories bring them (helper H2b): a velocity column, a free stiffness, a fit that cannot
# converge, the detrend's slope ---------------------------------------------------------------------------------

def _interval(ds, name):
    return float(ds[f"{name}_lower"][0]), float(ds[f"{name}_upper"][0])


def test_velocity_column_record_recovers_a_b_dc():
    """A load-point velocity column (the servo's 1 -> 10 um/s, 1 % noise) at 100 Hz with jitter instead of the
    displacement: the history found from it, a, b, Dc (and mu0) inside their 95 % intervals on 3 draws of noise 1e-3
    in mu. (A velocity column places a change midway between the two samples around it, up to half a spacing off:
    at noise 2e-4 on 2,500 samples that biased a and b by 2-5 standard errors; the displacement column does not.)"""
    rng = np.random.default_rng(31)
    t = np.concatenate(([0.0], np.arange(0.01, 25.0, 0.01) + 0.005 * rng.uniform(size=2499)))
    mu, _ = record_reference(TRUE["a"], TRUE["b"], TRUE["Dc"], TRUE["mu0"], K, [1e-6, 1e-5], [5.0, 20.0], t)
    v = np.where(t < 5.0, 1e-6, 1e-5)
    for _ in range(3):
        rec = Record(t, mu + 1e-3 * rng.standard_normal(t.size), velocity=v * (1 + 0.01 * rng.standard_normal(t.size)),
                     k=K)
        ds = sweep.fit(rec, free=tuple(TRUE), params=START)
        assert int(ds["fit_status"][0]) == 0
        assert _covered(ds).all(), {n: _interval(ds, n) for n in TRUE}


def test_free_stiffness_is_recovered_with_covering_intervals(vstep):
    """k free with a, b, Dc, mu0 from a start at half the truth (no k in the record): its 95 % interval covers the
    truth on at least 5 of 6 draws, every fit ok, and its width is a few per cent (k is well determined by the
    elastic loading after the step, dmu/dt = k v_lp)."""
    t, mu, disp = vstep
    rng = np.random.default_rng(32)
    hits, widths = [], []
    for _ in range(6):
        rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp)
        ds = sweep.fit(rec, free=(*TRUE, "k"), params=START, start={"k": K / 2})
        assert int(ds["fit_status"][0]) == 0
        lo, hi = _interval(ds, "k")
        hits.append(lo <= K <= hi)
        widths.append((hi - lo) / K)
    assert sum(hits) >= 5, hits
    assert max(widths) < 0.05, widths


@pytest.mark.parametrize("case", ["bounds exclude the truth", "one round", "no parameter set fits"])
def test_a_record_fit_that_cannot_converge_says_so(vstep, case):
    """A record fit that cannot succeed reports a failed fit_status and one warning line, never an ok-looking
    result: Dc bounded away from the truth (at_bound), the least squares cut to one round (not_converged), a record
    whose friction no parameter set fits (a sine, given noise: the misfit is far above its degrees of freedom)."""
    from sweep.fit import levenberg
    from sweep.scene.plausibility import PlausibilityWarning

    t, mu, disp = vstep
    rng = np.random.default_rng(33)
    rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=K)
    kwargs = {"free": tuple(TRUE), "params": START}
    if case == "bounds exclude the truth":
        kwargs["bounds"] = {"Dc": (1.5e-5, 5e-5)}
    elif case == "no parameter set fits":
        rec = Record(t, 0.6 + 0.01 * np.sin(t) + NOISE * rng.standard_normal(t.size), displacement=disp, k=K,
                     noise=NOISE)
    with pytest.MonkeyPatch.context() as mp:
        if case == "one round":
            mp.setattr(levenberg, "FIT", levenberg.Tolerances(ftol=1e-10, xtol=1e-9, max_rounds=1))
            mp.setattr("sweep.fit.local.FIT", levenberg.FIT)
            mp.setattr("sweep.fit.core.local.FIT", levenberg.FIT)
        with pytest.warns(PlausibilityWarning, match="the fit failed"):
            ds = sweep.fit(rec, **kwargs)
    status = ds["fit_status"].attrs["flag_meanings"].split()[int(ds["fit_status"][0])]
    assert status != "ok", status
    if case == "bounds exclude the truth":
        assert status == "at_bound" and int(ds["Dc_at_bound"][0]) == 2
    if case == "one round":
        assert status == "not_converged"


def test_detrend_slopes_are_reported_and_counted(vstep):
    """Two records, one drifting 2e-5 per second (detrend="time"), one -3 per metre of load-point displacement
    (detrend="displacement"), each its own sample: their slopes at the best fit in the Dataset (units s-1 and m-1)
    within 5 % of the drift, one parameter each in degrees_of_freedom, and in plot_fit's legend (trend_lines)."""
    from sweep.fit.plot import trend_lines

    t, mu, disp = vstep
    rng = np.random.default_rng(34)
    recs = [Record(t, mu + NOISE * rng.standard_normal(t.size) + 2e-5 * t, displacement=disp, k=K, detrend="time",
                   name="drift_t"),
            Record(t, mu + NOISE * rng.standard_normal(t.size) - 3.0 * disp, displacement=disp, k=K,
                   detrend="displacement", name="drift_x"),
            Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=K, name="flat")]
    ds = sweep.fit(recs, free=tuple(TRUE), params=START, per_data_set=True)
    assert ds["record_name"].values.tolist() == ["drift_t", "drift_x", "flat"]
    assert ds["detrend_slope_time"].attrs["units"] == "s-1" and ds["detrend_slope_displacement"].attrs["units"] == "m-1"
    assert float(ds["detrend_slope_time"][0]) == pytest.approx(2e-5, rel=0.05)
    assert float(ds["detrend_slope_displacement"][1]) == pytest.approx(-3.0, rel=0.05)
    assert np.isnan(ds["detrend_slope_time"][1:]).all() and np.isnan(ds["detrend_slope_displacement"][[0, 2]]).all()
    assert ds["degrees_of_freedom"].values.tolist() == [t.size - 5, t.size - 5, t.size - 4]
    assert ds["observed"].attrs["units"] == "1" and ds["noise"].attrs["units"] == "1"  # friction, not slip
    lines = trend_lines(ds)
    assert lines[0].startswith("trend 2") and "/s in time" in lines[0] and "/m in displacement" in lines[1]
    assert lines[2] == ""


def test_a_record_with_its_true_noise_given_is_not_a_poor_fit(vstep):
    """The control of poor_fit: the noise given as drawn, the misfit is near its degrees of freedom and the fit ok."""
    t, mu, disp = vstep
    rec = Record(t, mu + NOISE * np.random.default_rng(35).standard_normal(t.size), displacement=disp, k=K,
                 noise=NOISE)
    ds = sweep.fit(rec, free=tuple(TRUE), params=START)
    assert int(ds["fit_status"][0]) == 0
    assert abs(float(ds["misfit"][0]) - t.size + 4) < 5 * np.sqrt(2 * (t.size - 4))
