"""The driven protocol through the public API: Scene validation, the Dataset, agreement with the linear theory
over a grid, the netCDF file and the CLI."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep import physics
from sweep.cli import main
from sweep.errors import InputError
from sweep.integrate.driven import Regime

PARAMS = sweep.presets["sample2"]
KM = np.logspace(4, 6, 8)
V = np.array([1e-7, 1e-6, 3e-6])


def driven(**kw) -> sweep.Scene:
    return sweep.Scene(protocol="driven", params=PARAMS, K_over_M=kw.pop("K_over_M", KM), V=kw.pop("V", V), **kw)


@pytest.mark.parametrize("kw, name", [
    (dict(method="rk4"), "method"),
    (dict(perturbation=0.0), "perturbation"),
    (dict(perturbation=2.0), "perturbation"),
    (dict(max_cycles=2), "max_cycles"),
    (dict(observables=("xi_inf",)), "observables"),
    (dict(step=0.1), "step"),
    (dict(precision="float32"), "precision"),
    (dict(model="newtonian"), "model"),
    (dict(model_tol=0.0), "model_tol"),
    (dict(model_tol=0.9), "model_tol"),
])
def test_bad_driven_scene_names_the_parameter(kw, name):
    with pytest.raises(InputError, match=name):
        driven(**kw)


def test_driven_grid_follows_the_linear_theory():
    """Where the linear growth rate is clearly negative the regime is steady and the measured rate (from at
    least two cycles) equals it; where clearly positive the point is not steady; every status is a known one."""
    ds = sweep.run_sweep(driven(model="quasistatic"), progress=False)
    regime, lin, grow = ds["regime"].values, ds["growth_rate_linear"].values, ds["growth_rate"].values
    clearly_stable, clearly_unstable = lin < -1e-3, lin > 1e-3
    assert clearly_stable.sum() >= 5 and clearly_unstable.sum() >= 3
    assert np.all(regime[clearly_stable] == Regime.STEADY)
    assert np.all(regime[clearly_unstable] != Regime.STEADY)
    measured = clearly_stable & (ds["cycles"].values >= 2)
    assert measured.sum() >= 3
    np.testing.assert_allclose(grow[measured], lin[measured], rtol=2e-3)
    assert np.all(np.isin(ds["status"].values, [sweep.Status.OK, sweep.Status.QUASISTATIC_BREAKDOWN]))
    assert np.all((regime == Regime.RUNAWAY) == (ds["status"].values == sweep.Status.QUASISTATIC_BREAKDOWN))
    assert np.all(ds["amplitude"].values[regime == Regime.STEADY] == 0.0)
    assert not np.any(np.isnan(ds["amplitude"].values[regime == Regime.STICK_SLIP]))
    omega = ds["Omega_c"].values
    mu1 = physics.mu1(V, PARAMS.m1, PARAMS.m2, PARAMS.V0)
    np.testing.assert_allclose(omega, V / PARAMS.D0 * np.sqrt(mu1 / PARAMS.A))


def test_only_the_observables_asked_for_are_stored(tmp_path):
    ds = sweep.run_sweep(driven(observables=("period",), K_over_M=KM[-2:], V=V[:1]), progress=False)
    assert "period" in ds and "regime" in ds and "growth_rate" not in ds and "amplitude" not in ds
    path = tmp_path / "d.nc"
    ds.to_netcdf(path)
    back = xr.open_dataset(path)
    assert back["regime"].attrs["flag_meanings"].split()[0] == "steady"
    np.testing.assert_array_equal(back["regime"].values, ds["regime"].values)


def test_cli_runs_a_driven_scene(tmp_path, capsys):
    cfg = tmp_path / "driven.toml"
    cfg.write_text('protocol = "driven"\npreset = "sample2"\n[K_over_M]\nstart = 1e4\nstop = 1e6\nnum = 4\n'
                   '[V]\nvalues = [1e-6, 1e-5]\n')
    out = tmp_path / "d.nc"
    assert main(["run", str(cfg), "-o", str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "regime:" in text and out.exists() and out.with_suffix(".png").stat().st_size > 10_000
    assert main(["plot", str(out), "-o", str(tmp_path / "p.png")]) == 0
    assert (tmp_path / "p.png").stat().st_size > 10_000


def test_inertial_stop_scene_refuses_what_it_does_not_compute():
    """The inertial stop computes the relaxed slip only, with its own stepper."""
    for kw in (dict(observables=("xi_inf", "trajectory")), dict(method="rk4"), dict(precision="float32", rtol=1e-4)):
        with pytest.raises(InputError, match="model 'inertial'"):
            sweep.Scene(protocol="stop", params=PARAMS, K_over_M=KM, V=V, model="inertial", **kw)


def test_inertial_driven_grid_follows_its_own_linear_theory():
    """Fast drives (gamma/A 0.03 .. 3 at m2 = 0): the inertial model's line chi_c = mu1 (1 + gamma/A) moves to
    stiffer springs; steady exactly where its linear theory is stable, not where the quasi-static one is."""
    params = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)
    v = np.sqrt(np.array([0.03, 0.3, 3.0]) * params.g * params.D0 * params.A)
    km = np.logspace(5, 6, 12)  # the quasi-static line is at 1.75e5 s^-2, the inertial one 1.03 .. 4x higher
    ds = sweep.run_sweep(sweep.Scene(protocol="driven", params=params, K_over_M=km, V=v, model="inertial"),
                         progress=False)
    np.testing.assert_allclose(ds["chi_c"], ds["chi_c_quasistatic"] * (1 + ds["gamma"] / params.A))
    lin = ds["growth_rate_linear"].values
    clear = np.abs(lin) > 1e-3
    assert clear.sum() > 20
    np.testing.assert_array_equal(ds["regime"].values[clear] == Regime.STEADY, lin[clear] < 0)
    quasi_unstable = ds["chi"].values[:, None] < ds["chi_c_quasistatic"].values[None, :]
    assert np.any((ds["stable"].values == 0) & ~quasi_unstable)  # unstable only because of inertia
    assert "inertial" in ds.attrs["plan_model"] and 'model = "inertial"' in ds.attrs["scene"]


def test_auto_driven_model_per_velocity_and_breakdowns_run_again_with_inertia():
    """model="auto": inertia where gamma/A > model_tol; below the quasi-static line with m2 = 0 the quasi-static run
    breaks down (runaway), so the point is run again with inertia and reaches stick-slip (the stick phases are
    stiff at gamma/A = 2e-3: RODAS3 steps); model_error is the line's relative shift gamma/A; chi_c follows the
    model of each V, chi_c_quasistatic is kept."""
    params = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)
    ratios = np.array([2e-3, 5e-2])
    v = np.sqrt(ratios * params.g * params.D0 * params.A)
    km = np.array([0.98, 1.2]) * params.m1 * params.g / params.D0
    ds = sweep.run_sweep(sweep.Scene(protocol="driven", params=params, K_over_M=km, V=v), progress=False)
    np.testing.assert_array_equal(ds["model"].values, [[1, 1], [0, 1]])
    np.testing.assert_array_equal(ds["regime"].values, [[Regime.STICK_SLIP, Regime.STICK_SLIP],
                                                        [Regime.STEADY, Regime.STEADY]])
    assert np.all(ds["status"].values == sweep.Status.OK)
    np.testing.assert_allclose(ds["model_error"].values, np.broadcast_to(ratios, (2, 2)), rtol=1e-12)
    np.testing.assert_allclose(ds["chi_c"].values, params.m1 * np.array([1.0, 1.0 + ratios[1]]), rtol=1e-12)
    np.testing.assert_allclose(ds["chi_c_quasistatic"].values, params.m1, rtol=1e-12)
    forced = sweep.run_sweep(sweep.Scene(protocol="driven", params=params, K_over_M=km[:1], V=v[:1],
                                         model="quasistatic"), progress=False)
    assert forced["regime"].values[0, 0] == Regime.RUNAWAY and "model_error" not in forced
