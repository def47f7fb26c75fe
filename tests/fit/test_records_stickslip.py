"""Stick-slip (sawtooth) laboratory records (issue 34): a spring softer than critical, k = 0.5 (b - a)/Dc, under a
velocity step 1 -> 10 um/s. The quasi-static model runs away there, so friction_at runs such a set with inertia
(docs/physics.md 7b, "Stick-slip: the quasi-static runaway"). The records come from the independent scipy reference
of Newton's law (tests/reference_history.inertial_reference_at, Radau at rtol 1e-10) in the laboratory's
parameters (a = A, b - a = m1, Dc = D0, K/M = k g), with the record's inertia as g = N/M (the normal load per slider
mass; 9.81 m/s^2 is sweep.fit's default, FrictionParams.g), irregular sampling and noise."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from reference_history import inertial_reference_at

import sweep
from sweep.fit.events import event_scale, record_events, slip_events
from sweep.fit.records import Record
from sweep.protocols.history.forward import LoadHistory, friction_at
from sweep.status import Status

A, B, MU0, V0 = 0.01, 0.015, 0.6, 1e-6
NOISE = 2e-4
STEP = LoadHistory(np.array([1e-6, 1e-5]), np.array([5.0, 30.0]))


def sawtooth(Dc: float, g: float, n: int, seed: int, load: LoadHistory = STEP):
    """(t, mu, load-point displacement, k) of a record at k = 0.5 (b - a)/Dc and inertia g = N/M [m/s^2]."""
    k = 0.5 * (B - A) / Dc
    rng = np.random.default_rng(seed)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, load.total, n - 1))))
    mu, _ = inertial_reference_at(A, B - A, 0.0, Dc, k * g, load.velocities, load.durations, t, m0=MU0, V0=V0, g=g)
    ends = np.concatenate(([0.0], np.cumsum(load.durations)))
    disp = np.interp(t, ends, np.concatenate(([0.0], np.cumsum(load.velocities * load.durations))))
    return t, mu, disp, k


def params(Dc: float, k: float, g: float) -> dict[str, float]:
    return {"A": A, "m1": B - A, "m2": 0.0, "D0": Dc, "m0": MU0, "V0": V0, "K_over_M": k * g, "g": g}


@pytest.mark.parametrize(("Dc", "g"), [(3e-6, 9.81), (3e-6, 1e3), (1e-5, 9.81)])
def test_sawtooth_records_against_newtons_law(Dc, g):
    """friction_at through 1-4 slip events (stress drops of > 3 a each, irregular samples): the inertial model (the
    quasi-static one runs away); against the reference at rtol 1e-6 and 1e-8, 99 % of the samples within rtol
    (|mu| + a) (the rest, inside a slip at dmu/dt ~ -2/s, within 8x: measured), the error falling with rtol, and
    the estimate (the looser run's error, ~9x the true one) above it at the largest error and at >= 95 % of the
    samples (in stick-slip it can pass rtol (|mu| + a): status error_above_tol, the values kept)."""
    t, mu, _, k = sawtooth(Dc, g, 600, seed=3)
    assert np.sum(np.diff(mu) < -3 * A) >= 1 and np.ptp(mu[t > 6.0]) > 5 * A
    worst = []
    for rtol in (1e-6, 1e-8):
        out = friction_at(params(Dc, k, g), STEP, t, rtol=rtol)
        assert out.model.tolist() == [1] and out.status[0] in (Status.OK, Status.ERROR_ABOVE_TOL)
        true = np.abs(out.mu[0] - mu)
        assert np.mean(true <= rtol * (np.abs(mu) + A)) >= 0.99
        assert true.max() <= out.error.max() and np.mean(true <= out.error[0]) >= 0.95
        worst.append(true.max())
    assert worst[1] < worst[0] / 30


def test_a_sawtooth_record_fitted_from_the_truth():
    """Six noise draws of a one-event sawtooth record (Dc = 10 um, k = 250/m, 600 samples, noise 2e-4), a, b, Dc,
    mu0 free, k fixed, noise estimated, started at the truth: the 95 % profile intervals cover the truth in [0.85, 1]
    of the 24 cases and the noise is recovered within 15 %. From starts 30 % off: tests/fit/
    test_records_sawtooth_fit.py (the event stage, sweep/fit/event_fit.py)."""
    t, mu, disp, k = sawtooth(1e-5, 9.81, 600, seed=3, load=LoadHistory(STEP.velocities, np.array([5.0, 20.0])))
    truth = {"a": A, "b": B, "Dc": 1e-5, "mu0": MU0}
    rng = np.random.default_rng(21)
    hits, noise = [], []
    for _ in range(6):
        rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=k)
        ds = sweep.fit(rec, free=tuple(truth), params=sweep.FrictionParams.from_lab(A, B, 1e-5, MU0))
        assert int(ds["fit_status"][0]) == 0
        hits += [float(ds[f"{n}_lower"][0]) <= v <= float(ds[f"{n}_upper"][0]) for n, v in truth.items()]
        noise.append(float(ds["datum_noise"][0]))
    assert 0.85 <= np.mean(hits) <= 1.0, np.mean(hits)
    np.testing.assert_allclose(noise, NOISE, rtol=0.15)


# --- slip events and the verdict events_missed (issue 34: a stable model through a sawtooth must not say ok) ---

SHORT_LOAD = LoadHistory(STEP.velocities, np.array([5.0, 20.0]))


@pytest.fixture(scope="module")
def one_event():
    """The one-event sawtooth of the test above (Dc = 10 um, k = 250/m, 600 samples over 25 s)."""
    return sawtooth(1e-5, 9.81, 600, seed=3, load=SHORT_LOAD)


def test_noise_scale_of_an_irregular_trended_series():
    """The record's noise scale: drawn noise on a steep linear trend (60x the noise per sample) at irregular times,
    and on a sawtooth's slow loading with its slip: the drawn standard deviation within 10 %."""
    from sweep.fit.events import noise_scale

    rng = np.random.default_rng(4)
    times = np.sort(rng.uniform(0.0, 25.0, 600))
    saw_t, saw, _, _ = sawtooth(1e-5, 9.81, 600, seed=3, load=SHORT_LOAD)
    for t, base in ((times, 0.3 * times), (saw_t, saw)):
        s = [noise_scale(t, base + NOISE * rng.standard_normal(t.size)) for _ in range(5)]
        np.testing.assert_allclose(s, NOISE, rtol=0.1)


@pytest.mark.parametrize(("Dc", "g", "durations"), [(1e-5, 9.81, [5.0, 20.0]), (3e-6, 9.81, [5.0, 30.0]),
                                                    (3e-6, 1e3, [5.0, 30.0])])
def test_slip_events_of_sawtooth_records(Dc, g, durations):
    """The events of the reference's sawtooths (1-4 of them) under noise 2e-4, five draws each: as many as the
    noise-free reference's stress drops of more than 3 a within two samples (the independent count)."""
    from sweep.fit.events import count_events, event_scale

    t, mu, _, _ = sawtooth(Dc, g, 600, seed=3, load=LoadHistory(STEP.velocities, np.array(durations)))
    drops = np.flatnonzero(mu[:-2] - np.minimum(mu[1:-1], mu[2:]) > 3 * A)
    truth = 1 + int(np.sum(np.diff(drops) > 2))
    assert truth >= 1
    rng = np.random.default_rng(8)
    for noisy in mu + NOISE * rng.standard_normal((5, t.size)):
        assert count_events(noisy, event_scale(t, noisy)) == truth


def test_smooth_transients_have_no_slip_events():
    """Stable records (k = 2e3/m, four times critical, and 1e3/m) sampled irregularly at ~0.1 s (a gap of 0.5 s at
    the step down), finer than their transients (Dc/V = 1 s at 10 um/s, the direct effect of a step down over
    a/(k V) = 0.5-1 s): velocity steps up and down and a slide-hold-slide (independent references in the
    laboratory's and in the paper's parameters), noise-free and with noise 2e-4: no events."""
    from reference_history import history_reference_at
    from reference_records import record_reference

    from sweep.fit.events import count_events, event_scale

    rng = np.random.default_rng(6)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 599))))
    series = [record_reference(A, B, 1e-5, MU0, k, v, d, t)[0]
              for k, v, d in ((2e3, [1e-6, 1e-5], [20.0, 40.0]), (2e3, [1e-5, 1e-6], [20.0, 40.0]),
                              (1e3, [1e-5, 1e-6], [20.0, 40.0]), (2e3, [1e-6, 0.0, 1e-6], [20.0, 20.0, 20.0]))]
    series.append(history_reference_at(A, B - A, 0.0, 1e-5, 1e3 * 9.81, [1e-6, 1e-5], [20.0, 40.0], t, m0=MU0))
    for mu in series:
        for noisy in (mu, *(mu + NOISE * rng.standard_normal((3, t.size)))):
            assert count_events(noisy, event_scale(t, noisy)) == 0


