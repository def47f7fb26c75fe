"""mu_t of a history scene (friction at the times t_obs, sweep/protocols/history/sampled.py) against the scipy
reference of tests/reference_history.py (Radau at rtol 1e-10, each value a step's end at the sample time)."""

from __future__ import annotations

import numpy as np
import pytest
from reference_history import history_reference_at

import sweep
from sweep.errors import InputError
from sweep.status import Status

P = sweep.FrictionParams.from_lab(a=0.01, b=0.015, Dc=1e-5, mu0=0.6)
K_LAB = 1e3  # [1/m]
SEGMENTS = [{"V_ratio": 1, "duration": 20.0}, {"V_ratio": 10, "duration": 10.0}, {"hold": 30.0},
            {"V_ratio": 1, "duration": 40.0}]
T_OBS = [0.0, 5.0, 20.0, 20.5, 22.0, 29.9, 30.0, 45.0, 60.0, 60.3, 61.0, 70.0, 99.0, 100.0, 150.0]


def scene(**kw):
    return sweep.Scene(protocol="history", params=P, K_over_M=[K_LAB * 9.81], V=[1e-6, 3e-6], rtol=1e-7,
                       model="quasistatic", observables=("mu_end", "mu_t"), t_obs=T_OBS,
                       options={"segments": SEGMENTS}, **kw)


def test_mu_t_against_the_reference():
    ds = sweep.run_sweep(scene())
    assert ds["mu_t"].dims == ("K_over_M", "V", "t_obs") and ds["t_obs"].attrs["units"] == "s"
    assert (ds["status"] == Status.OK).all()
    for j, V in enumerate(ds["V"].values):
        durations = np.array([s.get("duration", s.get("hold")) for s in SEGMENTS])
        inside = np.array(T_OBS) <= durations.sum()
        ref = history_reference_at(P.A, P.m1, P.m2, P.D0, K_LAB * 9.81, V * np.array([1, 10, 0, 1]), durations,
                                   np.array(T_OBS)[inside], m0=P.m0)
        mu = ds["mu_t"].values[0, j]
        assert np.all(np.isnan(mu[~inside]))  # past the history's end
        assert np.abs(mu[inside] - ref).max() <= 1e-7 * P.A * 10
        assert np.all(ds["mu_t_error"].values[0, j, inside] <= 1e-7 * (np.abs(mu[inside]) + P.A))
        # a sample at a segment's end is that segment's mu_end (two drivers, same equations)
        np.testing.assert_allclose(mu[np.isin(T_OBS, [20.0, 30.0, 60.0, 100.0])], ds["mu_end"].values[0, j],
                                   rtol=0, atol=1e-7 * P.A * 10)


def test_mu_t_needs_t_obs():
    with pytest.raises(InputError, match="t_obs"):
        sweep.Scene(protocol="history", params=P, K_over_M=[K_LAB * 9.81], V=[1e-6], observables=("mu_t",),
                    options={"segments": SEGMENTS})
    with pytest.raises(InputError, match="t_obs must be finite, >= 0 and strictly increasing"):
        sweep.Scene(protocol="history", params=P, K_over_M=[1e4], V=[1e-6], observables=("mu_t",), t_obs=(5.0, 1.0),
                    options={"segments": SEGMENTS})


def test_asking_for_mu_t_leaves_the_other_observables_as_they_were():
    """With mu_t the per-segment records come from the dense-output driver: the same steps as the records' own
    driver, so the same numbers, bit for bit."""
    obs = ("mu_end", "delta_mu_ss", "delta_mu_peak", "delta_mu_relax")
    with_t = sweep.run_sweep(scene())
    without = sweep.run_sweep(sweep.Scene(protocol="history", params=P, K_over_M=[K_LAB * 9.81], V=[1e-6, 3e-6],
                                          rtol=1e-7, model="quasistatic", observables=obs,
                                          options={"segments": SEGMENTS}))
    np.testing.assert_array_equal(with_t["mu_end"].values, without["mu_end"].values)
    np.testing.assert_array_equal(with_t["mu_end_error"].values, without["mu_end_error"].values)
