"""Maps with more points than pixels (sweep/plot/blocks.py): the blocks cover exactly their points' cells, hold the
geometric mean of their points, and the picture says what was done."""

from __future__ import annotations

import logging
import statistics

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import sweep  # noqa: E402
from sweep.plot.blocks import MAX_CELLS, block_edges, block_means, block_size, reduction_note  # noqa: E402
from sweep.plot.maps import draw_map  # noqa: E402


def matplotlib_edges(x: np.ndarray) -> np.ndarray:
    """The cell edges matplotlib itself gives points at ``x`` with shading="nearest" (the reference)."""
    fig, ax = plt.subplots()
    mesh = ax.pcolormesh(x, [0.0, 1.0], np.ones((2, x.size)), shading="nearest")
    edges = mesh.get_coordinates()[0, :, 0]
    plt.close(fig)
    return edges


@pytest.mark.parametrize("n, most, expected", [(1, 400, 1), (400, 400, 1), (401, 400, 2), (1000, 400, 3),
                                               (1200, 400, 3), (1201, 400, 4)])
def test_block_size_is_the_fewest_points_per_block_that_fit(n, most, expected):
    assert block_size(n, most) == expected
    assert -(-n // expected) <= most  # cells drawn


@pytest.mark.parametrize("x", [np.logspace(3, 6, 10), np.array([1.0, 2.0, 7.0, 7.5, 30.0, 31.0, 90.0])])
def test_block_edges_are_matplotlibs_cell_edges_every_s_points(x):
    full = matplotlib_edges(x)
    np.testing.assert_array_equal(block_edges(x, 1), full)
    for s in (2, 3, 4):
        expected = np.append(full[::s], full[-1]) if (x.size % s) else full[::s]
        np.testing.assert_array_equal(block_edges(x, s), expected)
        assert block_edges(x, s).size == -(-x.size // s) + 1


def test_block_means_are_geometric_means_of_the_finite_positive_points():
    rng = np.random.default_rng(3)
    z = 10.0 ** rng.uniform(-3, 3, (7, 11))
    z[0, 0], z[1, 4], z[2, 5], z[6, 10] = np.nan, 0.0, -2.0, np.inf  # never part of a mean
    z[3:6, 6:9] = np.nan  # a whole block without a value: blank
    got = block_means(z, 3, 3)
    assert got.shape == (3, 4)  # uneven last blocks: rows 6, columns 9..10
    for bi, r in enumerate(range(0, 7, 3)):
        for bj, c in enumerate(range(0, 11, 3)):
            values = [v for v in z[r:r + 3, c:c + 3].ravel() if np.isfinite(v) and v > 0]
            if values:
                assert got[bi, bj] == pytest.approx(statistics.geometric_mean(values), rel=1e-12)
            else:
                assert np.isnan(got[bi, bj])
    np.testing.assert_allclose(block_means(z, 1, 1), np.where(np.isfinite(z) & (z > 0), z, np.nan), rtol=1e-14)


def test_reduction_note_says_what_was_drawn():
    assert reduction_note((300, 200), (1, 1)) is None
    assert reduction_note((1000, 401), (3, 2)) == ("1000 x 401 points (K/M x V) shown as 334 x 201 cells: geometric "
                                                   "means of blocks of 3 x 2 points")


def test_a_map_larger_than_the_picture_is_drawn_in_blocks_and_says_so(caplog):
    n_km = MAX_CELLS + 1
    ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=sweep.presets["sample2"],
                                     K_over_M=np.logspace(3, 6, n_km), V=np.logspace(-7, -4, 3)), progress=False)
    fig, ax = plt.subplots()
    with caplog.at_level(logging.INFO, logger="sweep"):
        draw_map(fig, ax, ds, "xi_inf")
    note = f"{n_km} x 3 points (K/M x V) shown as {MAX_CELLS // 2 + 1} x 3 cells: geometric means of blocks of 2 x 1"
    assert ax.get_title().startswith(note)
    assert any(note in r.getMessage() for r in caplog.records)
    mesh = ax.collections[0]
    z = ds["xi_inf"].values.T
    shown = mesh.get_array().reshape(3, -1)
    np.testing.assert_allclose(shown[:, 0], np.sqrt(z[:, 0] * z[:, 1]), rtol=1e-12)  # the first block: 2 points
    np.testing.assert_allclose(shown[:, -1], z[:, -1], rtol=1e-12)  # the last: one point
    assert (mesh.norm.vmin, mesh.norm.vmax) == (z.min(), z.max())  # the colour scale spans every point
    x_edges = mesh.get_coordinates()[0, :, 0]
    assert x_edges[0] == matplotlib_edges(ds["K_over_M"].values)[0]
    assert x_edges[-1] == matplotlib_edges(ds["K_over_M"].values)[-1]
    plt.close(fig)


def test_a_map_within_the_picture_is_drawn_point_by_point():
    ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=sweep.presets["sample2"],
                                     K_over_M=np.logspace(3, 6, 12), V=np.logspace(-7, -4, 5)), progress=False)
    fig, ax = plt.subplots()
    draw_map(fig, ax, ds, "xi_inf")
    assert ax.get_title() == ""
    np.testing.assert_array_equal(ax.collections[0].get_array().reshape(5, 12), ds["xi_inf"].values.T)
    plt.close(fig)
