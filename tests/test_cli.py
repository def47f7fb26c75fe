"""The command line: run (config, dry run, default output names), plot, info, and errors."""

import re
import subprocess
import sys

import pytest

import sweep

CONFIG = """
protocol = "stop"
preset = "sample2"
rtol = 1e-5
observables = ["xi_inf", "t50"]
[params]
m2 = 0.003
[K_over_M]
start = 1e3
stop = 1e6
num = 12
spacing = "log"
[V]
values = [1e-7, 1e-6, 1e-5, 1e-4]
"""


def sweep_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "sweep.cli", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=600)


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(CONFIG)
    return path


@pytest.mark.slow
def test_run_plot_info(config, tmp_path):
    out = tmp_path / "res" / "out.nc"
    proc = sweep_cli("run", str(config), "-o", str(out), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert out.exists() and out.with_suffix(".png").stat().st_size > 10_000
    # "wrote <file> (48 points in T s: computed in C s, R points/s, then the file and the picture; ...)": the rate is
    # the computing's own, not the file's and the picture's
    line = next(t for t in proc.stdout.splitlines() if t.startswith("wrote") and ".nc" in t)
    found = re.search(r"\((\d+) points in ([\d.]+) s: computed in ([\d.e-]+) s, ([\d,]+) points/s", line)
    assert found, line
    n, total, computed, rate = (float(g.replace(",", "")) for g in found.groups())
    assert n == 48 and 0 < computed <= total, line
    assert rate == pytest.approx(n / computed, rel=0.06), line  # the printed seconds are rounded to 2 digits
    ds = sweep.open(out)
    assert ds.sizes == {"K_over_M": 12, "V": 4}
    assert ds.attrs["scene"].count("m2 = 0.003") == 1 and "t50" in ds
    assert "sweep run" in ds.attrs["history"]
    png = tmp_path / "map.png"
    proc = sweep_cli("plot", str(out), "-o", str(png), cwd=tmp_path)
    assert proc.returncode == 0 and png.stat().st_size > 10_000, proc.stderr
    proc = sweep_cli("info", str(out), cwd=tmp_path)
    assert proc.returncode == 0 and "xi_inf" in proc.stdout and "status: ok 48" in proc.stdout, proc.stdout


def test_dry_run_prints_the_plan_and_writes_nothing(config, tmp_path):
    proc = sweep_cli("run", str(config), "--dry-run", "-o", str(tmp_path / "x.nc"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    for word in ("model", "stepper", "step", "horizon", "points", "estimated time"):
        assert word in proc.stdout
    assert not (tmp_path / "x.nc").exists()


def test_bad_config_is_a_clear_error(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(CONFIG.replace("rtol = 1e-5", "rtol = 5"))
    proc = sweep_cli("run", str(bad), "-o", str(tmp_path / "x.nc"), cwd=tmp_path)
    assert proc.returncode == 2 and "rtol" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "x.nc").exists()


NO_LIMIT = "[params]\nm2 = -0.001\n"


@pytest.mark.parametrize("axes", ["[K_over_M]\nvalues = [1e3, 1e4, 1e5]\n[V]\nvalues = [1e-6]\n",
                                  "[K_over_M]\nvalues = [2.8e5]\n[V]\nvalues = [1e-6]\n",
                                  NO_LIMIT + "[K_over_M]\nvalues = [1e3, 1e5]\n[V]\nvalues = [1e-6]\n",
                                  NO_LIMIT + "[K_over_M]\nvalues = [1e3, 1e5]\n[V]\nvalues = [1e-6, 1e-5]\n"])
def test_run_on_a_line_a_point_or_without_finite_values_draws_a_picture(tmp_path, axes):
    """`sweep run` through sweep.cli.main in this process: what is checked is the picture drawn for degenerate
    grids; the command as a separate process is test_run_plot_info's (a subprocess here only added ~2.5 s of
    start-up per case)."""
    from sweep.cli import main

    config = tmp_path / "line.toml"
    config.write_text('preset = "sample2"\n' + axes)
    assert main(["run", str(config), "-o", str(tmp_path / "line.nc")]) == 0
    assert (tmp_path / "line.png").stat().st_size > 10_000
