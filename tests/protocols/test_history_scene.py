"""The history scene's surface (issue 34): sweeps over a history's own numbers (a segment's hold, duration,
displacement or V_ratio naming a grid axis), against the independent scipy reference (tests/reference_history.py:
Radau at rtol 1e-10) and the analytic steady-state jump; the axes' units, TOML tables, chunking and one-line errors."""

from __future__ import annotations

import numpy as np
import pytest
from reference_history import history_reference

import sweep
from sweep.errors import InputError

P = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)
K, V = 3e5, 1e-6  # chi = 0.021 > mu1 = 0.0125: steady sliding stable
RTOL = 1e-8
TOL = 2e-9  # friction units, as tests/protocols/test_history.py
SHS = [{"V_ratio": 1, "displacement": 2e-5}, {"hold": "t_hold"}, {"V_ratio": 1, "displacement": 2e-5}]


def scene(segments, axes, params=P, K_over_M=(K,), **kw) -> sweep.Scene:
    return sweep.Scene(protocol="history", params=params, K_over_M=None if K_over_M is None else list(K_over_M),
                       V=[V], rtol=RTOL, model="quasistatic", axes=axes, options={"segments": segments}, **kw)


def mu_ss(params, v):
    lv = np.log(v / params.V0)
    return params.m0 - params.m1 * lv + params.m2 * lv**2


def test_a_hold_axis_gives_each_hold_its_own_reference():
    holds = [1.0, 30.0, 300.0]
    ds = sweep.run_sweep(scene(SHS, {"t_hold": holds}), progress=False).isel(K_over_M=0, V=0)
    assert ds.mu_end.dims == ("t_hold", "segment") and ds.t_hold.attrs["units"] == "s"
    assert np.all(ds.status.values == 0)
    for i, hold in enumerate(holds):
        segs = [SHS[0], {"hold": hold}, SHS[2]]
        ref = history_reference(P.A, P.m1, P.m2, P.D0, K, V, segs, m0=P.m0)[0]
        np.testing.assert_allclose(ds.mu_end.values[i], [r["mu_end"] for r in ref], rtol=0, atol=TOL)
        np.testing.assert_allclose(ds.delta_mu_relax.values[i, 1], ref[1]["mu_start"] - ref[1]["mu_end"], atol=TOL)
        np.testing.assert_allclose(ds.delta_mu_peak.values[i, 2], ref[2]["mu_peak"] - mu_ss(P, V), atol=TOL)
    assert np.all(np.diff(ds.delta_mu_peak.values[:, 2]) > 0)  # the aging law heals at rest
    assert "segment 1 -> t_hold" in ds.duration.attrs["comment"] and np.isnan(ds.duration.values[1])


def test_V_ratio_and_displacement_axes_step_to_the_analytic_steady_jump():
    """At m2 = 0 a step V -> r V that reaches steady sliding jumps by (a - b) ln r (docs/physics.md 7b); every point
    of a (ratio x displacement) grid has its own ratio, which the kernel takes per call (one call per ratio)."""
    lab = sweep.FrictionParams.from_lab(a=0.007, b=0.0195, Dc=0.7e-6)
    segs = [{"V_ratio": 1, "displacement": 2e-5}, {"V_ratio": "ratio", "displacement": "slide"}]
    ratios, slides = [0.3, 3.0, 10.0], [6e-5, 1e-4]
    ds = sweep.run_sweep(scene(segs, {"ratio": ratios, "slide": slides}, params=lab), progress=False)
    ds = ds.isel(K_over_M=0, V=0)
    assert ds.mu_end.dims == ("ratio", "slide", "segment")
    assert ds.ratio.attrs["units"] == "1" and ds.slide.attrs["units"] == "m"
    jump = ds.delta_mu_ss.values[:, :, 1]
    want = (0.007 - 0.0195) * np.log(ratios)[:, None] * np.ones((1, 2))
    np.testing.assert_allclose(jump, want, rtol=0, atol=1e-7)
    ref = history_reference(lab.A, lab.m1, lab.m2, lab.D0, K, V, [segs[0], {"V_ratio": 10.0, "displacement": 6e-5}],
                            m0=lab.m0)[0]
    np.testing.assert_allclose(ds.mu_end.values[2, 0], [r["mu_end"] for r in ref], rtol=0, atol=TOL)


