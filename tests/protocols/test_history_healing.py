"""The healing rate beta = d Delta mu_peak / d log10 t_h of a slide-hold-slide series (sweep/protocols/history/
healing.py): the least squares against numpy's polyfit, its error bound, and a scene's beta against the peaks of
the scipy reference (tests/reference_history.py, Radau at rtol 1e-10)."""

from __future__ import annotations

import numpy as np
from reference_history import history_reference

import sweep
from sweep.protocols.history.healing import healing_rate, hold_before, is_series

P = sweep.FrictionParams.from_lab(a=0.01, b=0.015, Dc=1e-5, mu0=0.6)
K_LAB, V = 1e3, 1e-6
HOLDS = (1.0, 10.0, 100.0, 1000.0)


def shs(holds, slide=2e-5):
    segs = [{"V_ratio": 1, "displacement": slide}]
    for t_h in holds:
        segs += [{"hold": t_h}, {"V_ratio": 1, "displacement": slide}]
    return segs


def test_least_squares_is_polyfit_and_its_error_a_bound():
    rng = np.random.default_rng(3)
    t_hold = np.array([[np.nan, 1.0, np.nan, 10.0, np.nan, 100.0, np.nan, 1000.0],
                       [np.nan, 3.0, np.nan, 30.0, np.nan, np.nan, np.nan, np.nan],
                       [np.nan, 5.0, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan]])
    peak = np.where(np.isfinite(t_hold), 0.004 * np.log10(np.nan_to_num(t_hold, nan=1.0)) + 0.01, np.nan)
    peak[0, 5] = np.nan  # a failed peak is left out
    peak += rng.normal(0, 1e-4, peak.shape)
    error = np.where(np.isfinite(peak), rng.uniform(1e-8, 1e-6, peak.shape), np.nan)
    beta, beta_error = healing_rate(peak, error, t_hold)
    for i in range(2):
        use = np.isfinite(peak[i]) & np.isfinite(t_hold[i])
        np.testing.assert_allclose(beta[i], np.polyfit(np.log10(t_hold[i, use]), peak[i, use], 1)[0], rtol=1e-10)
        # the bound: the largest change of the slope when each peak moves by its error
        x = np.log10(t_hold[i, use])
        worst = np.polyfit(x, peak[i, use] + error[i, use] * np.sign(x - x.mean()), 1)[0]
        np.testing.assert_allclose(abs(worst - beta[i]), beta_error[i], rtol=1e-6)
    assert np.isnan(beta[2]) and np.isnan(beta_error[2])  # one hold: no slope


def test_hold_before_and_series():
    ratios = np.array([1.0, 0.0, 1.0, 0.0, 2.0])
    durations = np.array([[5.0, 10.0, 5.0, 100.0, 5.0]])
    np.testing.assert_array_equal(hold_before(ratios, durations), [[np.nan, np.nan, 10.0, np.nan, 100.0]])
    segs = sweep.Scene(protocol="history", params=P, K_over_M=[1e4], V=[V], options={"segments": shs(HOLDS)})
    assert is_series(segs.options.segments) and not is_series(shs((1.0,)))


def test_scene_beta_against_the_reference():
    ds = sweep.run_sweep(sweep.Scene(protocol="history", params=P, K_over_M=[K_LAB * 9.81], V=[V], rtol=1e-7,
                                     model="quasistatic", options={"segments": shs(HOLDS)})).isel(K_over_M=0, V=0)
    ref = history_reference(P.A, P.m1, P.m2, P.D0, K_LAB * 9.81, V, shs(HOLDS), m0=P.m0)[0]
    peaks = np.array([ref[j]["mu_peak"] for j in range(2, 2 * len(HOLDS) + 1, 2)]) - P.m0  # mu_ss(V0) = mu0
    beta_ref = np.polyfit(np.log10(HOLDS), peaks, 1)[0]
    assert 0.1 * P.to_lab()["b"] < beta_ref < P.to_lab()["b"] * np.log(10)  # healing: below b ln 10 per decade
    assert abs(float(ds.beta) - beta_ref) <= 1e-6 * P.A
    assert float(ds.beta_error) <= 1e-6 * P.A and ds.beta.attrs["units"] == "1"
