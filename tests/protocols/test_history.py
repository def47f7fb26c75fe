"""The history protocol (issue 34) against an independent scipy reference of the spring-slider
(tests/reference_history.py: Radau at rtol 1e-10 in physical units), the analytic steady-state jump, the stop and
driven scenes, and a run through a file."""

from __future__ import annotations

import numpy as np
import pytest
from reference_history import history_reference

import sweep
from sweep.errors import InputError
from sweep.integrate.driven import Regime

P = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)
K, V = 3e5, 1e-6  # chi = 0.021 > mu1 = 0.0125: steady sliding stable
RTOL = 1e-8
TOL = 2e-9  # friction units: rtol x (|dmu| + A) x 30 at most


def history(segments, params=P, K_over_M=K, V=V, **kw):
    scene = sweep.Scene(protocol="history", params=params, K_over_M=[K_over_M], V=[V], rtol=RTOL,
                        model="quasistatic", options={"segments": segments, **kw.pop("options", {})}, **kw)
    return sweep.run_sweep(scene).isel(K_over_M=0, V=0)


def reference(segments, params=P, K_over_M=K, V=V, **kw):
    return history_reference(params.A, params.m1, params.m2, params.D0, K_over_M, V, segments, m0=params.m0, **kw)[0]


def mu_ss(params, v):
    lv = np.log(v / params.V0)
    return params.m0 - params.m1 * lv + params.m2 * lv**2


@pytest.mark.parametrize("law", ["aging", "slip"])
def test_velocity_steps_up_and_down(law):
    segs = [{"V_ratio": 1, "displacement": 5e-6}, {"V_ratio": 10, "displacement": 3e-5},
            {"V_ratio": 0.3, "displacement": 1e-5}]
    ds, ref = history(segs, state_law=law), reference(segs, law=law)
    got = ds.mu_end.values
    want = np.array([r["mu_end"] for r in ref])
    assert np.all(ds.status.values == 0)
    np.testing.assert_allclose(got, want, rtol=0, atol=TOL)
    assert np.all(ds.mu_end_error.values <= TOL)


@pytest.mark.parametrize("law", ["aging", "slip"])
def test_slide_hold_slide(law):
    segs = [{"V_ratio": 1, "displacement": 2e-5}]
    for hold in (1.0, 10.0, 100.0):
        segs += [{"hold": hold}, {"V_ratio": 1, "displacement": 2e-5}]
    ds, ref = history(segs, state_law=law), reference(segs, law=law)
    assert np.all(ds.status.values == 0)
    np.testing.assert_allclose(ds.mu_end.values, [r["mu_end"] for r in ref], rtol=0, atol=TOL)
    relax = [r["mu_start"] - r["mu_end"] if s.get("hold") else np.nan for s, r in zip(segs, ref)]
    np.testing.assert_allclose(ds.delta_mu_relax.values, relax, rtol=0, atol=TOL)
    peak = [np.nan] + [r["mu_peak"] - mu_ss(P, V) if "hold" in segs[j - 1] else np.nan
                       for j, r in enumerate(ref) if j > 0]
    np.testing.assert_allclose(ds.delta_mu_peak.values, peak, rtol=0, atol=TOL)
    if law == "aging":  # the aging law heals at rest: longer holds, higher peaks
        assert np.all(np.diff(ds.delta_mu_peak.values[2::2]) > 0)


def test_steady_state_jump_is_a_minus_b_ln_ratio_at_m2_zero():
    """Lab parameterisation a = A, b = A + m1, Dc = D0 at m2 = 0: Delta mu_ss = (a - b) ln(V2/V1)."""
    p = sweep.FrictionParams(A=0.007, m1=0.004, m2=0.0, D0=0.7e-6)
    a, b = p.A, p.A + p.m1
    segs = [{"V_ratio": 1, "displacement": 1e-5}, {"V_ratio": 10, "displacement": 2e-4},
            {"V_ratio": 1, "displacement": 2e-4}]
    ds = history(segs, params=p)
    want = [np.nan, (a - b) * np.log(10), (a - b) * np.log(0.1)]
    np.testing.assert_allclose(ds.delta_mu_ss.values, want, rtol=0, atol=TOL)


def test_one_long_hold_is_the_stop_scene():
    """The stop's stress relaxation chi xi_inf = Delta mu_relax of an (effectively) infinite hold."""
    hold = 1e8 * P.D0 / V
    ds = history([{"V_ratio": 1, "displacement": 1e-6}, {"hold": hold}])
    stop = sweep.run_sweep(sweep.Scene(protocol="stop", params=P, K_over_M=[K], V=[V], rtol=RTOL,
                                       model="quasistatic", observables=["xi_inf"]))
    want = float(stop.stress_relaxation.values[0, 0])
    assert ds.delta_mu_relax.values[1] == pytest.approx(want, abs=TOL)