def test_hold_axis_from_toml_is_log_spaced_in_seconds_and_round_trips(tmp_path):
    text = ('protocol = "history"\nmodel = "quasistatic"\npreset = "sample2"\n[K_over_M]\nvalues = [3e5]\n'
            '[V]\nvalues = [1e-6]\n[[segments]]\nV_ratio = 1\ndisplacement = 2e-5\n[[segments]]\nhold = "t_hold"\n'
            '[[segments]]\nV_ratio = 1\ndisplacement = 2e-5\n[t_hold]\nstart = 1\nstop = 1e4\nnum = 5\n')
    sc = sweep.load_scene(text)
    assert sc.dims == ("K_over_M", "V", "t_hold")
    np.testing.assert_allclose(sc.axes["t_hold"], [1, 10, 100, 1e3, 1e4])
    back = sweep.load_scene(sc.to_toml())
    np.testing.assert_array_equal(back.axes["t_hold"], sc.axes["t_hold"])
    assert back.options.segments == sc.options.segments


def test_an_axis_scene_gives_the_same_numbers_whatever_the_chunking():
    sc = scene(SHS, {"t_hold": [1.0, 10.0, 100.0]}, K_over_M=(1e5, 3e5))
    whole = sweep.run_sweep(sc, progress=False)
    parts = sweep.run_sweep(sc, progress=False, chunk_size=2)
    for name in ("mu_end", "delta_mu_peak", "status", "steps"):
        np.testing.assert_array_equal(whole[name].values, parts[name].values)


@pytest.mark.parametrize("segments, axes, words", [
    (SHS, {"t_hold": [1.0], "t_other": [2.0]}, "axes has unknown name(s) ['t_other']"),
    (SHS, {}, "segments[1].hold names axis 't_hold', which the scene does not give"),
    ([SHS[0], {"hold": "A"}], {"A": [0.01]}, "segments[1].hold names axis 'A', which is a parameter"),
    ([SHS[0], {"hold": "Dc"}], {}, "which is a parameter"),
    ([SHS[0], {"hold": "duration"}], {"duration": [1.0]}, "a name of the history file"),
    ([SHS[0], {"hold": "x"}, {"V_ratio": 1, "displacement": "x"}], {"x": [1.0]}, "an axis has one unit"),
    (SHS, {"t_hold": [-1.0, 1.0]}, "axis t_hold (segments[1].hold) must be > 0 s"),
    ([{"V_ratio": "r", "duration": 1.0}], {"r": [0.0, 1.0]}, "must be > 0 1"),
    ([SHS[0], {"V_ratio": "r", "duration": 1.0}], {"r": [-1.0, 1.0]}, "must be >= 0 1"),
    ([SHS[0], {"hold": "t hold"}], {}, "names an axis: use letters"),
    ([SHS[0], {"hold": "beta"}], {"beta": [1.0]}, "a name of the history file"),
])
def test_bad_axes_of_segments_are_refused_in_one_line(segments, axes, words):
    with pytest.raises(InputError) as info:
        scene(segments, axes)
    assert words in str(info.value) and "\n" not in str(info.value), str(info.value)


def test_a_table_that_no_segment_names_is_an_unknown_key():
    with pytest.raises(InputError, match=r"unknown key\(s\) \['t_hold'\]"):
        sweep.load_scene('protocol = "history"\npreset = "sample2"\n[K_over_M]\nvalues = [3e5]\n[V]\nvalues = [1e-6]\n'
                         '[[segments]]\nV_ratio = 1\nduration = 1.0\n[t_hold]\nvalues = [1.0]\n')


