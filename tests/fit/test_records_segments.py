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