def test_a_stable_model_misses_the_sawtooths_events(one_event):
    """record_events against independent model series: the reference at the truth (plus other noise: a fit to the
    noise) keeps the events; the reference at k = 2 (b - a)/Dc (stable: it slides through the sawtooth) has none,
    and one with b - a 20 % smaller (the same event, a fall ~20 % smaller) misses them too."""
    from sweep.fit.events import record_events

    t, mu, disp, k = one_event
    rng = np.random.default_rng(9)
    rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=k, name="saw")
    w = np.ones(t.size)
    stable, _ = inertial_reference_at(A, B - A, 0.0, 1e-5, 4 * k * 9.81, STEP.velocities, [5.0, 20.0], t, m0=MU0,
                                      V0=V0, g=9.81)
    smaller, _ = inertial_reference_at(A, 0.8 * (B - A), 0.0, 1e-5, k * 9.81, STEP.velocities, [5.0, 20.0], t,
                                       m0=MU0, V0=V0, g=9.81)
    assert record_events([rec], mu + NOISE * rng.standard_normal(t.size) - rec.mu, w) == []
    (name, falls, model, why, _), = record_events([rec], stable - rec.mu, w)
    assert name == "saw" and len(falls) == 1 and falls[0] > 3 * A and model == [] and why == "count"
    (_, falls, model, why, _), = record_events([rec], smaller - rec.mu, w)
    assert len(model) == 1 and falls[0] - model[0] > 10 * NOISE and why == "fall"


