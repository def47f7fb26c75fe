"""Stick-slip (sawtooth) records fitted from a realistic start (issue 34, sweep/fit/event_fit.py): synthetic records
from the independent scipy reference of Newton's law (tests/reference_history.inertial_reference_at, Radau at rtol
1e-10; the records of tests/fit/test_records_stickslip.py), noise 2e-4 estimated, starts 30 % off in a, b and Dc."""

from __future__ import annotations

import warnings

import numpy as np
from reference_history import inertial_reference_at
from test_records_stickslip import MU0, NOISE, SHORT_LOAD, STEP, A, B, sawtooth

import sweep
from sweep.fit.records import Record
from sweep.fit.verdict import FIT_STATUS

FREE = ("a", "b", "Dc", "mu0")


def _fit(rec: Record, Dc: float, start: dict[str, float]):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sweep.fit(rec, free=FREE, params=sweep.FrictionParams.from_lab(A, B, Dc, MU0), start=start)


def _outcome(ds, truth: dict[str, float]) -> tuple[str, float, bool]:
    """(fit_status, estimated noise / drawn noise, whether every 95 % interval covers the truth)."""
    cover = all(float(ds[f"{n}_lower"][0]) <= v <= float(ds[f"{n}_upper"][0]) for n, v in truth.items())
    return FIT_STATUS[int(ds["fit_status"][0])], float(ds["datum_noise"][0]) / NOISE, cover


def test_event_times_between_samples():
    """event_times of a fall that is a linear ramp 1.6 sample intervals long (a slip as the inertial model resolves
    it), on a rising line, moved in 21 steps across one sample interval: the event's time follows the ramp's middle
    within 0.2 intervals (measured: 0.15), never going back, where the index of the event's sample jumps by one."""
    from sweep.fit.events import event_scale, event_times, slip_events

    dt = 0.05
    t = np.arange(0.0, 20.0, dt)
    mids = np.linspace(5.0, 5.0 + dt, 21)
    times, starts = [], []
    for m in mids:
        mu = 0.6 + 2e-3 * t - 0.08 * np.clip((t - m) / (1.6 * dt) + 0.5, 0.0, 1.0)
        ev = slip_events(mu, event_scale(t, mu))
        assert len(ev) == 1
        times.append(event_times(t, mu, ev)[0][0])
        starts.append(ev[0][0])
    assert np.max(np.abs(np.array(times) - mids)) < 0.2 * dt
    assert np.all(np.diff(times) >= 0) and starts[-1] == starts[0] + 1


def test_aligned_residuals_of_a_model_late_by_a_shift():
    """The aligned residuals (event_fit._Events) of the reference sawtooth against the same reference 0.3 s later
    (~7 samples; noise-free): after the event they compare the record with the model in time since its own slip,
    so they are ~0 (interpolation between samples) where the plain residuals hold the full fall on ~7 samples; the
    event's time term is w F (0.3 s)/dt to within the sampling of the fall (one interval), its fall term ~0."""
    from sweep.fit.event_fit import _Events

    t, mu, disp, k = sawtooth(1e-5, 9.81, 600, seed=3, load=SHORT_LOAD)
    late, _ = inertial_reference_at(A, B - A, 0.0, 1e-5, k * 9.81, STEP.velocities, [5.3, 20.0], t, m0=MU0, V0=1e-6,
                                    g=9.81)  # the step 0.3 s later: everything after it is 0.3 s later
    rec = Record(t, mu, displacement=disp, k=k)
    ev = _Events(rec, slice(0, t.size))
    w = np.full(t.size, 1.0 / NOISE)
    out = ev.aligned(late, w)
    after = ev.phase == 1
    plain = (late - mu) * w
    assert ev.n == 1 and np.max(np.abs(plain[after])) > 300  # the fall, in noise units
    assert np.sqrt(np.mean(out[:t.size][after] ** 2)) < 0.02 * np.sqrt(np.mean(plain[after] ** 2))
    dt_term = out[t.size] / (ev.falls[0] / NOISE / ev.dt)  # the model's event time less the record's [s]
    assert abs(dt_term - 0.3) < np.max(np.diff(t))
    assert abs(out[t.size + 1]) < 0.05 * ev.falls[0] / NOISE


