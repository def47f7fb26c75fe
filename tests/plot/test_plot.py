"""``sweep plot``: the picture that fits the file (stop maps and transients, driven regimes, Hopf line) at its pixel
size, with what it must show: the Hopf lines where the stability flag flips, the stick-slip side hatched, the V range
without a Hopf line, failed points, units on the axes, the parameters in the title."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402

import sweep  # noqa: E402
from sweep.cli import main  # noqa: E402
from sweep.plot.curves import draw_hopf, draw_psi, draw_xi, trajectory_points  # noqa: E402
from sweep.plot.files import file_kind, plot_file  # noqa: E402
from sweep.plot.maps import draw_map, draw_regime_map  # noqa: E402
from sweep.plot.style import caption, no_hopf_line_band  # noqa: E402

SAMPLE2 = sweep.presets["sample2"]
PAIR, MAP = (520, 1280), (560, 760)  # pixel sizes (rows, columns) of the two-panel and one-panel pictures
V_STAR_UM = np.exp(SAMPLE2.m1 / (2 * SAMPLE2.m2))  # mu1(V) = 0 for sample2: 6.65 um/s (docs/physics.md 5: 6.6)


def png_shape(path) -> tuple[int, int]:
    """(rows, columns) of a PNG that is not blank."""
    image = mpimg.imread(path)
    assert image[..., :3].std() > 0.05, f"{path} looks blank"
    return image.shape[:2]


def labels(ax) -> list[str]:
    return ax.get_legend_handles_labels()[1]


def line(ax, start: str):
    """The line of ``ax`` whose legend label starts with ``start``."""
    found = [ln for ln in ax.get_lines() if ln.get_label().startswith(start)]
    assert found, f"no line labelled {start!r} in {labels(ax)}"
    return found[0]


@pytest.fixture(scope="module")
def stop_file(tmp_path_factory):
    ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=SAMPLE2, K_over_M=np.logspace(3, 6, 10),
                                     V=np.logspace(-7, -4, 8), simulated_hopf_line=True), progress=False)
    ds["status"][2:4, 0] = sweep.Status.ERROR_ABOVE_TOL  # two failed points to mark
    return sweep.save(ds, tmp_path_factory.mktemp("plot") / "stop.nc")


@pytest.fixture(scope="module")
def driven_file(tmp_path_factory):
    ds = sweep.run_sweep(sweep.Scene(protocol="driven", params=SAMPLE2, K_over_M=np.logspace(4, 6, 6),
                                     V=np.logspace(-7, -5, 4)), progress=False)
    return sweep.save(ds, tmp_path_factory.mktemp("plot") / "driven.nc")


@pytest.fixture(scope="module")
def hopf_file(tmp_path_factory):
    ds = sweep.locate_hopf(SAMPLE2, [1e-7, 1e-6, 3e-6, 1e-5, 1e-4])
    return sweep.save(ds, tmp_path_factory.mktemp("plot") / "hopf.nc")


def test_each_kind_of_file_gets_its_picture_from_the_cli(stop_file, driven_file, hopf_file, tmp_path, capsys):
    for path, kind in ((stop_file, "stop"), (driven_file, "driven"), (hopf_file, "hopf")):
        assert file_kind(sweep.open(path)) == kind
        png = tmp_path / f"{kind}.png"
        assert main(["plot", str(path), "-o", str(png)]) == 0
        assert f"wrote {png}" in capsys.readouterr().out
        assert png_shape(png) == PAIR  # stop: xi_inf and stress relaxation; driven: regime and amplitude; hopf: 2
    one = tmp_path / "one.png"
    assert main(["plot", str(stop_file), "-o", str(one), "--variable", "xi_inf"]) == 0
    assert png_shape(one) == MAP


def test_stop_map_shows_the_hopf_line_where_stability_flips(stop_file):
    ds = sweep.open(stop_file)
    fig, ax = plt.subplots()
    draw_map(fig, ax, ds, "xi_inf")
    hopf = line(ax, "Hopf line, linear theory")
    km_line, v_line = hopf.get_xdata(), hopf.get_ydata()
    order = np.argsort(v_line)
    checked = 0
    for j, v_um in enumerate(ds["V"].values * 1e6):
        stable = ds["stable"].values[:, j] == 1
        if stable.all() or not stable.any():
            continue
        k_c = np.exp(np.interp(np.log(v_um), np.log(v_line[order]), np.log(km_line[order])))
        km = ds["K_over_M"].values
        assert km[~stable].max() < k_c < km[stable].min(), v_um
        checked += 1
    assert checked >= 3
    assert line(ax, "Hopf line located by simulation").get_xdata().size == ds.sizes["V"]
    # the stick-slip side hatched; the edge of the range without a Hopf line at mu1(V) = 0
    assert any("//" in (c.get_hatch() or "") for c in ax.collections if hasattr(c, "get_hatch"))
    np.testing.assert_allclose(line(ax, "no Hopf line").get_ydata(), V_STAR_UM, rtol=1e-9)
    assert any(t.startswith("failed (status): error_above_tol 2") for t in labels(ax))
    assert ax.get_xlabel() == "K/M [s$^{-2}$]" and ax.get_ylabel() == "V [µm/s]"
    assert ax.get_xscale() == ax.get_yscale() == "log"
    assert ax.collections[0].get_cmap().name == "viridis"
    plt.close(fig)


def test_stop_map_draws_the_line_moved_by_inertia_where_the_model_has_it():
    params = SAMPLE2.replace(m2=0.0)  # mu1 = m1 at every V; gamma/A = 0.21 at 100 um/s
    ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=params, K_over_M=np.logspace(4, 7, 6),
                                     V=np.logspace(-6, -4, 4)), progress=False)
    fig, ax = plt.subplots()
    draw_map(fig, ax, ds, "xi_inf")
    moved = line(ax, "Hopf line with inertia").get_xdata()
    gamma = ds["V"].values ** 2 / (params.g * params.D0)
    assert moved[-1] == pytest.approx(params.m1 * (1 + gamma[-1] / params.A) * params.g / params.D0, rel=1e-12)
    np.testing.assert_allclose(line(ax, "Hopf line, linear theory").get_xdata(), params.m1 * params.g / params.D0,
                               rtol=1e-12)
    plt.close(fig)


def test_driven_map_regimes_and_amplitude(driven_file):
    ds = sweep.open(driven_file)
    fig, (ax_r, ax_a) = plt.subplots(1, 2)
    draw_regime_map(fig, ax_r, ds)
    draw_map(fig, ax_a, ds, "amplitude")
    assert ax_a.collections[0].get_cmap().name == "magma"
    names = [t.get_text() for t in fig.axes[2].get_yticklabels()]  # the regime colour bar
    assert names == ds["regime"].attrs["flag_meanings"].split()
    # the amplitude is blank (masked) exactly where the point decayed to steady sliding
    amp = ax_a.collections[0].get_array()
    assert np.array_equal(np.ma.getmaskarray(amp), (ds["amplitude"].values.T <= 0) | np.isnan(ds["amplitude"].values.T))
    for ax in (ax_r, ax_a):
        assert "Hopf line, linear theory (eq. 3, quasi-static)" in labels(ax)
    plt.close(fig)


def test_hopf_picture_both_ways(hopf_file):
    ds = sweep.open(hopf_file)
    fig, ax = plt.subplots()
    draw_hopf(ax, ds)
    assert "linear theory, direct (l1 < 0)" in labels(ax)  # sample2's line is direct wherever it exists (l1 < 0)
    assert "located by simulation: supercritical" in labels(ax)
    assert any(t.startswith("no Hopf line") for t in labels(ax))
    patch = [p for p in ax.patches if p.get_label().startswith("no Hopf line")][0]
    assert np.isclose(patch.get_y(), V_STAR_UM, rtol=1e-9)  # the band starts at mu1 = 0 (sample2: 6.65 um/s)
    plt.close(fig)


def test_transients_on_log_axes(tmp_path):
    ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=SAMPLE2, K_over_M=[1e4, 1e5], V=[1e-6, 1e-5],
                                     observables=("xi_inf", "trajectory"), trajectory_tau=(1e-3, 1e3, 31)),
                         progress=False)
    written = plot_file(ds, tmp_path / "grid.png")
    assert [p.name for p in written] == ["grid.png", "grid_trajectories.png"]
    assert [png_shape(p) for p in written] == [PAIR, PAIR]
    single = plot_file(ds.isel(K_over_M=[0], V=[1]), tmp_path / "point.png")
    assert [p.name for p in single] == ["point.png"] and png_shape(single[0]) == PAIR
    fig, (ax_xi, ax_psi) = plt.subplots(1, 2)
    points = trajectory_points(ds)
    assert len(points) == 4
    draw_xi(ax_xi, ds, points)
    draw_psi(ax_psi, ds, points)
    for ax in (ax_xi, ax_psi):
        assert ax.get_xscale() == ax.get_yscale() == "log" and "[1]" in ax.get_xlabel() + ax.get_ylabel()
    assert "eq. 12: early stage at ψ ≈ 1" in labels(ax_xi)
    np.testing.assert_array_equal(line(ax_psi, "asymptote ψ = τ").get_ydata(), ds["tau"].values)
    plt.close(fig)


def test_no_hopf_line_band_is_exact_in_ln_v():
    v = np.logspace(-1, 2, 7)  # um/s
    mu1 = SAMPLE2.m1 - 2 * SAMPLE2.m2 * np.log(v)
    (lo, hi), = no_hopf_line_band(v, mu1)
    assert np.isclose(lo, V_STAR_UM, rtol=1e-12) and hi == v[-1]
    assert no_hopf_line_band(v, np.ones(7)) == []
    assert no_hopf_line_band(v, -np.ones(7)) == [(v[0], v[-1])]
    (lo2, hi2), = no_hopf_line_band(v, -mu1)  # mu1 <= 0 at the slow end instead
    assert lo2 == v[0] and np.isclose(hi2, V_STAR_UM, rtol=1e-12)


def test_title_names_the_parameters(stop_file, hopf_file):
    text = caption(sweep.open(stop_file), "stop")
    for part in ("preset sample2", "A=0.007", "m1=0.0125", "m2=0.0033", "D0=0.7 µm", "rtol 1e-06", "model auto"):
        assert part in text
    assert "preset sample2" in caption(sweep.open(hopf_file), "hopf")
    custom = sweep.run_sweep(sweep.Scene(protocol="stop", params=SAMPLE2.replace(m2=0.001), K_over_M=[1e5],
                                         V=[1e-6]), progress=False)
    assert "preset" not in caption(custom, "x") and "m2=0.001" in caption(custom, "x")


def test_a_lab_scene_is_captioned_in_the_labs_parameters():
    """A load history given in the laboratory's a, b, Dc, mu0 (files store the paper's A, m1, m2, D0) is captioned in
    a, b, Dc (a = A, b = A + m1, Dc = D0: docs/physics.md 7b); a stop scene of the same law keeps the paper's names."""
    lab = sweep.FrictionParams.from_lab(a=0.011, b=0.017, Dc=3e-6, mu0=0.55)
    hist = sweep.run_sweep(sweep.Scene(protocol="history", params=lab, K_over_M=[2e4], V=[1e-6], model="quasistatic",
                                       options={"segments": [{"V_ratio": 1.0, "duration": 1.0},
                                                             {"V_ratio": 10.0, "duration": 1.0}]}), progress=False)
    text = caption(hist, "h")
    for part in ("a=0.011", "b=0.017", "Dc=3 µm", "mu0=0.55", "V0=1 µm/s"):
        assert part in text, (part, text)
    assert "m1=" not in text and "A=" not in text
    stop = sweep.run_sweep(sweep.Scene(protocol="stop", params=lab, K_over_M=[1e5], V=[1e-6]), progress=False)
    assert "A=0.011" in caption(stop, "s") and "a=" not in caption(stop, "s")


def test_what_cannot_be_drawn_is_a_clear_error(stop_file, tmp_path, capsys):
    other = tmp_path / "other.nc"
    xr.Dataset({"foo": ("x", np.arange(3.0))}).to_netcdf(other)
    assert main(["plot", str(other), "-o", str(tmp_path / "o.png")]) == 2
    assert "not a sweep file" in capsys.readouterr().err
    assert main(["plot", str(stop_file), "--variable", "nope", "-o", str(tmp_path / "o.png")]) == 2
    assert "--variable must be" in capsys.readouterr().err
