"""friction_at (sweep/protocols/history/forward.py), the forward model of record fits, against the independent scipy
reference of tests/reference_history.py (Radau at rtol 1e-10, each value a step's end at the sample time): steps up
and down, holds and a slide-hold-slide for both state laws, at rtol 1e-6 and 1e-8, with irregular sampling."""

from __future__ import annotations

import numpy as np
import pytest
from reference_history import history_reference_at, inertial_reference_at

import sweep
from sweep.errors import InputError
from sweep.protocols.history.forward import LoadHistory, friction_at
from sweep.status import Status

LAB = sweep.FrictionParams.from_lab(a=0.01, b=0.015, Dc=1e-5, mu0=0.6)  # m2 = 0
PAPER = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)  # a preset-like m2 > 0
SHS = LoadHistory(np.array([1e-6, 1e-5, 0.0, 1e-6, 3e-7]), np.array([20.0, 10.0, 30.0, 40.0, 30.0]))


def params_of(fp: sweep.FrictionParams, k_lab: float) -> dict[str, float]:
    return {"A": fp.A, "m1": fp.m1, "m2": fp.m2, "D0": fp.D0, "m0": fp.m0, "V0": fp.V0, "K_over_M": k_lab * 9.81}


def sample_times(load: LoadHistory, n: int, seed: int = 0) -> np.ndarray:
    """Irregular times over the whole history, with its start, end and segment boundaries among them."""
    t = np.random.default_rng(seed).uniform(0.0, load.total, n)
    return np.sort(np.concatenate([t, [0.0, load.total], np.cumsum(load.durations)[:-1]]))


def reference(fp, k_lab, load, t, law="aging", stretch=0.0):
    return history_reference_at(fp.A, fp.m1, fp.m2, fp.D0, k_lab * 9.81, load.velocities, load.durations, t,
                                law=law, m0=fp.m0, V0=fp.V0, stretch=stretch)


