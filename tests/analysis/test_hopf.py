"""sweep.locate_hopf (quasi-static): the line located by simulation against the analytic one (docs/physics.md 3b,
eq. 3), the bifurcation type against the known behaviour (m2 > 0 supercritical, m2 = 0 degenerate), no line where
mu1(V) <= 0, and the CLI."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import sweep
from sweep.analysis.hopf import AGREEMENT, BIFURCATIONS, hopf_summary
from sweep.analysis.lyapunov import TYPES
from sweep.cli import main
from sweep.errors import InputError
from sweep.write.netcdf import open_dataset

SAMPLE2 = sweep.presets["sample2"]
V = np.array([1e-7, 1e-6, 3e-6, 5e-6])  # mu1 > 0 below 6.6 um/s for sample2


@pytest.mark.parametrize("params, kind", [(SAMPLE2, "supercritical"), (SAMPLE2.replace(m2=0.0), "degenerate"),
                                          (sweep.presets["sample1"], "supercritical")])
def test_line_by_simulation_matches_the_analytic_line(params, kind):
    ds = sweep.locate_hopf(params, V)
    np.testing.assert_allclose(ds["K_over_M_c"], ds["K_over_M_c_linear"], rtol=5e-3)
    # the default bracket width 1e-3: the located midpoint is within half of it
    np.testing.assert_allclose(ds["K_over_M_c"], ds["K_over_M_c_linear"], rtol=6e-4)
    names = ds["bifurcation"].attrs["flag_meanings"].split()
    assert [names[c] for c in ds["bifurcation"].values] == [kind] * V.size
    assert [TYPES[c] for c in ds["bifurcation_l1"].values] == [kind] * V.size  # l1 agrees, degenerate too
    assert np.all(ds["types_agree"].values == AGREEMENT.index("agree"))
    assert np.all(ds["simulations"].values > 2)
    if kind == "supercritical":
        assert np.all(ds["limit_cycle_amplitude"].values > 0)


def test_no_line_where_mu1_is_not_positive():
    ds = sweep.locate_hopf(SAMPLE2, [1e-5, 1e-4])  # mu1 < 0 above 6.6 um/s
    assert np.all(np.isnan(ds["K_over_M_c"])) and np.all(np.isnan(ds["K_over_M_c_linear"]))
    assert np.all(ds["bifurcation"].values == 0) and np.all(ds["simulations"].values == 0)


def test_tighter_tolerance_locates_closer():
    """The growth rate is linear in k through a quasi-static line (Re sigma = (a - k)/2): the root of the chord
    through the first bracket brackets the line at the first try, whatever rtol (4 runs; bisection halved the
    +-10 % bracket down to rtol: 7 runs at 1e-2, 17 at 1e-5)."""
    loose = sweep.locate_hopf(SAMPLE2, [1e-6], rtol=1e-2, bifurcation=False)
    tight = sweep.locate_hopf(SAMPLE2, [1e-6], rtol=1e-5, bifurcation=False)
    exact = float(tight["K_over_M_c_linear"][0])
    assert abs(float(loose["K_over_M_c"][0]) / exact - 1) < 0.5e-2
    assert abs(float(tight["K_over_M_c"][0]) / exact - 1) < 1e-5
    assert int(loose["simulations"][0]) == int(tight["simulations"][0]) == 4


def test_curved_growth_rate_of_the_inertial_line_located_to_a_tight_tolerance():
    """With inertia the growth rate bends through the line (its slope changes by 12 % over the +-10 % bracket at
    gamma/A = 1): the root from inverse quadratic interpolation, then a bracket of 0.9 rtol around it; the line
    chi_c = mu1 (1 + gamma/A) (docs/physics.md 3b) to 1e-7 in at most 8 runs (bisection: 23)."""
    params = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)
    v = np.sqrt(np.array([0.1, 1.0, 10.0]) * params.g * params.D0 * params.A)
    ds = sweep.locate_hopf(params, v, model="inertial", bifurcation=False, lyapunov=False, rtol=1e-7)
    np.testing.assert_allclose(ds["K_over_M_c"], ds["K_over_M_c_linear"], rtol=1e-7)
    assert np.all(ds["simulations"].values <= 8)


@pytest.mark.parametrize("kw, name", [(dict(model="newtonian"), "model"), (dict(rtol=0.5), "rtol"),
                                      (dict(V=[-1e-6]), "V")])
def test_bad_input_names_the_parameter(kw, name):
    with pytest.raises(InputError, match=name):
        sweep.locate_hopf(SAMPLE2, **{"V": [1e-6], **kw})


def test_cli_hopf_writes_file_and_picture(tmp_path, capsys):
    cfg = tmp_path / "h.toml"
    cfg.write_text('preset = "sample2"\n[V]\nstart = 1e-7\nstop = 1e-5\nnum = 5\n')
    out = tmp_path / "hopf.nc"
    assert main(["hopf", str(cfg), "-o", str(out)]) == 0
    assert "supercritical" in capsys.readouterr().out
    ds = open_dataset(out)
    assert ds.sizes["V"] == 5 and out.with_suffix(".png").stat().st_size > 10_000


def test_sweep_files_carry_the_simulated_line_next_to_the_analytic_one_when_asked():
    scene = sweep.Scene(protocol="stop", params=SAMPLE2, K_over_M=[1e4, 1e5], V=[1e-6, 3e-6, 1e-5])
    assert "K_over_M_c_simulated" not in sweep.run_sweep(scene, progress=False).coords  # not asked: not computed
    ds = sweep.run_sweep(dataclasses.replace(scene, simulated_hopf_line=True), progress=False)
    assert sweep.load_scene(ds.attrs["scene"]).simulated_hopf_line  # the file says that it was asked for
    analytic = ds["chi_c"].values * ds["K_over_M"].values[0] / ds["chi"].values[0]
    simulated = ds["K_over_M_c_simulated"].values
    np.testing.assert_allclose(simulated[:2], analytic[:2], rtol=6e-4)
    assert np.isnan(simulated[2]) and np.isnan(analytic[2])  # mu1 < 0 at 10 um/s: no line


def test_inertial_line_by_simulation_matches_the_analytic_line_for_gamma_over_A_1e3_to_10():
    """chi_c = mu1 (1 + gamma/A) (docs/physics.md 3b) from the full Newton equation, gamma/A = 1e-3 .. 10 (m2 = 0, so
    mu1 = m1 at every V and only gamma changes)."""
    params = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)
    ratios = np.array([1e-3, 1e-2, 0.1, 1.0, 10.0])
    v = np.sqrt(ratios * params.g * params.D0 * params.A)
    ds = sweep.locate_hopf(params, v, model="inertial", bifurcation=False)
    np.testing.assert_allclose(ds["gamma"].values / params.A, ratios, rtol=1e-12)
    np.testing.assert_allclose(ds["K_over_M_c_linear"], params.g / params.D0 * params.m1 * (1 + ratios), rtol=1e-12)
    np.testing.assert_allclose(ds["K_over_M_c"], ds["K_over_M_c_linear"], rtol=6e-4)
    quasi = sweep.locate_hopf(params, v[-1:], model="quasistatic", bifurcation=False)  # 11x lower there
    assert float(ds["K_over_M_c"][-1]) / float(quasi["K_over_M_c"][0]) == pytest.approx(11.0, rel=1e-3)


def test_stop_files_carry_the_pure_inertia_bound_and_the_creep_criterion():
    """eq. 15: xi_in = sqrt(gamma/chi), i.e. Dx_in = V sqrt(M/K); creep_over_inertia = xi_inf/xi_in."""
    km, v = np.array([1e3, 1e6]), np.array([1e-7, 1e-4])
    ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=SAMPLE2, K_over_M=km, V=v), progress=False)
    dx_in = v[None, :] * np.sqrt(1.0 / km[:, None])  # V sqrt(M/K) [m]
    np.testing.assert_allclose(ds["xi_inertial"].values * SAMPLE2.D0, dx_in, rtol=1e-12)
    np.testing.assert_allclose(ds["creep_over_inertia"], ds["xi_inf"] / ds["xi_inertial"], rtol=1e-12)
    ratio = ds["creep_over_inertia"].values
    assert ratio[0, 0] > 100 and ratio[1, 1] < ratio[0, 0]  # slow drive on a soft spring: creep dominates


def test_inertia_unfolds_the_degenerate_m2_zero_line_subcritical_then_supercritical():
    """m2 = 0 (degenerate without inertia): with inertia the line is subcritical at gamma/A = 0.01 (a large
    stick-slip cycle right below the line, and kept by a large start above it while a small start decays) and
    supercritical at gamma/A = 1 (small cycles growing like the square root of the distance); found, not assumed
    (docs/physics.md 3b leaves the type to the sweep)."""
    params = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)
    ratios = np.array([1e-2, 1.0])
    v = np.sqrt(ratios * params.g * params.D0 * params.A)
    ds = sweep.locate_hopf(params, v, model="inertial")
    kinds = [BIFURCATIONS[i] for i in ds["bifurcation"].values]
    assert kinds == ["subcritical", "supercritical"]
    amp = ds["limit_cycle_amplitude"].values
    assert amp[0] > 1.0 and amp[1] < 0.2  # a jump to large stick-slip vs a cycle born small
    # the normal form says the same (sweep/analysis/lyapunov.py), and the file says that they agree
    assert [TYPES[i] for i in ds["bifurcation_l1"].values] == kinds
    assert ds["types_agree"].values.tolist() == [AGREEMENT.index("agree")] * 2
    assert ds["l1"].values[0] > ds["l1_error"].values[0] and ds["l1"].values[1] < -ds["l1_error"].values[1]


def test_auto_model_follows_gamma_over_A_per_velocity():
    """locate_hopf(model="auto"): inertia where gamma/A > model_tol (the line's relative shift), flagged per V."""
    params = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)
    ratios = np.array([2e-3, 5e-2])
    v = np.sqrt(ratios * params.g * params.D0 * params.A)
    ds = sweep.locate_hopf(params, v, bifurcation=False, model_tol=1e-2)
    np.testing.assert_array_equal(ds["model"].values, [0, 1])
    np.testing.assert_allclose(ds["K_over_M_c_linear"].values, params.g / params.D0 * params.m1 * np.array(
        [1.0, 1.0 + ratios[1]]), rtol=1e-12)
    np.testing.assert_allclose(ds["K_over_M_c"], ds["K_over_M_c_linear"], rtol=6e-4)


