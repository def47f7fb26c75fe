"""The laboratory's parameters in a scene (issue 34): [params] as a, b, Dc, mu0, V0 (never mixed with the paper's),
a, b, Dc as axes (A = a, m1 = b - a, D0 = Dc per point at m2 = 0) and the stiffness k [1/m] instead of K/M (K/M = k g),
on the stop and history protocols; the driven scene and the Hopf line accept the laboratory's [params]."""

from __future__ import annotations

import numpy as np
import pytest
from reference_history import history_reference

import sweep
from sweep.errors import InputError
from sweep.scene.scene import hopf_config

LAB = 'a = 0.007\nb = 0.0195\nDc = 0.7e-6\nmu0 = 0.55\nV0 = 2e-6\n'
GRID = '[V]\nvalues = [1e-6, 2e-6]\n'


def test_lab_params_table_is_the_papers_law_at_m2_zero():
    sc = sweep.load_scene('[params]\n' + LAB + '[K_over_M]\nvalues = [1e4]\n' + GRID)
    p = sc.params
    assert (p.A, p.m1, p.m2, p.D0, p.m0, p.V0) == (0.007, 0.0195 - 0.007, 0.0, 0.7e-6, 0.55, 2e-6)


@pytest.mark.parametrize("table, words", [
    ('[params]\na = 0.007\nb = 0.0195\nDc = 1e-6\nm2 = 0.001\n', "mixes the paper's ['m2'] and the laboratory's"),
    ('[params]\na = 0.007\nb = 0.0195\n', "needs a, b and Dc; missing ['Dc']"),
    ('preset = "sample2"\n[params]\nb = 0.02\n', "describe m2 = 0 only"),
    ('[params]\na = 0.007\nb = 0.0195\nDc = 1e-6\nmu = 0.6\n', "unknown key(s) ['mu']"),
    ('[params]\na = -0.007\nb = 0.0195\nDc = 1e-6\n', "a must be > 0"),
])
def test_bad_lab_params_are_refused_in_one_line(table, words):
    with pytest.raises(InputError) as info:
        sweep.load_scene(table + '[K_over_M]\nvalues = [1e4]\n' + GRID)
    assert words in str(info.value) and "\n" not in str(info.value), str(info.value)


def test_k_and_lab_axes_map_per_point_to_the_papers_parameters():
    """chi = K D0/(M g) = k Dc and mu1 = m1 = b - a (m2 = 0) on every point; the file keeps the names k, a, b, Dc."""
    sc = sweep.load_scene('protocol = "history"\nmodel = "quasistatic"\n[[segments]]\nV_ratio = 1\nduration = 1.0\n'
                          '[params]\n' + LAB + '[k]\nstart = 1e3\nstop = 1e5\nnum = 3\n' + GRID
                          + '[a]\nvalues = [0.005, 0.01]\n[b]\nvalues = [0.012, 0.02]\n[Dc]\nvalues = [5e-7, 2e-6]\n')
    assert sc.dims == ("k", "V", "a", "b", "Dc")
    np.testing.assert_allclose(sc.axes["k"], [1e3, 1e4, 1e5])  # log spacing by default
    np.testing.assert_array_equal(sc.K_over_M, sc.axes["k"] * 9.81)
    ds = sweep.run_sweep(sc, progress=False)
    assert ds.k.attrs["units"] == "m-1" and "K_over_M = k g" in ds.k.attrs["comment"]
    assert ds.b.attrs["units"] == "1" and ds.Dc.attrs["units"] == "m"
    k, a, b, Dc = (ds[n] for n in ("k", "a", "b", "Dc"))
    np.testing.assert_allclose(ds.chi, k * Dc, rtol=1e-14)
    np.testing.assert_allclose(ds.mu1, (b - a).broadcast_like(ds.mu1), rtol=1e-14)
    assert ds.mu_end.dims == ("k", "V", "a", "b", "Dc", "segment") and np.all(ds.status.values == 0)
    back = sweep.load_scene(sc.to_toml())
    assert back.dims == sc.dims and np.array_equal(back.axes["b"], sc.axes["b"])


