"""``sweep run`` draws its picture while the netCDF file is written (sweep.api.PreparedRun.finish ``picture``), and
the picture appears only once the data are safe: a failed write leaves no new picture and keeps an old one; Ctrl-C
while drawing still leaves a whole file (and no journal)."""

from __future__ import annotations

import errno
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import sweep
import sweep.plot.files as plot
import sweep.write.netcdf as netcdf
from sweep.cli import main
from sweep.run.journal import journal_path


@pytest.fixture
def config(tmp_path) -> Path:
    scene = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, 6),
                        V=np.logspace(-7, -4, 5))
    path = tmp_path / "scene.toml"
    path.write_text(scene.to_toml())
    return path


def leftovers(folder: Path) -> list[str]:
    """Hidden files or folders (a picture's staging folder) left in ``folder``."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_the_picture_is_drawn_while_the_file_is_written(tmp_path, config, monkeypatch):
    events, real_write, real_plot = [], netcdf.write, plot.plot_file

    def write(*args, **kwargs):
        events.append(("write starts", threading.current_thread().name))
        time.sleep(0.3)  # a slow disk: the drawing must not wait for it
        out = real_write(*args, **kwargs)
        events.append(("write ends", threading.current_thread().name))
        return out

    def plot_file(*args, **kwargs):
        events.append(("picture starts", threading.current_thread().name))
        return real_plot(*args, **kwargs)

    monkeypatch.setattr(netcdf, "write", write)
    monkeypatch.setattr(plot, "plot_file", plot_file)
    out = tmp_path / "s.nc"
    assert main(["run", str(config), "-o", str(out), "-q"]) == 0
    order = [e for e, _ in events]
    assert order.index("picture starts") < order.index("write ends"), events
    assert dict(events)["write starts"] != dict(events)["picture starts"]  # two threads
    assert out.with_suffix(".png").is_file() and not journal_path(out).exists() and leftovers(tmp_path) == []
    xr.testing.assert_equal(sweep.open(out), sweep.run_sweep(sweep.load_scene(config), progress=False))


def test_a_failed_write_leaves_no_new_picture_and_keeps_the_old_one(tmp_path, config, monkeypatch, capsys):
    def full_disk(ds, output, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(output))

    monkeypatch.setattr(netcdf, "write", full_disk)
    out, png = tmp_path / "s.nc", tmp_path / "s.png"
    png.write_bytes(b"the old picture")
    assert main(["run", str(config), "-o", str(out), "-q", "--overwrite"]) == 3
    assert "No space left on device" in capsys.readouterr().err
    assert png.read_bytes() == b"the old picture" and not out.exists() and leftovers(tmp_path) == []
    assert journal_path(out).is_dir()  # kept for --resume


def test_ctrl_c_while_drawing_still_leaves_a_whole_file(tmp_path, config, monkeypatch, capsys):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(plot, "plot_file", interrupted)
    out = tmp_path / "s.nc"
    assert main(["run", str(config), "-o", str(out), "-q"]) == 130
    assert "interrupted" in capsys.readouterr().err
    assert sweep.open(out)["xi_inf"].shape == (6, 5)
    assert not journal_path(out).exists() and not out.with_suffix(".png").exists() and leftovers(tmp_path) == []
