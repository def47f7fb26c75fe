"""A run's file written block by block (sweep/write/regions.py, sweep.write.netcdf.NetCDFRegions): the same values as
the whole Dataset written at once, each block in its own storage chunks, written while the next chunks compute; a
grid too large to hold returns the file and draws a lattice of it."""

from __future__ import annotations

import math
import threading

import netCDF4
import numpy as np
import pytest
import xarray as xr

import sweep
from sweep.plan.layout import block_shape, chunk_bounds
from sweep.write.netcdf import open_dataset

P2 = sweep.presets["sample2"]
VARYING = ("history", "elapsed_seconds")


def stop(**kw) -> sweep.Scene:
    return sweep.Scene(**{"protocol": "stop", "params": P2, "K_over_M": np.logspace(3, 6, 11),
                          "V": np.logspace(-7, -3.5, 13), **kw})


SCENES = {
    "stop": stop,
    "trajectories": lambda: stop(observables=("xi_inf", "trajectory", "t50", "slip_at"), t_obs=(0.05, 2.0),
                                 trajectory_tau=(1e-3, 1e5, 7)),
    "axes": lambda: stop(K_over_M=np.logspace(3, 6, 5), V=np.logspace(-7, -4, 4),
                         axes={"A": [0.008, 0.012, 0.02], "m2": [0.0, 0.001]}),
    "driven": lambda: sweep.Scene(protocol="driven", params=P2, K_over_M=np.logspace(4, 6, 6),
                                  V=np.logspace(-7, -5, 5)),
}


def assert_bitwise(a: xr.Dataset, b: xr.Dataset) -> None:
    """Every variable and coordinate with the same dtype, dims and bits (NaN where NaN), the same attributes (but
    the run's own history and elapsed time)."""
    assert list(a.data_vars) == list(b.data_vars) and set(a.coords) == set(b.coords)
    for name in list(a.variables):
        x, y = a[name], b[name]
        assert x.dims == y.dims and x.dtype == y.dtype, name
        assert np.array_equal(x.values, y.values, equal_nan=x.dtype.kind == "f"), name
        assert x.attrs.keys() == y.attrs.keys() and all(np.array_equal(x.attrs[k], y.attrs[k]) for k in x.attrs), name
    assert {k: v for k, v in a.attrs.items() if k not in VARYING} == {k: v for k, v in b.attrs.items()
                                                                      if k not in VARYING}


@pytest.mark.parametrize("name", list(SCENES))
def test_region_writes_give_the_file_of_the_whole_dataset_bit_for_bit(name, tmp_path):
    """Chunk sizes of one point, of part of a row, of rows and of the whole grid; the file read back equals the
    in-memory run written whole with xarray (sweep.save), and the returned Dataset equals both."""
    scene = SCENES[name]()
    in_memory = sweep.run_sweep(scene, progress=False)
    whole = open_dataset(sweep.save(in_memory, tmp_path / "whole.nc"))
    row = math.prod(scene.shape[1:])
    for size in (1, max(1, row // 2), 2 * row, scene.n_points):
        out = tmp_path / f"r{size}.nc"
        returned = sweep.run_sweep(scene, progress=False, output=out, chunk_size=size)
        in_file = open_dataset(out)
        assert_bitwise(in_file, whole)
        assert_bitwise(returned.load(), in_file)


def test_each_block_fills_its_own_storage_chunks(tmp_path):
    """Every grid variable is stored in chunks of the block's shape (with its trailing dims whole), so that no two
    chunks of a run share a storage chunk, and each block is written once."""
    import sweep.write.netcdf as netcdf

    scene, size = SCENES["trajectories"](), 20
    puts = []
    real_put = netcdf.NetCDFRegions.put

    def counting(self, block):
        puts.append(block.slices)
        return real_put(self, block)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(netcdf.NetCDFRegions, "put", counting)
        sweep.run_sweep(scene, progress=False, output=tmp_path / "s.nc", chunk_size=size)
    flat = np.arange(scene.n_points).reshape(scene.shape)
    assert sorted(int(flat[s].min()) for s in puts) == [lo for lo, _ in chunk_bounds(scene.shape, size)]
    block = block_shape(scene.shape, size)
    with netCDF4.Dataset(tmp_path / "s.nc") as nc:
        grid = [v for v in nc.variables.values() if v.dimensions[:2] == ("K_over_M", "V")]
        assert {v.name for v in grid} >= {"xi_inf", "status", "xi", "psi", "slip_at"}
        for var in grid:
            assert tuple(var.chunking()) == block + var.shape[2:], var.name


def test_the_file_is_written_while_the_chunks_compute(tmp_path):
    """A block reaches the file before the last chunk has started computing: writing overlaps the compute."""
    import sweep.protocols.stop.chunk as stop_chunks
    import sweep.write.netcdf as netcdf

    events, lock = [], threading.Lock()
    real_put, real_chunk = netcdf.NetCDFRegions.put, stop_chunks.stop_chunk

    def put(self, block):
        with lock:
            events.append("written")
        return real_put(self, block)

    def chunk(scene, plan, progress=False):
        compute = real_chunk(scene, plan, progress)

        def run(points):
            with lock:
                events.append("computing")
            return compute(points)
        return run

    scene = stop(K_over_M=np.logspace(3, 6, 40))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(netcdf.NetCDFRegions, "put", put)
        patch.setattr(stop_chunks, "stop_chunk", chunk)
        sweep.run_sweep(scene, progress=False, output=tmp_path / "s.nc", chunk_size=13)
    assert events.count("computing") == events.count("written") == 40
    last_start = len(events) - 1 - events[::-1].index("computing")
    assert "written" in events[:last_start], events


def test_a_grid_larger_than_the_lattice_returns_its_file_and_draws_a_lattice(tmp_path, monkeypatch):
    """Past LATTICE_BYTES the run holds every n-th point along each dim for its picture (attribute ``lattice``),
    the same values as the file's there, and returns the file opened lazily."""
    import sweep.api as api

    scene = stop(K_over_M=np.logspace(3, 6, 31), V=np.logspace(-7, -3.5, 23))
    monkeypatch.setattr(api, "lattice_steps", lambda shape, per_point: sweep.write.regions.lattice_steps(
        shape, per_point, budget=100 * per_point))
    drawn = []
    with api.prepare_run(scene, tmp_path / "s.nc") as run:
        returned = run.finish(progress=False, picture=drawn.append)
    (lattice,) = drawn
    in_file = open_dataset(tmp_path / "s.nc")
    step = lattice.attrs["lattice"].split()[1].rstrip("th")
    every = {d: slice(None, None, int(step)) for d in scene.dims}
    assert lattice.sizes["K_over_M"] * lattice.sizes["V"] <= 100 < scene.n_points
    assert_bitwise(lattice.drop_attrs(deep=False), in_file.isel(every).drop_attrs(deep=False))
    assert_bitwise(returned.load(), in_file)
    assert run.totals.points == scene.n_points and sum(run.totals.counts["status"].values()) == scene.n_points