def test_hopf_file_carries_the_bautin_point_the_bistable_band_and_draws_the_type(tmp_path):
    """Inertial m2 = 0 over gamma/A = 0.05 .. 0.5 (model "inertial"; no simulated type, so nothing compared): l1
    changes sign once, at the Bautin point in the attributes; the bistable band is measured where l1 > 0 only; the
    file survives netCDF; hopf_summary and the picture show it."""
    from sweep.plot.files import plot_hopf
    from sweep.write.netcdf import save

    params = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)
    ratios = np.array([0.05, 0.1, 0.5])
    v = np.sqrt(ratios * params.g * params.D0 * params.A)
    ds = sweep.locate_hopf(params, v, model="inertial", bifurcation=False, bistable_band=True)
    assert [TYPES[c] for c in ds["bifurcation_l1"].values] == ["subcritical", "subcritical", "supercritical"]
    assert np.all(ds["types_agree"].values == AGREEMENT.index("not_compared"))
    assert 0.1 < float(np.atleast_1d(ds.attrs["bautin_gamma_over_A"])[0]) < 0.5
    width = ds["bistable_width"].values
    assert np.all(width[:2] > 0) and np.isnan(width[2]) and width[0] > width[1]  # shrinks towards the Bautin point
    back = open_dataset(save(ds, tmp_path / "h.nc"))
    text = hopf_summary(back)
    assert "supercritical 1, subcritical 2" in text and "Bautin point" in text and "gamma/A = 0.128" in text
    assert "relative width" in text
    assert plot_hopf(back, tmp_path / "h.png").stat().st_size > 10_000
    single = sweep.locate_hopf(params, v[:1], model="inertial", bifurcation=False)
    assert "not searched" in hopf_summary(single)