def test_records_without_events_take_no_event_stage():
    """event_start leaves the starts of a stable velocity-step record (the reference, k = 2e3/m) as they are and
    solves nothing (the fit of records without events is unchanged)."""
    from reference_records import record_reference

    from sweep.fit.event_fit import event_start
    from sweep.fit.problem import make_problems
    from sweep.fit.record_forward import RecordStack, make_record_space

    rng = np.random.default_rng(5)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 599))))
    mu, disp = record_reference(A, B, 1e-5, MU0, 2e3, [1e-6, 1e-5], [20.0, 40.0], t)
    rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=2e3)
    space = make_record_space(FREE, sweep.FrictionParams.from_lab(A, B, 1e-5, MU0), 2e3)
    stack = RecordStack(make_problems([rec], space, False), 1e-6, estimates=False)
    theta = [space.start * 1.1]
    out = event_start(stack, theta, space.start)
    assert stack.rounds == 0 and np.array_equal(out[0], theta[0])


def test_one_event_sawtooth_fitted_from_starts_30_percent_off():
    """Six noise draws of the one-event sawtooth (Dc = 10 um, k = 250/m, 600 irregular samples over 25 s), each
    from a start 30 % off in a, b and Dc (each up or down at random), global stage and profiles as by default: the
    fit ends ok with every 95 % interval covering the truth on >= 5 of the 6 (measured: 6; before the event stage,
    1; with boxes of starts in a and Dc only, 5), and never ok otherwise: an ok fit's estimated noise is the drawn
    one within 15 %, a failed fit says events_missed or poor_fit (measured with the smaller boxes: one
    events_missed, a local minimum with the record's event whose residuals are serially correlated, noise 1.14x)."""
    t, mu, disp, k = sawtooth(1e-5, 9.81, 600, seed=3, load=SHORT_LOAD)
    truth = {"a": A, "b": B, "Dc": 1e-5, "mu0": MU0}
    rng = np.random.default_rng(21)
    good = 0
    for i in range(6):
        rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=k, name=f"d{i}")
        f = rng.choice([0.7, 1.3], 3)
        status, noise, cover = _outcome(_fit(rec, 1e-5, {"a": A * f[0], "b": B * f[1], "Dc": 1e-5 * f[2]}), truth)
        assert status in ("ok", "events_missed", "poor_fit"), status
        assert status != "ok" or abs(noise - 1) < 0.15, noise
        good += status == "ok" and cover
    assert good >= 5, good


def test_one_event_sawtooth_with_k_free():
    """The one-event sawtooth with k free too (the record without k), one draw from 30 % off in a, b, Dc and k: ok,
    the noise within 15 %, all five intervals covering the truth (measured: 6 of 6 draws from other 30 % starts,
    7.6-10.7 s each)."""
    t, mu, disp, k = sawtooth(1e-5, 9.81, 600, seed=3, load=SHORT_LOAD)
    truth = {"a": A, "b": B, "Dc": 1e-5, "mu0": MU0, "k": k}
    rng = np.random.default_rng(21)
    rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = sweep.fit(rec, free=tuple(truth), params=sweep.FrictionParams.from_lab(A, B, 1e-5, MU0),
                       start={"a": 1.3 * A, "b": 0.7 * B, "Dc": 0.7e-5, "k": 0.7 * k})
    status, noise, cover = _outcome(ds, truth)
    assert status == "ok" and abs(noise - 1) < 0.15 and cover, (status, noise, cover)


