"""The load history of a record found from a noisy load-point displacement (sweep.fit.segments): known velocity
steps up and down and a hold, irregular sampling, noise; and a record that starts in a hold is refused."""

from __future__ import annotations

import numpy as np
import pytest

from sweep.errors import InputError
from sweep.fit.records import Record
from sweep.fit.segments import detect_steps, load_history, record_steps

STARTS = np.array([0.0, 40.0, 70.0, 130.0, 160.0])
VELOCITIES = np.array([1e-6, 1e-5, 0.0, 1e-6, 3e-6])  # up 10x, a 60 s hold, reslide, up 3x


def _displacement(t):
    seg = np.searchsorted(STARTS, t, side="right") - 1
    x0 = np.concatenate(([0.0], np.cumsum(VELOCITIES[:-1] * np.diff(STARTS))))
    return x0[seg] + VELOCITIES[seg] * (t - STARTS[seg])


@pytest.mark.parametrize("seed, noise", [(0, 1e-9), (1, 1e-8), (2, 0.0)])
def test_known_steps_found_from_noisy_displacement(seed, noise):
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0.0, 220.0, 3000))
    steps = detect_steps(t, _displacement(t) + noise * rng.standard_normal(t.size))
    assert len(steps) == STARTS.size, steps
    found_t, found_v = np.array(steps).T
    spacing = np.max(np.diff(t))
    np.testing.assert_allclose(found_t[1:], STARTS[1:], atol=2 * spacing)
    assert found_v[2] == 0.0
    np.testing.assert_allclose(found_v, VELOCITIES, rtol=0.01, atol=0)


def test_velocity_column_and_load_history():
    t = np.linspace(0.0, 220.0, 2201)
    v = VELOCITIES[np.searchsorted(STARTS, t, side="right") - 1]
    rec = Record(t, np.full(t.size, 0.6), velocity=v)
    steps = record_steps(rec)
    assert [s[1] == 0.0 for s in steps] == [False, False, True, False, False]
    load = load_history(rec)
    assert load.total == pytest.approx(220.0)
    np.testing.assert_allclose(load.velocities, VELOCITIES, rtol=0.01)


def test_record_starting_in_a_hold_is_refused():
    t = np.linspace(0.0, 100.0, 500)
    x = np.where(t < 50.0, 0.0, 1e-6 * (t - 50.0))
    with pytest.raises(InputError, match="starts in a hold"):
        record_steps(Record(t, np.full(t.size, 0.6), displacement=x))


def _history(starts, velocities, t):
    seg = np.searchsorted(starts, t, side="right") - 1
    x0 = np.concatenate(([0.0], np.cumsum(velocities[:-1] * np.diff(starts))))
    return x0[seg] + velocities[seg] * (t - starts[seg])


def _check(steps, starts, velocities, spacing, rtol=0.01):
    found_t, found_v = np.array(steps).T
    assert found_t.size == starts.size, steps
    np.testing.assert_allclose(found_t[1:], starts[1:], atol=2 * spacing)
    assert np.all((found_v == 0.0) == (velocities == 0.0)), found_v
    np.testing.assert_allclose(found_v, velocities, rtol=rtol, atol=0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_slide_hold_slide_series_short_holds_noisy_displacement(seed):
    """An SHS series (1 um/s, holds of 1, 3, 10, 30, 100 s) at 10 Hz with jitter and 0.1 um of noise on the load
    point, and 100 Hz for 5 s after each reslide (a DAQ that samples faster at a change): every hold found, the
    1 s hold (10 samples, 1 um missing) too."""
    rng = np.random.default_rng(seed)
    starts, velocities, end = [0.0], [1e-6], 50.0
    for hold in (1.0, 3.0, 10.0, 30.0, 100.0):
        starts += [end, end + hold]
        velocities += [0.0, 1e-6]
        end += hold + 50.0
    starts, velocities = np.array(starts), np.array(velocities)
    t = np.concatenate([np.arange(0.0, end, 0.1)] + [np.arange(s, s + 5.0, 0.01) for s in starts[2::2]])
    t = np.unique(np.round(t + 0.004 * rng.uniform(size=t.size), 5))
    x = _history(starts, velocities, t) + 1e-7 * rng.standard_normal(t.size)
    _check(detect_steps(t, x), starts, velocities, 0.1, rtol=0.02)


def test_a_displacement_written_to_its_resolution():
    """0.1 um/s written to 0.1 um (a staircase: one step a second, its neighbour scatter 0): three pieces, not one
    per stair."""
    starts, velocities = np.array([0.0, 100.0, 200.0]), np.array([1e-7, 3e-7, 1e-7])
    t = np.sort(np.random.default_rng(1).uniform(0.0, 300.0, 3000))
    x = np.round(_history(starts, velocities, t) / 1e-7) * 1e-7
    _check(detect_steps(t, x), starts, velocities, np.max(np.diff(t)), rtol=0.02)


def test_a_sawtooth_in_friction_does_not_move_the_steps():
    """Stick-slip (k = 480 1/m below k_c = 500 1/m: a sawtooth in mu after a step to 10 um/s) on an irregularly
    sampled, noisy load point: the record's steps are the load point's, whatever friction does."""
    from reference_records import record_reference

    rng = np.random.default_rng(4)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 2999))))
    mu, disp = record_reference(0.01, 0.015, 1e-5, 0.6, 480.0, [1e-6, 1e-5], [10.0, 50.0], t)
    assert np.ptp(mu[t > 30]) > 0.02  # the sawtooth is there
    rec = Record(t, mu + 1e-4 * rng.standard_normal(t.size), displacement=disp + 5e-8 * rng.standard_normal(t.size))
    _check(record_steps(rec), np.array([0.0, 10.0]), np.array([1e-6, 1e-5]), np.max(np.diff(t)))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_hold_too_short_for_a_piece_is_found_as_the_slides_lag(seed):
    """A 1 s hold between two 50 s slides at 1 um/s, 10 Hz, 0.3 um of noise: 10 samples and 1 um missing, too little
    for the hinge split (it was merged into one slide at 0.985 um/s), found as the lag of the slide after it: the hold
    within 0.3 s (the noise over the velocity), the velocity within 0.5 %. A plain slide under the same noise gets no
    pause."""
    rng = np.random.default_rng(seed)
    starts, velocities = np.array([0.0, 50.0, 51.0]), np.array([1e-6, 0.0, 1e-6])
    t = np.arange(0.0, 101.0, 0.1) + 0.01 * rng.uniform(size=1010)
    _check(detect_steps(t, _history(starts, velocities, t) + 3e-7 * rng.standard_normal(t.size)), starts, velocities,
           0.15, rtol=0.005)
    plain = detect_steps(t, 1e-6 * t + 3e-7 * rng.standard_normal(t.size))
    assert len(plain) == 1 and plain[0][1] == pytest.approx(1e-6, rel=0.005), plain
