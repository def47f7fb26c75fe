"""Sweep axes beyond (K/M, V) (issue 21, part 1): A, m1, m2, D0 as extra grid axes of a stop scene.

A point of an N-D sweep is the point of the 2-D sweep with those parameters, bit for bit (its inputs are computed
per point); a few points are also checked against the independent scipy reference (tests/reference.py). The file
is CF (units on every coordinate), written in chunks, resumable, readable by ``sweep plot`` and ``sweep info``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr
from faults import interrupt_after
from reference import reference_stop

import sweep
from sweep.cli import main
from sweep.plan.plan import scene_plan_hash
from sweep.run.journal import journal_path
from sweep.write.netcdf import open_dataset

P2 = sweep.presets["sample2"]
K, V = np.logspace(4, 6, 3), np.logspace(-7, -5.5, 2)
TIME_RESOLVED = dict(observables=("xi_inf", "trajectory", "slip_at", "t50"), t_obs=(0.1, 1.0, 10.0),
                     trajectory_tau=(1e-2, 1e3, 4))


def scene(axes, **kw) -> sweep.Scene:
    return sweep.Scene(protocol="stop", params=P2, K_over_M=K, V=V, axes=axes, **kw)


def assert_slices_are_the_2d_sweeps(ds: xr.Dataset, axes: dict, **kw) -> None:
    """Every slice of ``ds`` along its extra axes equals, bit for bit, the 2-D sweep with those parameters."""
    names = list(axes)
    for values in np.ndindex(*(len(axes[n]) for n in names)):
        at = {n: float(axes[n][i]) for n, i in zip(names, values)}
        flat = sweep.run_sweep(sweep.Scene(protocol="stop", params=P2.replace(**at), K_over_M=K, V=V, **kw),
                               progress=False)
        sl = ds.sel(at)
        assert set(sl.data_vars) == set(flat.data_vars)
        for name in list(flat.data_vars) + ["chi", "mu1", "chi_c", "chi_c_quasistatic", "gamma"]:
            got = np.broadcast_to(sl[name].values, flat[name].shape)
            np.testing.assert_array_equal(got, flat[name].values, err_msg=f"{name} at {at}")


def test_a_4d_sweep_over_A_and_m1_is_the_2d_sweeps_bit_for_bit():
    axes = {"A": [0.006, 0.009], "m1": [0.005, 0.0125]}
    ds = sweep.run_sweep(scene(axes), progress=False)
    assert ds["xi_inf"].dims == ("K_over_M", "V", "A", "m1")
    assert ds["chi"].dims == ("K_over_M",) and ds["mu1"].dims == ("V", "m1") and ds["chi_c"].dims == ("V", "A", "m1")
    assert_slices_are_the_2d_sweeps(ds, axes)


@pytest.mark.slow
def test_the_relaxed_slip_of_an_nd_sweep_matches_the_scipy_reference():
    """Points of a (K/M, V, A, m1, m2, D0) sweep against tests/reference.py (rtol 1e-13), within 2 x the sweep's
    rtol."""
    axes = {"A": [0.006, 0.009], "m1": [0.005, 0.0125], "m2": [0.001, 0.0033], "D0": [0.5e-6, 1e-6]}
    ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=P2, K_over_M=[1e5, 1e6], V=[1e-6, 3e-6], axes=axes,
                                     model="quasistatic", rtol=1e-6), progress=False)
    assert ds["xi_inf"].dims == ("K_over_M", "V", "A", "m1", "m2", "D0")
    rng = np.random.default_rng(3)
    for flat in rng.choice(ds["xi_inf"].size, 12, replace=False):
        idx = np.unravel_index(flat, ds["xi_inf"].shape)
        pt = {d: float(ds[d].values[i]) for d, i in zip(ds["xi_inf"].dims, idx)}
        chi = pt["K_over_M"] * pt["D0"] / P2.g
        mu1 = pt["m1"] - 2 * pt["m2"] * math.log(pt["V"] / P2.V0)
        ref = reference_stop(chi, pt["A"], mu1, pt["m2"]).xi_inf
        got = float(ds["xi_inf"].values[idx])
        assert abs(got / ref - 1) < 2e-6, pt
        assert float(ds["slip_inf"].values[idx]) == got * pt["D0"]


def test_time_resolved_nd_sweep_written_in_chunks_equals_the_2d_sweeps(tmp_path):
    """m2 and D0 axes (D0 changes the sample times tau = V t/D0 and the slip scale of each point), trajectories and
    slip_at written into the file chunk by chunk (chunks of 5 points cut the rows of the 4-D grid anywhere)."""
    axes = {"m2": [0.0, 0.0033], "D0": [0.5e-6, 1e-6]}
    sc = scene(axes, **TIME_RESOLVED)
    in_memory = sweep.run_sweep(sc, progress=False)
    returned = sweep.run_sweep(sc, progress=False, output=tmp_path / "nd.nc", chunk_size=5)
    in_file = open_dataset(tmp_path / "nd.nc")
    xr.testing.assert_identical(in_memory.drop_attrs(deep=False), in_file.drop_attrs(deep=False))
    xr.testing.assert_identical(in_file, returned.load())
    assert in_file["slip_at"].dims == ("K_over_M", "V", "m2", "D0", "t_obs")
    assert_slices_are_the_2d_sweeps(in_memory, axes, **TIME_RESOLVED)


def test_the_file_is_cf_with_units_on_every_coordinate_and_its_scene_round_trips(tmp_path):
    sc = scene({"A": [0.006, 0.009], "D0": [0.5e-6, 1e-6]})
    ds = sweep.run_sweep(sc, progress=False, output=tmp_path / "s.nc")
    assert ds.attrs["Conventions"] == "CF-1.11"
    for name, var in ds.coords.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert (ds["A"].attrs["units"], ds["D0"].attrs["units"]) == ("1", "m")
    again = sweep.load_scene(ds.attrs["scene"])
    assert again.dims == sc.dims and again.to_toml() == sc.to_toml()
    assert scene_plan_hash(again) == ds.attrs["plan_hash"]


def test_a_4d_sweep_resumes_to_the_same_numbers(tmp_path, monkeypatch):
    import sweep.protocols.stop.chunk as stop_chunks
    import sweep.run.runner as runner

    sc, out = scene({"A": [0.006, 0.009], "m1": [0.005, 0.0125]}, **TIME_RESOLVED), tmp_path / "r.nc"
    real_chunk = stop_chunks.stop_chunk
    interrupt_after(monkeypatch, 2)
    with pytest.raises(runner.Interrupted, match=f"2 of {len(runner.chunk_ranges(sc.shape, 7))} chunks are saved"):
        sweep.run_sweep(sc, progress=False, output=out, chunk_size=7)
    monkeypatch.setattr(stop_chunks, "stop_chunk", real_chunk)
    resumed = sweep.run_sweep(sc, progress=False, output=out, chunk_size=7, resume=True)
    xr.testing.assert_identical(resumed.load().drop_attrs(deep=False),
                                sweep.run_sweep(sc, progress=False).drop_attrs(deep=False))
    assert not journal_path(out).exists()


def test_toml_tables_of_extra_axes():
    sc = sweep.load_scene('preset = "sample2"\n[K_over_M]\nvalues = [1e5]\n[V]\nvalues = [1e-6]\n'
                          '[A]\nstart = 0.004\nstop = 0.016\nnum = 3\n[m1]\nstart = -0.01\nstop = 0.02\nnum = 4\n')
    assert sc.dims == ("K_over_M", "V", "A", "m1") and sc.shape == (1, 1, 3, 4) and sc.n_points == 12
    np.testing.assert_allclose(sc.axes["A"], [0.004, 0.008, 0.016])  # log spacing by default for A and D0
    np.testing.assert_allclose(sc.axes["m1"], [-0.01, 0.0, 0.01, 0.02], atol=1e-18)  # linear for m1, m2


@pytest.mark.parametrize("kw, words", [
    (dict(axes={"mu": [0.1]}), ["axes has unknown name(s) ['mu']", "allowed"]),
    (dict(axes={"A": [0.01, 0.005]}), ["A must be strictly increasing"]),
    (dict(axes={"D0": [-1e-6, 1e-6]}), ["D0 must be > 0"]),
    (dict(axes={"m1": [0.0, np.nan]}), ["m1 contains NaN"]),
    (dict(axes={"A": [0.01]}, protocol="driven"), ["protocol 'stop' and 'history' only", "'driven'"]),
    (dict(axes={"A": [0.01]}, simulated_hopf_line=True), ["simulated_hopf_line", "axes ['A']"]),
])
def test_bad_extra_axes_are_refused_naming_the_field(kw, words):
    with pytest.raises(sweep.InputError) as exc:
        sweep.Scene(**{"protocol": "stop", "params": P2, "K_over_M": K, "V": V, **kw})
    for w in words:
        assert w in str(exc.value), (w, str(exc.value))


def test_sweep_plot_and_info_read_nd_files(tmp_path, capsys):
    """Small multiples of the (K/M, V) map over A x m1; a map over (A, m1) at one (K/M, V); ``sweep info``."""
    big = tmp_path / "big.nc"
    sweep.run_sweep(scene({"A": [0.006, 0.009], "m1": [0.005, 0.0125, 0.02]}, **TIME_RESOLVED), progress=False,
                    output=big)
    point = tmp_path / "point.nc"
    sweep.run_sweep(sweep.Scene(protocol="stop", params=P2, K_over_M=[2.8e5], V=[1e-6],
                                axes={"A": np.geomspace(0.004, 0.012, 4), "m1": np.linspace(0, 0.03, 3)}),
                    progress=False, output=point)
    assert main(["plot", str(big), "-o", str(tmp_path / "big.png")]) == 0
    assert (tmp_path / "big.png").stat().st_size > 0 and (tmp_path / "big_trajectories.png").is_file()
    assert main(["plot", str(point), "-o", str(tmp_path / "point.png"), "--variable", "stress_relaxation"]) == 0
    assert (tmp_path / "point.png").stat().st_size > 0
    assert main(["plot", str(point), "-o", str(tmp_path / "x.png"), "--variable", "gamma"]) == 2
    assert main(["info", str(big)]) == 0
    out = capsys.readouterr().out
    assert "A" in out and "m1" in out


def test_a_log_spaced_m1_table_through_zero_is_refused_with_the_fix():
    with pytest.raises(sweep.InputError, match='m1.start and m1.stop must be > 0 for spacing "log".*"linear"'):
        sweep.load_scene('preset = "sample2"\n[K_over_M]\nvalues = [1e5]\n[V]\nvalues = [1e-6]\n'
                         '[m1]\nstart = -0.01\nstop = 0.02\nnum = 4\nspacing = "log"\n')