@pytest.mark.parametrize("K_over_M, regime, span", [(3e5, Regime.STEADY, 2000), (1.2e5, Regime.STICK_SLIP, 100)])
def test_one_perturbed_segment_is_the_driven_scene(K_over_M, regime, span):
    """One segment at V from a stretched spring: back to steady sliding where the driven scene finds it steady
    (mu_end = mu_ss(V), the segment flagged steady by a second one), oscillating where it finds stick-slip (over
    ``span`` D0/V: the reference's Radau takes ~1 s per 30 D0/V of stick-slip)."""
    driven = sweep.run_sweep(sweep.Scene(protocol="driven", params=P, K_over_M=[K_over_M], V=[V], rtol=1e-6,
                                         model="quasistatic", perturbation=0.05))
    assert driven.regime.values[0, 0] == regime
    segs = [{"V_ratio": 1, "duration": span * P.D0 / V}, {"V_ratio": 1, "duration": 10 * P.D0 / V}]
    ds = history(segs, K_over_M=K_over_M, options={"perturbation": 0.05})
    ref = reference(segs, K_over_M=K_over_M, stretch=0.05 * P.D0)
    np.testing.assert_allclose(ds.mu_end.values, [r["mu_end"] for r in ref], rtol=0, atol=1e3 * TOL)
    steady = np.isfinite(ds.delta_mu_ss.values[1])
    assert steady == (regime == Regime.STEADY)


def test_run_through_a_file(tmp_path):
    segs = [{"V_ratio": 1, "displacement": 2e-5}, {"hold": 10.0}, {"V_ratio": 1, "displacement": 2e-5}]
    scene = sweep.Scene(protocol="history", params=P, K_over_M=[2e5, 3e5], V=[1e-6, 2e-6], rtol=1e-6,
                        model="quasistatic", options={"segments": segs})
    out = tmp_path / "h.nc"
    ds = sweep.run_sweep(scene, output=out)
    back = sweep.open(out)
    assert back.mu_end.dims == ("K_over_M", "V", "segment")
    np.testing.assert_array_equal(back.mu_end.values, ds.mu_end.values)
    assert back.delta_mu_peak.attrs["units"] == "1" and list(back.V_ratio.values) == [1, 0, 1]
    assert sweep.load_scene(_toml(tmp_path, scene)).options.segments == scene.options.segments


def _toml(tmp_path, scene):
    path = tmp_path / "scene.toml"
    path.write_text(scene.to_toml())
    return path


@pytest.mark.parametrize("segments, words", [
    ([], "1 to"),
    ([{"V_ratio": 1, "duration": -1.0}], "duration must be > 0"),
    ([{"V_ratio": -1, "duration": 1.0}], "V_ratio must be >= 0"),
    ([{"V_ratio": 1, "duration": 1.0, "displacement": 1e-6}], "exactly one of duration"),
    ([{"V_ratio": 1}], "exactly one of duration"),
    ([{"hold": 3.0}], "segments[0]: V_ratio must be > 0"),
    ([{"V_ratio": 1, "duration": 1.0}, {"V_ratio": 0, "displacement": 1e-6}], "needs V_ratio > 0"),
    ([{"V_ratio": 1, "slip": 1.0}], "unknown key"),
])
def test_bad_segments_are_refused_in_one_line(segments, words):
    with pytest.raises(InputError, match=None) as info:
        sweep.Scene(protocol="history", params=P, K_over_M=[K], V=[V], model="quasistatic",
                    options={"segments": segments})
    assert words in str(info.value) and "\n" not in str(info.value)


def test_auto_model_refused_where_inertia_matters_without_an_inertial_law():
    """The slip law has no inertial model: model "auto" is refused where inertia matters (the aging law runs it:
    tests/protocols/test_history_inertial.py)."""
    with pytest.raises(InputError, match="no inertial model for the slip law"):
        sweep.Scene(protocol="history", params=P, K_over_M=[K], V=[1e-4], state_law="slip", options={"segments": [
            {"V_ratio": 1, "duration": 1.0}]})


def test_one_perturbed_segment_decays_at_the_driven_scenes_growth_rate():
    """The history's mu(t) (mu_t, dense output) over one perturbed segment below the Hopf line: the growth rate and
    period of its oscillation from successive peaks (parabola through the samples) are the driven scene's, measured
    on its own envelope, to 1e-3 once the first cycle's nonlinearity has decayed (measured 5e-4 and 3e-4)."""
    K_over_M = 2.2e5
    driven = sweep.run_sweep(sweep.Scene(protocol="driven", params=P, K_over_M=[K_over_M], V=[V], rtol=1e-6,
                                         model="quasistatic", perturbation=0.05)).isel(K_over_M=0, V=0)
    growth, period = float(driven.growth_rate), float(driven.period)
    assert growth < 0
    t = np.linspace(0.0, 4 * period * P.D0 / V, 4001)
    ds = history([{"V_ratio": 1, "duration": t[-1]}], K_over_M=K_over_M, observables=("mu_end", "mu_t"),
                 t_obs=tuple(t), options={"perturbation": 0.05})
    mu = ds.mu_t.values - mu_ss(P, V)
    i = np.flatnonzero((mu[1:-1] > mu[:-2]) & (mu[1:-1] >= mu[2:])) + 1
    y0, y1, y2 = mu[i - 1], mu[i], mu[i + 1]
    off = 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    peak, tau = y1 - 0.25 * (y0 - y2) * off, (t[i] + off * (t[1] - t[0])) * V / P.D0
    assert i.size >= 4
    assert np.log(peak[-1] / peak[-2]) / (tau[-1] - tau[-2]) == pytest.approx(growth, rel=1e-3)
    assert tau[-1] - tau[-2] == pytest.approx(period, rel=1e-3)