def test_sweep_plot_draws_the_segments_the_healing_and_mu_t(tmp_path):
    """``sweep plot`` of a (k x t_hold) file with mu_t: one figure; the healing rate it labels is the slope of
    Delta mu_peak over log10 t_h; a per-segment --variable is drawn, any other refused in one line."""
    from sweep.cli import main
    from sweep.plot.history import healing_rate, hold_axes

    lab = sweep.FrictionParams.from_lab(a=0.007, b=0.0195, Dc=0.7e-6)
    sc = sweep.Scene(protocol="history", params=lab, K_over_M=None, V=[V], model="quasistatic",
                     axes={"k": [5e4, 1e5], "t_hold": [1.0, 10.0, 100.0]},
                     observables=["mu_end", "delta_mu_peak", "mu_t"],
                     options={"segments": SHS, "t_obs": [0.0, 20.0, 40.0, 80.0]})
    out = tmp_path / "h.nc"
    sweep.run_sweep(sc, progress=False, output=out)
    ds = sweep.open(out)
    assert hold_axes(ds) == {"t_hold": 1}
    png = tmp_path / "h.png"
    assert main(["plot", str(out), "-o", str(png)]) == 0 and png.stat().st_size > 10_000
    assert main(["plot", str(out), "-o", str(tmp_path / "p.png"), "--variable", "delta_mu_peak"]) == 0
    assert main(["plot", str(out), "-o", str(tmp_path / "x.png"), "--variable", "mu_t"]) == 2
    t = np.array([1.0, 10.0, 100.0, 1000.0])
    assert healing_rate(t, 0.004 + 0.02 * np.log10(t)) == pytest.approx(0.02, rel=1e-12)
    assert np.isnan(healing_rate(t, np.array([np.nan, 1.0, np.nan, np.nan])))


def test_the_user_guides_load_history_examples_run():
    """Every TOML and Python example of docs/user-guide.md's "Load histories" runs, and the healing it shows is
    there: longer holds, higher peaks on reslide."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "user-guide.md").read_text()
    section = text.split("## Load histories", 1)[1].split("\n## ", 1)[0]
    tomls = re.findall(r"```toml\n(.*?)```", section, re.S)
    pythons = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(tomls) == 2 and len(pythons) == 1
    runs = [sweep.run_sweep(sweep.load_scene(t), progress=False) for t in tomls]
    for ds in runs:
        assert np.all(ds.status.values == 0)
    shs, grid = runs
    peaks = shs.delta_mu_peak.values.reshape(-1)[[2, 4]]
    assert peaks[1] > peaks[0] > 0 and np.isfinite(shs.mu_t.values).all()
    assert grid.mu_end.dims == ("k", "V", "b", "t_hold", "segment")
    assert np.all(np.diff(grid.delta_mu_peak.isel(segment=2).values, axis=-1) > 0)
    namespace = {"sweep": sweep, "np": np}
    exec(pythons[0], namespace)
    step = namespace["ds"].delta_mu_ss.values.reshape(-1)[1]
    assert step == pytest.approx((0.007 - 0.0195) * np.log(10), abs=1e-6)


def test_the_healing_rate_of_a_series_whose_holds_are_axes_is_the_slope_over_each_points_holds():
    """beta per point (H1's healing.py) over holds given by two axes: the least-squares slope of that point's own
    peaks against log10 of its own hold times."""
    from sweep.plot.history import healing_rate

    segs = [SHS[0], {"hold": "t1"}, SHS[2], {"hold": "t2"}, SHS[2]]
    ds = sweep.run_sweep(scene(segs, {"t1": [1.0, 10.0], "t2": [100.0, 1000.0]}), progress=False)
    ds = ds.isel(K_over_M=0, V=0)
    for i, t1 in enumerate([1.0, 10.0]):
        for j, t2 in enumerate([100.0, 1000.0]):
            peaks = ds.delta_mu_peak.values[i, j, [2, 4]]
            want = healing_rate(np.array([t1, t2]), peaks)
            assert ds.beta.values[i, j] == pytest.approx(want, rel=1e-12)