CASES = {  # name: (friction law, k [1/m], history, state law, stretch [m])
    "shs_aging": (LAB, 1e3, SHS, "aging", 0.0),
    "shs_slip": (LAB, 1e3, SHS, "slip", 0.0),
    "steps_m2_stretched": (PAPER, 5e5 / 9.81, LoadHistory(np.array([1e-6, 1e-5, 1e-7]), np.array([5.0, 3.0, 60.0])),
                           "aging", 2e-8),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_friction_at_against_the_reference(name):
    fp, k_lab, load, law, stretch = CASES[name]
    t = sample_times(load, 150)
    ref = reference(fp, k_lab, load, t, law, stretch)
    assert np.ptp(ref) > 10 * fp.A * 1e-2  # the history moves mu
    for rtol in (1e-6, 1e-8):
        out = friction_at(params_of(fp, k_lab), load, t, state_law=law, rtol=rtol, stretch=stretch)
        assert out.mu.shape == out.error.shape == (1, t.size) and out.status.tolist() == [Status.OK]
        true = np.abs(out.mu[0] - ref)
        # stricter than rtol (|mu| + A): the accuracy of s = (mu - mu_ss(V))/A that the stepper controls
        scale = rtol * (fp.A + np.abs(ref - ref[0]))
        assert np.all(true <= scale), (rtol, np.max(true / scale))
        # the estimate is the looser run's error: it bounds the largest error, and the error sample by sample where
        # the two runs' errors do not happen to be alike (a few % of the samples, measured)
        assert true.max() <= out.error.max()
        assert np.mean(true <= out.error[0]) >= 0.9
        assert np.all(out.error[0] <= rtol * (np.abs(out.mu[0]) + fp.A))


def test_error_falls_with_rtol():
    """The dp5 runs converge: the true error at rtol 1e-8 is below a tenth of that at rtol 1e-6 (both well above
    the reference's accuracy)."""
    fp, k_lab, load, law, stretch = CASES["shs_aging"]
    t = sample_times(load, 60, seed=1)
    ref = reference(fp, k_lab, load, t)
    err = [np.abs(friction_at(params_of(fp, k_lab), load, t, rtol=r).mu[0] - ref).max() for r in (1e-5, 1e-7)]
    assert err[1] < err[0] / 10


def test_many_sets_in_one_call_are_each_set_alone():
    load = SHS
    t = sample_times(load, 500, seed=2)
    p = params_of(LAB, 1e3)
    sets = {**p, "m1": p["m1"] * np.array([0.5, 1.0, 1.5]), "D0": p["D0"] * np.array([1.0, 2.0, 0.5])}
    many = friction_at(sets, load, t)
    assert many.mu.shape == (3, t.size)
    for i in range(3):
        one = friction_at({**p, "m1": sets["m1"][i], "D0": sets["D0"][i]}, load, t)
        np.testing.assert_array_equal(many.mu[i], one.mu[0])
        np.testing.assert_array_equal(many.error[i], one.error[0])


def test_steady_sliding_stays_at_mu_ss_and_a_step_reaches_the_analytic_jump():
    """Constant load-point velocity: mu = mu_ss(V) at every time; a long step V -> 10 V ends at (a - b) ln 10."""
    p = params_of(LAB, 1e3)
    flat = friction_at(p, LoadHistory(np.array([1e-6]), np.array([100.0])), np.linspace(0, 100, 11), rtol=1e-8)
    np.testing.assert_allclose(flat.mu[0], LAB.m0, rtol=0, atol=1e-12)
    step = friction_at(p, LoadHistory(np.array([1e-6, 1e-5]), np.array([1.0, 200.0])), [0.5, 201.0], rtol=1e-8)
    a, b = LAB.to_lab()["a"], LAB.to_lab()["b"]
    assert step.mu[0, 1] - step.mu[0, 0] == pytest.approx((a - b) * np.log(10), abs=1e-9)


def test_status_flags_inertia_and_step_budget():
    p = params_of(LAB, 1e3)
    # gamma/A = v^2/(g D0 A) at 30 um/s: 9e-4 with D0 = 10 um, 0.9 with D0 = 10 nm (k > (b - a)/Dc: stable)
    sets = {**p, "D0": [1e-5, 1e-8], "K_over_M": [1e3 * 9.81, 1e6 * 9.81]}
    load = LoadHistory(np.array([1e-5, 3e-5]), np.array([1.0, 1.0]))
    fast = friction_at(sets, load, [0.0, 2.0])
    assert fast.status.tolist() == [Status.OK, Status.OK] and fast.model.tolist() == [0, 1]
    slip = friction_at(sets, load, [0.0, 2.0], state_law="slip")  # no inertial slip law: flagged
    assert slip.status.tolist() == [Status.OK, Status.QUASISTATIC_BREAKDOWN] and slip.model.tolist() == [0, 0]
    short = friction_at(p, SHS, [0.0, 50.0, SHS.total], max_steps=20)
    assert short.status.tolist() == [Status.MAX_STEPS] and np.isnan(short.mu[0, -1])


def test_inertial_sets_against_newtons_law():
    """Where gamma/A > INERTIA_LIMIT the set runs with inertia: against Newton's law integrated by Radau
    (tests/reference_history.inertial_reference_at), a step up, a hold and a reslide at gamma/A = 0.1..0.9."""
    fp = sweep.FrictionParams(A=0.01, m1=0.005, m2=0.0, D0=1e-6, m0=0.6)
    load = LoadHistory(np.array([1e-4, 3e-4, 0.0, 1e-4]), np.array([0.05, 0.05, 0.2, 0.1]))
    t = sample_times(load, 40, seed=4)
    ref, _ = inertial_reference_at(fp.A, fp.m1, fp.m2, fp.D0, 2e4 * 9.81, load.velocities, load.durations, t,
                                   m0=fp.m0)
    out = friction_at(params_of(fp, 2e4), load, t, rtol=1e-6)
    assert out.model.tolist() == [1] and out.status.tolist() == [Status.OK]
    assert np.abs(out.mu[0] - ref).max() <= 1e-6 * fp.A * 3
    assert np.abs(out.mu[0] - ref).max() <= out.error.max()


def test_a_soft_spring_runs_away_quasistatically_and_is_run_with_inertia():
    """k = 0.5 (b - a)/Dc: after a step 1 -> 10 um/s the quasi-static equations run away (v -> inf in finite time:
    the Radau reference of the quasi-static model cannot pass it), so friction_at runs the set with inertia (aging
    law; a record's inertia N/M = 1e3 m/s^2 as g: gamma/A = 1e-6 at 10 um/s, far below INERTIA_LIMIT), which gives
    the stick-slip sawtooth of Newton's law (Radau); the slip law, with no inertial model, is flagged."""
    k_lab, g = 0.5 * 5e-3 / LAB.D0, 1e3
    load = LoadHistory(np.array([1e-6, 1e-5]), np.array([5.0, 20.0]))
    t = sample_times(load, 150, seed=5)
    p = {**params_of(LAB, k_lab), "K_over_M": k_lab * g, "g": g}
    with pytest.raises(AssertionError, match="step size"):  # no quasi-static solution past the runaway
        history_reference_at(LAB.A, LAB.m1, LAB.m2, LAB.D0, k_lab * g, load.velocities, load.durations, t, g=g,
                             m0=LAB.m0, V0=LAB.V0)
    ref, _ = inertial_reference_at(LAB.A, LAB.m1, LAB.m2, LAB.D0, k_lab * g, load.velocities, load.durations, t,
                                   m0=LAB.m0, V0=LAB.V0, g=g)
    assert np.ptp(ref[t > 6.0]) > 5 * LAB.A  # a sawtooth: stress drops of several A
    out = friction_at(p, load, t, rtol=1e-6)
    assert out.model.tolist() == [1] and out.status.tolist() == [Status.OK]
    assert np.abs(out.mu[0] - ref).max() <= 1e-6 * LAB.A
    assert np.abs(out.mu[0] - ref).max() <= out.error.max()
    slip = friction_at(p, load, t, state_law="slip")
    assert slip.status.tolist() == [Status.QUASISTATIC_BREAKDOWN] and slip.model.tolist() == [0]
    assert np.all(np.isfinite(slip.mu[0, t < 5.0])) and np.isnan(slip.mu[0, -1])


@pytest.mark.parametrize(("kwargs", "field"), [
    ({"velocities": [0.0, 1e-6], "durations": [1.0, 1.0]}, "velocities[0]"),
    ({"velocities": [1e-6, -1e-6], "durations": [1.0, 1.0]}, "velocities"),
    ({"velocities": [1e-6], "durations": [0.0]}, "durations"),
    ({"velocities": [1e-6, 1e-6], "durations": [1.0]}, "durations"),
    ({"velocities": [1e-6, np.nan], "durations": [1.0, 1.0]}, "velocities"),
])
def test_bad_history_is_refused(kwargs, field):
    with pytest.raises(InputError, match=field.replace("[", r"\[")):
        LoadHistory(**{k: np.array(v) for k, v in kwargs.items()})


@pytest.mark.parametrize(("change", "field"), [
    ({"A": -0.01}, "A"), ({"D0": 0.0}, "D0"), ({"K_over_M": np.nan}, "K_over_M"),
    ({"m1": [1, 2, 3], "A": [1, 2]}, "broadcast"), ({"Dc": 1e-5}, "unknown"), ({"g": 0.0}, "g"),
])
def test_bad_params_are_refused(change, field):
    with pytest.raises(InputError, match=field):
        friction_at({**params_of(LAB, 1e3), **change}, SHS, [0.0, 1.0])


@pytest.mark.parametrize(("t", "kw", "field"), [
    ([1.0, 0.5], {}, "sorted"), ([0.0, SHS.total * 1.01], {}, r"t must lie"), ([-1.0], {}, "t must lie"),
    ([0.0], {"rtol": 1.0}, "rtol"), ([0.0], {"state_law": "ruina"}, "state_law"),
    ([0.0], {"max_steps": 0}, "max_steps"),
])
def test_bad_times_and_options_are_refused(t, kw, field):
    with pytest.raises(InputError, match=field):
        friction_at(params_of(LAB, 1e3), SHS, t, **kw)