def _fit(rec, start):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = sweep.fit(rec, free=("a", "b", "Dc", "mu0"), params=sweep.FrictionParams.from_lab(A, B, 1e-5, MU0),
                       start=start, profiles=False)
    return int(ds["fit_status"][0]), float(ds["datum_noise"][0]), [str(w.message) for w in caught]


def test_sawtooth_fits_that_miss_the_events_are_not_ok(one_event):
    """The one-event sawtooth, noise estimated, three draws, fitted with b and Dc held 30 % below the truth (a and mu0
    free): no model of that family makes the record's event (measured: a stable model, or the event 47 samples off;
    estimated noise many times the drawn one): fit_status events_missed, one warning line naming the record and the
    reason (the count, or the place); from the truth, a, b, Dc and mu0 free, the same draws fit ok (noise within
    15 %). (From a start 30 % off with a, b, Dc free the fit now finds the events:
    tests/fit/test_records_sawtooth_fit.py.)"""
    from sweep.fit.verdict import FIT_STATUS

    t, mu, disp, k = one_event
    rng = np.random.default_rng(21)
    for i in range(3):
        rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=k, name=f"draw{i}")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ds = sweep.fit(rec, free=("a", "mu0"), params=sweep.FrictionParams.from_lab(A, 0.7 * B, 0.7e-5, MU0),
                           profiles=False)
        assert FIT_STATUS[int(ds["fit_status"][0])] == "events_missed" and float(ds["datum_noise"][0]) > 10 * NOISE
        line, = [str(m.message) for m in caught if "events_missed" in str(m.message)]
        assert re.search(f"record 'draw{i}': (the record slips 1 time|as many slips, but one [0-9]+ samples from)",
                         line), line
        status, noise, lines = _fit(rec, {"a": A, "b": B, "Dc": 1e-5})
        assert status == 0 and abs(noise / NOISE - 1) < 0.15 and not [m for m in lines if "fit failed" in m]