def _never_ok_wrongly(ds, truth: dict[str, float]) -> str:
    """The fit's status, asserting that an ok fit has the drawn noise (within 15 %) and intervals that cover."""
    status, noise, cover = _outcome(ds, truth)
    assert status != "ok" or (abs(noise - 1) < 0.15 and cover), (status, noise, cover)
    return status


def test_irregularly_sampled_sawtooth_is_never_ok_wrongly():
    """A one-event sawtooth sampled at two rates (200 samples over 25 s and 150 more in 8-14 s, where the event is)
    with a 1 s gap: one draw from a start 30 % off: ok, the noise within 15 %, the intervals covering. Measured (4
    draws): 4 ok at noise 0.96-1.06x, 3 with all four intervals covering (before the stick-slip problems' finer
    forward differences, event_fit.EVENT_FD_STEP: 3 not_converged and 1 events_missed at noise 1.05-1.7x)."""
    rng = np.random.default_rng(11)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 25.0, 200), rng.uniform(8.0, 14.0, 150))))
    t = t[(t < 15.5) | (t > 16.5)]
    k = 0.5 * (B - A) / 1e-5
    mu, _ = inertial_reference_at(A, B - A, 0.0, 1e-5, k * 9.81, STEP.velocities, [5.0, 20.0], t, m0=MU0, V0=1e-6,
                                  g=9.81)
    disp = np.interp(t, [0.0, 5.0, 25.0], [0.0, 5e-6, 5e-6 + 2e-4])
    truth = {"a": A, "b": B, "Dc": 1e-5, "mu0": MU0}
    rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=k)
    f = rng.choice([0.7, 1.3], 3)
    assert _never_ok_wrongly(_fit(rec, 1e-5, {"a": A * f[0], "b": B * f[1], "Dc": 1e-5 * f[2]}), truth) == "ok"


def test_three_event_sawtooth_fitted_from_starts_30_percent_off():
    """The three-event sawtooth (Dc = 3 um, k = 833/m, 600 samples over 35 s), six draws, each from a start 30 % off
    in a, b and Dc: ok with every 95 % interval covering the truth on >= 5 (measured: 6, 2.9-3.8 s a fit; from 2 %
    off also 6), never ok otherwise. Its misfit's valley is ~0.25 % wide in b: the event stage on the records cut
    after their first event, then one event more at a time, each least squares with forward differences of 1e-5
    (event_fit.EVENT_FD_STEP). Without the continuation: 0 of 6 (3 not_converged, 3 events_missed); with it but
    the default differences of 1e-3: 1 of 6 ok, its intervals not covering."""
    t, mu, disp, k = sawtooth(3e-6, 9.81, 600, seed=3)
    truth = {"a": A, "b": B, "Dc": 3e-6, "mu0": MU0}
    rng = np.random.default_rng(21)
    good = 0
    for i in range(6):
        rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=k, name=f"d{i}")
        f = rng.choice([0.7, 1.3], 3)
        ds = _fit(rec, 3e-6, {"a": A * f[0], "b": B * f[1], "Dc": 3e-6 * f[2]})
        good += _never_ok_wrongly(ds, truth) == "ok"
    assert good >= 5, good


def test_the_continuation_cuts_a_record_between_its_events():
    """event_fit._cut: the three-event record cut after its first and second events keeps one and two of them (the
    cut midway to the next), after its third (or more) the whole record."""
    from sweep.fit.event_fit import _cut
    from sweep.fit.events import record_slip_events

    t, mu, disp, k = sawtooth(3e-6, 9.81, 600, seed=3)
    rec = Record(t, mu + NOISE * np.random.default_rng(2).standard_normal(t.size), displacement=disp, k=k)
    events = record_slip_events(rec)
    assert len(events) == 3
    for j in (1, 2):
        cut = _cut(rec, j)
        assert len(record_slip_events(cut)) == j and events[j - 1][0] < cut.n < events[j][0]
    assert _cut(rec, 3) is rec and _cut(rec, 5) is rec