def test_a_history_grid_of_holds_stiffness_and_b_matches_the_reference_at_a_point(tmp_path):
    """The issue's sweep: holds x k x b in one scene (steady sliding stable: chi = k Dc > b - a); one of its points
    against the scipy Radau reference."""
    lab = sweep.FrictionParams.from_lab(a=0.007, b=0.0195, Dc=0.7e-6)
    segs = [{"V_ratio": 1, "displacement": 2e-5}, {"hold": "t_hold"}, {"V_ratio": 1, "displacement": 2e-5}]
    sc = sweep.Scene(protocol="history", params=lab, K_over_M=None, V=[1e-6], rtol=1e-8, model="quasistatic",
                     axes={"k": [5e4, 1e5], "b": [0.0195, 0.03], "t_hold": [1.0, 100.0]}, options={"segments": segs})
    assert sc.dims == ("k", "V", "b", "t_hold")
    ds = sweep.run_sweep(sc, progress=False)
    ds.to_netcdf(tmp_path / "h.nc")
    ds = sweep.open(tmp_path / "h.nc")  # the k dim is a grid's first axis, not a 0-d point's missing one
    assert ds.mu_end.dims == ("k", "V", "b", "t_hold", "segment")
    point = ds.isel(k=0, V=0, b=1, t_hold=1)
    A, m1, D0 = 0.007, 0.03 - 0.007, 0.7e-6
    ref = history_reference(A, m1, 0.0, D0, 5e4 * 9.81, 1e-6, [segs[0], {"hold": 100.0}, segs[2]], m0=lab.m0)[0]
    np.testing.assert_allclose(point.mu_end.values, [r["mu_end"] for r in ref], rtol=0, atol=2e-9)
    peak = ds.delta_mu_peak.isel(V=0, segment=2)
    assert np.all(peak.isel(t_hold=1) > peak.isel(t_hold=0))  # longer holds heal more, at every k and b


@pytest.mark.parametrize("kw, words", [
    (dict(axes={"A": [0.01], "a": [0.01]}), "mix the paper's ['A'] and the laboratory's ['a']"),
    (dict(axes={"b": [0.02]}, params=sweep.presets["sample2"]), "describe m2 = 0 only"),
    (dict(axes={"k": [1e3]}), "the stiffness is given twice"),
    (dict(K_over_M=None), "K_over_M is missing"),
    (dict(axes={"k": [1e3]}, K_over_M=None, protocol="driven", model="quasistatic"), "'stop' and 'history' only"),
    (dict(axes={"k": [-1.0, 1e3]}, K_over_M=None), "k must be > 0"),
])
def test_bad_lab_axes_are_refused_in_one_line(kw, words):
    base = dict(protocol="stop", params=sweep.FrictionParams.from_lab(a=0.007, b=0.0195, Dc=1e-6), K_over_M=[1e4],
                V=[1e-6])
    with pytest.raises(InputError) as info:
        sweep.Scene(**{**base, **kw})
    assert words in str(info.value) and "\n" not in str(info.value), str(info.value)


def test_driven_scene_and_hopf_line_accept_lab_params(tmp_path):
    sc = sweep.load_scene('protocol = "driven"\nmodel = "quasistatic"\n[params]\n' + LAB
                          + '[K_over_M]\nvalues = [1e4]\n' + GRID)
    assert sc.params.m1 == 0.0195 - 0.007 and sc.params.m2 == 0.0
    path = tmp_path / "h.toml"
    path.write_text('[params]\n' + LAB + GRID)
    params, V, _ = hopf_config(path)
    assert params == sc.params and list(V) == [1e-6, 2e-6]


def test_stop_files_over_k_and_over_a_b_are_drawn(tmp_path):
    """sweep plot of a stop file over k draws its maps over K/M = k g; over (a, b) its slices."""
    from sweep.cli import main

    lab = sweep.FrictionParams.from_lab(a=0.007, b=0.0195, Dc=0.7e-6)
    for name, kw in (("k", dict(K_over_M=None, axes={"k": [1e3, 1e4]})),
                     ("ab", dict(K_over_M=[1e4, 2e4], axes={"a": [0.005, 0.007], "b": [0.01, 0.02]}))):
        sc = sweep.Scene(protocol="stop", params=lab, V=[1e-6, 2e-6], **kw)
        out = tmp_path / f"{name}.nc"
        sweep.run_sweep(sc, progress=False, output=out)
        assert main(["plot", str(out), "-o", str(tmp_path / f"{name}.png")]) == 0
        assert (tmp_path / f"{name}.png").stat().st_size > 10_000


def test_a_scene_over_k_survives_dataclasses_replace():
    import dataclasses

    sc = sweep.Scene(protocol="stop", params=sweep.FrictionParams.from_lab(a=0.007, b=0.0195, Dc=1e-6),
                     K_over_M=None, V=[1e-6], axes={"k": [1e3, 1e4]})
    again = dataclasses.replace(sc, rtol=1e-5)
    assert again.dims == ("k", "V") and np.array_equal(again.K_over_M, sc.K_over_M) and again.rtol == 1e-5