def test_a_velocity_step_record_stays_ok():
    """A stable velocity-step record (k = 2e3/m, 4x critical; the reference, noise 2e-4 estimated) fitted from 30 %
    off: no events in the record, fit_status ok."""
    from reference_records import record_reference

    rng = np.random.default_rng(5)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 599))))
    mu, disp = record_reference(A, B, 1e-5, MU0, 2e3, [1e-6, 1e-5], [20.0, 40.0], t)
    rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=2e3)
    status, noise, _ = _fit(rec, {"a": 1.3 * A, "b": 0.7 * B, "Dc": 1.3e-5})
    assert status == 0 and abs(noise / NOISE - 1) < 0.15


def test_a_sawtooth_sampled_finer_than_its_slips_is_judged_at_a_coarser_rate():
    """A one-event sawtooth logged at 240 Hz (6,000 samples over 25 s; the slip lasts ~ half the natural period
    2 pi/sqrt(k g) = 0.13 s, ~15 samples) shows no slip event at its own rate, so a smooth model through it (the
    stable model of a fit from a start 30 % off, which said ok at 3-16x the noise) would pass unseen: record_events
    looks at every 2nd, 4th, ... sample (events.COARSER) and finds the record's slip at the first rate that shows
    one, the model counted there too. The reference's own friction is not missed; a smooth cubic through the record
    is."""
    t, mu, disp, k = sawtooth(1e-5, 9.81, 6000, seed=3, load=LoadHistory(STEP.velocities, np.array([5.0, 20.0])))
    y = mu + NOISE * np.random.default_rng(5).standard_normal(t.size)
    assert slip_events(y, event_scale(t, y)) == []
    rec, w = Record(t, y, displacement=disp, k=k, name="dense"), np.ones(t.size)
    assert record_events([rec], mu - y, w) == []
    smooth = np.polyval(np.polyfit(t, y, 3), t)
    missed = record_events([rec], smooth - y, w)
    assert [m[0] for m in missed] == ["dense"] and len(missed[0][1]) == 1 and missed[0][2] == []


@pytest.mark.parametrize("seed", [1, 3])
def test_falls_at_the_load_history_changes_are_not_slip_events(seed):
    """A slide-hold-slide record of a stiff machine (k = 4 k_c: no stick-slip possible; tests/lab_files.py: a
    logger's rates, noise 1e-4, drift detrended) falls by ~15 noise scales within two samples where a hold starts:
    counted as slip events, its fits from 30 % off said events_missed on these two draws (2 of 6). A fall whose
    neighbourhood holds a change of the load-point velocity is the load history's own (events.away_from_changes):
    they are ok, a, b, Dc, mu0 within 2 % of the truth (not always within 4 standard errors: draw 1's b is 0.2 %,
    4.2 standard errors, off; the hold starts found from the 1 Hz displacement are a sample spacing off at most)."""
    from lab_files import TRUTH, K, make

    lab = make("shs", seed=seed, noise=1e-4)
    rec = Record(lab.t, lab.mu, displacement=lab.disp, k=K, detrend="time")
    start = sweep.FrictionParams.from_lab(0.7 * TRUTH["a"], 1.3 * TRUTH["b"], 1.3 * TRUTH["Dc"], TRUTH["mu0"])
    ds = sweep.fit(rec, free=tuple(TRUTH), params=start, search="local")
    assert int(ds["fit_status"][0]) == 0
    for n, v in TRUTH.items():
        assert float(ds[n][0]) == pytest.approx(v, rel=0.02), n
