"""What a new user meets in the first hour (issue 16): packaging, one-line errors instead of tracebacks, warnings on
implausible units, logging and progress. The CLI is run through a subprocess: exit code and the one-line message."""

import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numba
import pytest

import sweep
from sweep.jitcache import source_digest

ROOT = Path(__file__).resolve().parents[1]


def sweep_cli(*args, cwd, timeout=600, env=None):
    return subprocess.run([sys.executable, "-m", "sweep.cli", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, env=env)


def one_line_error(proc, code=2) -> str:
    """The stderr of a refused command: exit ``code``, one line, no traceback."""
    assert proc.returncode == code, (proc.returncode, proc.stdout, proc.stderr)
    err = proc.stderr.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    return err


# --- packaging ---------------------------------------------------------------------------------------------------

def test_distribution_name_is_ours_and_the_version_has_one_source():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["name"] == "sweep-friction"  # "sweep" on PyPI is an unrelated project
    assert "version" not in project and "version" in project["dynamic"]
    assert project["license"] == "MIT" and (ROOT / "LICENSE").is_file()
    assert (ROOT / "sweep" / "py.typed").is_file()
    readme = (ROOT / "README.md").read_text()
    assert "sweep[" not in readme  # never an install command naming someone else's distribution


def test_version_flag(tmp_path):
    proc = sweep_cli("--version", cwd=tmp_path)
    assert proc.returncode == 0 and proc.stdout.strip() == f"sweep {sweep.__version__}", proc


# --- one-line errors instead of tracebacks ------------------------------------------------------------------------

SMALL = "preset = \"sample2\"\n[K_over_M]\nvalues = [1e4, 1e5]\n[V]\nvalues = [1e-6, 1e-5]\n"


def _write_kind(kind: str, folder: Path) -> Path:
    """A small file of each kind sweep writes (stop, driven, Hopf, a figure of ``sweep reproduce``)."""
    import numpy as np

    p = sweep.presets["sample2"]
    if kind == "figure":
        from sweep.figures import reproduce

        return reproduce("fig4b", folder)[0].data
    if kind == "hopf":
        return sweep.save(sweep.locate_hopf(p, [1e-6, 1e-4], bifurcation=False), folder / "hopf.nc")
    scene = sweep.Scene(protocol=kind, params=p, K_over_M=np.array([3e4, 3e5]), V=np.array([1e-6, 2e-6]))
    return sweep.save(sweep.run_sweep(scene, progress=False), folder / f"{kind}.nc")


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["stop", "driven", "hopf", "figure"])
def test_info_and_plot_handle_every_file_sweep_writes(tmp_path, kind):
    path = _write_kind(kind, tmp_path)
    proc = sweep_cli("info", str(path), cwd=tmp_path)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr
    assert f"({'stop' if kind == 'figure' else kind} file)" in proc.stdout
    proc = sweep_cli("plot", str(path), "-o", str(tmp_path / "p.png"), cwd=tmp_path)
    assert proc.returncode == 0 and "wrote" in proc.stdout, proc.stderr


def _not_a_sweep_file(what: str, folder: Path) -> Path:
    path = folder / "x.nc"
    if what == "text":
        path.write_text("hello\n")
    elif what == "other netCDF":
        import xarray as xr

        xr.Dataset({"a": ("x", [1.0, 2.0])}).to_netcdf(path)
    elif what == "directory":
        path.mkdir()
    return path


@pytest.mark.parametrize("command", ["info", "plot"])
@pytest.mark.parametrize("what, message", [("missing", "no such file"), ("text", "is not a netCDF file"),
                                           ("other netCDF", "is not a sweep file"), ("directory", "is not a file")])
def test_anything_else_is_refused_in_one_line(tmp_path, command, what, message):
    path = _not_a_sweep_file(what, tmp_path)
    err = one_line_error(sweep_cli(command, str(path), cwd=tmp_path))
    assert err.startswith("sweep: error:") and message in err and "x.nc" in err


@pytest.mark.parametrize("what, error, message", [
    ("missing", FileNotFoundError, "no such file"), ("text", sweep.InputError, "is not a netCDF file"),
    ("other netCDF", sweep.InputError, "is not a sweep file"), ("directory", FileNotFoundError, "is not a file")])
def test_sweep_open_refuses_anything_else_with_one_line_naming_the_path(tmp_path, what, error, message):
    path = _not_a_sweep_file(what, tmp_path)
    with pytest.raises(error) as caught:
        sweep.open(path)
    text = str(caught.value)
    assert message in text and "x.nc" in text and "\n" not in text, text
    assert caught.value.__context__ is None or caught.value.__suppress_context__  # no netCDF traceback chained


@pytest.mark.parametrize("command", ["run", "hopf"])
def test_a_netcdf_file_given_as_scene_is_refused_in_one_line(tmp_path, command):
    path = _write_kind("hopf", tmp_path)
    err = one_line_error(sweep_cli(command, str(path), "-o", str(tmp_path / "o.nc"), cwd=tmp_path))
    assert "not a TOML text file" in err


def test_a_bad_scheduler_address_fails_within_seconds(tmp_path):
    import time

    (tmp_path / "s.toml").write_text(SMALL)
    t0 = time.perf_counter()
    proc = sweep_cli("run", "s.toml", "-o", "o.nc", "--scheduler", "tcp://127.0.0.1:9", cwd=tmp_path, timeout=60)
    err = one_line_error(proc)
    assert "could not connect to the dask scheduler at 'tcp://127.0.0.1:9'" in err
    assert time.perf_counter() - t0 < 25  # 5 s connection timeout plus starting Python (was 30 s + a traceback)
    assert not any((tmp_path / "o.nc.journal").glob("chunk-*"))


def test_a_journal_without_chunks_does_not_block_a_new_run(tmp_path):
    """What a run stopped before its first chunk leaves (refused scheduler, Ctrl-C while compiling): nothing to
    resume, so a new run starts afresh instead of asking for --resume; a journal with chunks is still kept."""
    from sweep.run.journal import Journal, journal_path

    one_chunk = [(0, 1)]
    Journal.open(tmp_path / "o.nc", {"scene": "a"}, one_chunk, resume=False)
    Journal.open(tmp_path / "o.nc", {"scene": "b"}, one_chunk, resume=False)  # no InputError
    journal = Journal.open(tmp_path / "o.nc", {"scene": "b"}, one_chunk, resume=False)
    journal.write(0, {"x": __import__("numpy").zeros(1)})
    with pytest.raises(sweep.InputError, match="resume"):
        Journal.open(tmp_path / "o.nc", {"scene": "b"}, one_chunk, resume=False)
    assert journal_path(tmp_path / "o.nc").is_dir()


@pytest.mark.slow
@pytest.mark.parametrize("delay", [4.0, 8.0])
def test_ctrl_c_while_compiling_is_one_line_and_exit_130(tmp_path, delay):
    """An empty numba cache (NUMBA_CACHE_DIR): the kernels compile for tens of seconds; Ctrl-C in that time (an
    interrupt inside LLVM's code generation was lost there and the run ended in an unrelated RuntimeError)."""
    import os
    import signal
    import time

    (tmp_path / "s.toml").write_text(SMALL)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba-cache")}
    proc = subprocess.Popen([sys.executable, "-m", "sweep.cli", "run", "s.toml", "-o", "o.nc"], cwd=tmp_path,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, (out, err)
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "sweep: interrupted (Ctrl-C)", err


def test_api_messages_print_plain_numbers():
    with pytest.raises(sweep.InputError) as info:
        sweep.solve_point(sweep.presets["sample2"], K_over_M=-2.8e5, V=1e-6)
    assert "got min -280000.0" in str(info.value) and "np." not in str(info.value)
    import numpy as np

    with pytest.raises(sweep.InputError, match=r"got 0$"):
        sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=[1e4], V=[1e-6],
                    max_steps=np.int64(0))


# --- plausibility: likely unit mistakes ---------------------------------------------------------------------------

UM_AS_M = "preset = \"sample2\"\n[K_over_M]\nstart = 1e3\nstop = 1e6\nnum = 4\n[V]\nstart = 0.1\nstop = 100\nnum = 3\n"
NM_AS_M = UM_AS_M.replace("start = 0.1\nstop = 100", "start = 1e3\nstop = 1e5")


@pytest.mark.slow
def test_v_in_um_per_s_is_warned_once_before_any_work(tmp_path):
    """V of 0.1..100 "m/s" (meant µm/s): one warning in the dry run and one in the run, before its first line of
    progress (-q: nothing else). Whether such points solve is the inertial stop's business (test_extremes_inertial)."""
    (tmp_path / "um.toml").write_text(UM_AS_M)
    warning = "sweep: warning: V up to 100 m/s: did you give µm/s? V is in m/s"
    proc = sweep_cli("run", "um.toml", "--dry-run", "-o", "um.nc", cwd=tmp_path)
    assert proc.returncode == 0 and proc.stderr.count(warning) == 1, proc.stderr
    proc = sweep_cli("run", "um.toml", "-o", "um.nc", "-q", cwd=tmp_path)
    assert proc.stderr.startswith(warning) and proc.stderr.count(warning) == 1, proc.stderr


@pytest.mark.slow
def test_a_run_where_most_points_fail_is_warned_and_exits_1(tmp_path):
    """V of 1e3..1e5 "m/s" (meant nm/s): the inertial solve fails at such speeds (step underflow, error above tol);
    the run keeps the values, says how many points failed and why to look at the units, and exits 1."""
    (tmp_path / "nm.toml").write_text(NM_AS_M)
    proc = sweep_cli("run", "nm.toml", "-o", "nm.nc", "-q", cwd=tmp_path)
    warning = "sweep: warning: V up to 100000 m/s: V is in m/s"
    assert proc.returncode == 1 and proc.stderr.count(warning) == 1, (proc.stdout, proc.stderr)
    assert len(proc.stderr.strip().splitlines()) == 2  # -q: the warning and the summary, no progress or notes
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith("sweep: ") and " of 12 points failed (" in last and "check the units" in last, last
    assert int(last.split()[1]) > 6, last  # most of them (cli.MOST_FAILED)
    assert (tmp_path / "nm.nc").exists()  # the values are kept for inspection


@pytest.mark.parametrize("km, v, words", [([1e3, 1e13], [1e-6], "K/M 1000..1e+13 s^-2 is outside"),
                                          ([1e-3, 1e3], [1e-6], "K/M 0.001..1000 s^-2 is outside"),
                                          ([1e3], [1e-6, 5.0], "V up to 5 m/s: did you give µm/s?"),
                                          ([1e3], [1e-6, 1e5], "V up to 100000 m/s: V is in m/s")])
def test_implausible_axes_name_the_likely_unit_mistake(km, v, words):
    from sweep.scene.plausibility import implausible

    assert any(words in m for m in implausible(km, v)), implausible(km, v)
    assert implausible([1e3, 1e6], [1e-7, 1e-4]) == []


def test_solve_point_at_1_m_per_s_warns_and_is_solved_with_inertia():
    """1 m/s is far above any laboratory drive: a PlausibilityWarning says so; the point itself is solved with the
    inertial model (the stiff, oscillatory inertial stop, issue 37), near the pure inertial slip sqrt(gamma/chi)
    (eqs. 14-15), which inertia dominates at this speed (creep adds a little, never takes away)."""
    from sweep.scene.plausibility import PlausibilityWarning

    with pytest.warns(PlausibilityWarning) as record:
        pt = sweep.solve_point(sweep.presets["sample2"], K_over_M=2.8e5, V=1.0, observables=["xi_inf"])
    assert any("V" in str(w.message) for w in record), [str(w.message) for w in record]
    assert int(pt["status"]) == sweep.Status.OK and int(pt["model"]) == 1
    ratio = float(pt["xi_inf"]) / float(pt["xi_inertial"])
    assert 1.0 <= ratio < 1.01, ratio


# --- logging, the compile notice, progress ------------------------------------------------------------------------

def test_first_run_on_an_empty_cache_says_it_compiles_before_anything_else(tmp_path):
    """NUMBA_CACHE_DIR pointing to an empty folder is a fresh machine: the notice comes first, within a second."""
    import os
    import time

    (tmp_path / "s.toml").write_text(SMALL)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba-cache")}
    proc = subprocess.Popen([sys.executable, "-m", "sweep.cli", "run", "s.toml", "-o", "o.nc"], cwd=tmp_path,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.perf_counter()
    first = proc.stderr.readline()
    waited = time.perf_counter() - t0
    proc.kill()
    proc.communicate()
    assert first.startswith("sweep: compiling numba kernels, first run on this machine only: up to ~"), first
    assert waited < 10  # ~0.3 s when idle; the machine is shared


@pytest.mark.slow
def test_verbose_goes_through_the_sweep_logger(tmp_path):
    """(-q, warnings and errors only: test_a_run_where_most_points_fail_is_warned_and_exits_1.)"""
    (tmp_path / "s.toml").write_text(SMALL)
    loud = sweep_cli("run", "s.toml", "-o", "o.nc", "-v", cwd=tmp_path)
    assert loud.returncode == 0 and "sweep: kernels ready in" in loud.stderr, loud.stderr


def test_the_compile_notice_is_logged_from_python(monkeypatch, caplog):
    import logging

    import sweep.run.compile_notice as notice

    monkeypatch.setattr(notice, "_checked", False)
    monkeypatch.setattr(notice, "cache_is_cold", lambda: True)
    with caplog.at_level(logging.INFO, logger="sweep"):
        sweep.solve_point(sweep.presets["sample2"], K_over_M=1e4, V=1e-6, observables=["xi_inf"])
    assert any(r.name == "sweep" and "compiling numba kernels" in r.getMessage() for r in caplog.records)


def test_the_cli_called_from_python_leaves_logging_and_warnings_as_it_found_them(tmp_path, capsys):
    """``main`` in a notebook or a test binds a handler to the stderr of that moment; left behind, it would write to
    a closed stream later and hide the package's messages from the caller's own logging (propagate off)."""
    import logging
    import signal
    import warnings

    from sweep.cli import main

    logger = logging.getLogger("sweep")
    state = lambda: (list(logger.handlers), logger.level, logger.propagate, warnings.showwarning,  # noqa: E731
                     signal.getsignal(signal.SIGINT))
    before = state()
    assert main(["info", str(tmp_path / "missing.nc")]) == 2
    assert state() == before


def test_the_compile_notice_names_only_the_kernel_families_of_the_scene(monkeypatch, caplog):
    import dataclasses
    import logging

    import sweep.run.compile_notice as notice

    quasistatic = dataclasses.replace(sweep.default_scene(), model="quasistatic")
    inertial = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=[1e4], V=[1e-6],
                           model="inertial")
    monkeypatch.setattr(notice, "cache_is_cold", lambda: True)
    # model "auto" compiles the inertial stop only in a chunk whose points need it (none on the default scene)
    for scene, families in ((quasistatic, ["relaxed-slip engine"]), (sweep.default_scene(), ["relaxed-slip engine"]),
                            (inertial, ["inertial stop"])):
        monkeypatch.setattr(notice, "_checked", False)
        caplog.clear()
        with caplog.at_level(logging.INFO, logger="sweep"):
            assert notice.announce_if_cold(scene)
        (message,) = [r.getMessage() for r in caplog.records if r.name == "sweep"]
        assert f"up to ~{sum(notice.COLD_COMPILE_S[f] for f in families)} s" in message, message
        assert all(f in message for f in families) and "driven" not in message, message


def test_cache_is_cold_follows_numba_cache_dir(tmp_path, monkeypatch):
    from sweep.run.compile_notice import cache_is_cold

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert cache_is_cold()
    (tmp_path / "sweep_0123").mkdir()
    (tmp_path / "sweep_0123" / "engine.stop_batch-46.py311.nbi").write_bytes(b"")
    assert not cache_is_cold()


def test_locate_hopf_shows_progress_over_the_velocities(monkeypatch, capsys):
    import numpy as np

    import sweep.run.progress

    monkeypatch.setattr(sweep.run.progress, "SHOW_AFTER_S", 0.0)
    sweep.locate_hopf(sweep.presets["sample2"], np.logspace(-7, -6, 3), bifurcation=False, progress=True)
    err = capsys.readouterr().err
    assert "hopf [" in err and "3/3 velocities" in err and err.endswith("\n")


# --- pictures -----------------------------------------------------------------------------------------------------

def _stop(km, v, **kw):
    import numpy as np

    scene = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.asarray(km),
                        V=np.asarray(v), **kw)
    return sweep.run_sweep(scene, progress=False)


def _map(ds, variable="xi_inf"):
    from sweep.plot.maps import draw_map
    from sweep.plot.style import figure_legend, new_figure

    fig, ax = new_figure("map")
    draw_map(fig, ax, ds, variable)
    figure_legend(fig, ax)
    fig.canvas.draw()
    return fig, ax


def test_two_velocities_hatch_follows_the_line_not_the_cells():
    """Between the two rows of the grid the hatched region ends at the Hopf line (3 % either side of it), where
    hatching grid cells put a stable band under the hatch."""
    import matplotlib.pyplot as plt
    import numpy as np

    from sweep.plot.maps import hopf_line_dense

    ds = _stop(np.logspace(4, 6, 40), [1e-7, 1e-6])
    fig, ax = _map(ds)
    hatched = [c for c in ax.collections if c.get_hatch() == "//"]
    assert len(hatched) == 1
    region = hatched[0].get_paths()[0]  # data coordinates (K/M, V in µm/s)
    v_um, _, kc = hopf_line_dense(ds)
    between = (v_um > 0.12) & (v_um < 0.9)
    assert region.contains_points(np.c_[0.97 * kc[between], v_um[between]]).all()
    assert not region.contains_points(np.c_[1.03 * kc[between], v_um[between]]).any()
    plt.close(fig)


def test_single_map_legend_fits_inside_the_figure():
    import matplotlib.pyplot as plt
    import numpy as np

    ds = _stop(np.logspace(4, 6, 12), [1e-7, 1e-6], observables=["xi_inf", "t50"])
    fig, _ = _map(ds, "t50")
    box = fig.legends[0].get_window_extent()
    assert box.x0 >= 0 and box.x1 <= fig.bbox.width and box.y0 >= 0, (box, fig.bbox)
    plt.close(fig)


def test_the_simulated_line_over_200_velocities_is_thinned():
    import matplotlib.pyplot as plt
    import numpy as np

    ds = _stop(np.logspace(3, 6, 3), np.logspace(-7, -5, 200), simulated_hopf_line=True)
    fig, ax = _map(ds)
    (line,) = [ln for ln in ax.lines if ln.get_label().startswith("Hopf line located by simulation")]
    assert len(line.get_xdata()) <= 25 and "markers at" in line.get_label()
    plt.close(fig)


def test_hopf_gap_shows_the_located_bracket_on_each_point():
    import matplotlib.pyplot as plt
    import numpy as np

    from sweep.plot.curves import draw_hopf_gap
    from sweep.plot.style import new_figure

    ds = sweep.locate_hopf(sweep.presets["sample2"], np.logspace(-7, -6, 4), bifurcation=False)
    fig, ax = new_figure()
    draw_hopf_gap(ax, ds)
    assert ax.containers and "located bracket ± rtol/2" in ax.containers[0].get_label()
    assert "no gap resolved" in ax.get_title()
    plt.close(fig)


def test_dry_run_prints_one_model_line(tmp_path):
    (tmp_path / "s.toml").write_text(SMALL)
    proc = sweep_cli("run", "s.toml", "--dry-run", cwd=tmp_path)
    models = [line for line in proc.stdout.splitlines() if line.split(":")[0].strip() == "model"]
    assert proc.returncode == 0 and len(models) == 1 and "auto" in models[0], proc.stdout


def test_readme_numbers_are_those_of_the_benchmark_results():
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "readme_numbers.py"), "--check"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr


KERNELS_USED = """
import gc, sys
import numpy as np
from numba.core.dispatcher import Dispatcher
import sweep
scene = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, 4),
                    V=np.logspace(-7, -4, 3), model=sys.argv[1])
sweep.run_sweep(scene, progress=False)
for d in gc.get_objects():
    if isinstance(d, Dispatcher) and d.overloads and d.py_func.__module__.startswith("sweep."):
        print(d.py_func.__module__ + "." + d.py_func.__qualname__)
"""


WARMED_UP = """
import gc, sys
from numba.core.dispatcher import Dispatcher
import sweep
from sweep.api import warm_up_kernels
scene = sweep.default_scene()
warm_up_kernels(scene, fan_out=sys.argv[1] == "fan_out")
for d in gc.get_objects():
    if isinstance(d, Dispatcher) and d.overloads and d.py_func.__module__.startswith("sweep."):
        print(d.py_func.__module__ + "." + d.py_func.__qualname__)
"""


def test_the_warm_up_of_sweep_run_loads_only_the_kernels_every_point_uses():
    """``sweep run``'s warm-up of the default scene (model "auto") loads the relaxed-slip lanes and no inertial
    kernel: those compile in the chunk whose points first need them (none here). Before a dask fan-out (the workers
    should load every kernel from the cache) the inertial stop kernels are loaded too."""
    inertial = ("stop_inertial", "rosenbrock", "relax_batch", "relax_points")
    compiled = {}
    for how in ("threads", "fan_out"):
        proc = subprocess.run([sys.executable, "-c", WARMED_UP, how], capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
        compiled[how] = proc.stdout.split()
    assert compiled["threads"] and not [n for n in compiled["threads"] if any(k in n for k in inertial)]
    assert [n for n in compiled["fan_out"] if any(k in n for k in inertial)], compiled["fan_out"]


@pytest.mark.slow
def test_a_stop_scene_compiles_only_the_kernels_its_model_needs():
    """Every kernel compiled (or loaded from numba's cache) in a fresh process after a stop scene: the quasi-static
    model uses the relaxed-slip lanes and none of the driven or inertial kernels; "auto" at most one lane kernel
    more (the lanes that carry the first-order inertial correction, its model choice: with the adaptive lanes that
    run is the point's first, so it compiles instead of the plain kernel where no point needs a second run) and, on
    this grid where no point needs inertia or the per-point fallback, no inertial kernel; never the driven one."""
    def lane_kernel(name: str) -> bool:  # the fixed-step lanes' batch loop, or the adaptive lanes' entry point
        return (name.startswith("sweep.integrate.batch.lanes_batch")
                or name == "sweep.integrate.lanes_adaptive.make_adaptive_lane_kernels.<locals>.relax_runs")

    used = {}
    for model in ("quasistatic", "auto"):
        proc = subprocess.run([sys.executable, "-c", KERNELS_USED, model], capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
        used[model] = proc.stdout.split()
        names = set(used[model])
        assert any(lane_kernel(name) for name in names), names  # sees kernels
        inertial_batches = ("sweep.integrate.batch.relax_batch", "sweep.integrate.batch.relax_points")
        assert not {name for name in names if name in inertial_batches or "stop_inertial" in name
                    or "rosenbrock" in name}, names
        driven = ("sweep.integrate.driven", "sweep.integrate.models.driven")
        assert not any(name.startswith(driven) or "driven_batch" in name
                       for name in names), names
    lanes = {model: sum(lane_kernel(name) for name in names) for model, names in used.items()}
    assert 1 <= lanes["auto"] <= lanes["quasistatic"] + 1, lanes


KERNELS_COMPILED = """
import numpy as np
from numba.core import event
import sweep

compiled, depth = [], [0]
class Listener(event.Listener):  # the kernels compiled from Python (nested compilations not listed)
    def on_start(self, ev):
        depth[0] += 1
    def on_end(self, ev):
        depth[0] -= 1
        dispatcher = ev.data["dispatcher"]
        if depth[0] == 0 and str(dispatcher.py_func.__module__).startswith("sweep."):
            compiled.append(str(dispatcher._uuid))
event.register("numba:compile", Listener())
p, km, v = sweep.presets["sample2"], np.logspace(4, 6, 3), np.logspace(-7, -5, 3)
for kw in ({"model": "quasistatic"}, {"model": "auto"}, {"model": "inertial"},
           {"model": "quasistatic", "observables": ("xi_inf", "t50")},
           {"model": "quasistatic", "observables": ("xi_inf", "trajectory")},
           {"model": "quasistatic", "state_law": "slip"},
           {"protocol": "driven", "model": "quasistatic"}, {"protocol": "driven", "model": "inertial"}):
    sweep.run_sweep(sweep.Scene(**{"protocol": "stop", **kw}, params=p, K_over_M=km, V=v), progress=False)
print(" ".join(sorted(set(compiled))))
"""


@pytest.mark.slow
def test_a_second_process_loads_every_kernel_from_numba_cache():
    """A kernel whose cache key changes from process to process (a factory-built kernel holding a dispatcher of
    random identity, sweep/jitcache.py) compiles again in every new process: seconds lost on every run. The first
    process may compile (an empty cache); the second must load everything. Only the one-point driver's inertial
    variants (the full system and the slow-manifold form) may compile again, on purpose
    (sweep.integrate.driven.INERTIAL_NOT_CACHED), where a point leaves the inertial lanes for them (an undecided
    point's rerun); the lanes themselves load from the cache."""
    run = lambda: subprocess.run([sys.executable, "-W", "ignore", "-c", KERNELS_COMPILED], capture_output=True,  # noqa: E731
                                 text=True, timeout=900)
    first = run()
    assert first.returncode == 0, first.stderr
    second = run()
    assert second.returncode == 0, second.stderr
    again = second.stdout.split()
    inertial = {f"sweep:{source_digest()}:sweep.integrate.batch.driven_batch.<locals>.batch:aging:{variant}"
                for variant in ("inertial", "inertial-slaved")}
    assert set(again) <= inertial, again


def test_a_kernels_identity_changes_with_any_source_of_the_package(tmp_path):
    """Factory-built kernels are keyed in numba's cache by identities that carry a digest of the package's sources
    (sweep/jitcache.py): an edit of any module gives them new keys, so a kernel compiled into another module's loop
    never loads with the code of an older version of its factory (a stale lanes_batch once corrupted the heap)."""
    from sweep.jitcache import pin

    package = tmp_path / "pkg"
    shutil.copytree(Path(sweep.__file__).parent, package, ignore=shutil.ignore_patterns("__pycache__"))
    before = source_digest(package)
    assert before == source_digest(Path(sweep.__file__).parent)  # the names and contents, not where they lie
    edited = tmp_path / "edited"
    shutil.copytree(package, edited)
    module = edited / "integrate" / "lanes_adaptive.py"
    module.write_text(module.read_text() + "\n# an edit\n")
    assert source_digest(edited) != before
    kernel = pin(numba.njit(lambda x: x + 1), "variant")
    assert kernel._uuid.startswith(f"sweep:{source_digest()}:") and kernel._uuid.endswith(":variant")


def test_the_inertial_helper_compiles_the_package_this_process_runs(monkeypatch, tmp_path):
    """The helper process that compiles the inertial stop kernels on a cold cache imports the same sweep as this
    process: started inside a source checkout beside an installed copy (the README's quick start), it imported the
    checkout's files, whose cache entries the installed package never found (45 s instead of 18 s)."""
    import subprocess

    import sweep.run.compile_notice as notice

    started = []

    class Helper:
        def __init__(self, args, **kw):
            started.append(kw.get("cwd"))

        def wait(self, timeout=None):
            return 0

        def poll(self):
            return 0

    monkeypatch.setattr(notice, "cache_is_cold", lambda: True)
    monkeypatch.setattr(subprocess, "Popen", Helper)
    monkeypatch.chdir(tmp_path)
    with notice.inertial_stop_compiled_aside(sweep.default_scene()):
        pass
    assert started and Path(started[0]) == Path(sweep.__file__).resolve().parent.parent


def test_a_stuck_compile_helper_is_killed_after_its_wait(monkeypatch):
    """compiled_aside waits for its helper at most HELPER_WAIT_S once its own block is done: a helper that never
    ends (stuck for any reason) is killed, and the block's caller goes on (it compiles what it still needs)."""
    import subprocess

    import sweep.run.compile_notice as notice

    killed, waited = [], []

    class Stuck:
        def __init__(self, args, **kw):
            pass

        def wait(self, timeout=None):
            waited.append(timeout)
            raise subprocess.TimeoutExpired("python", timeout)

        def poll(self):
            return None

        def kill(self):
            killed.append(True)

    monkeypatch.setattr(notice, "cache_is_cold", lambda: True)
    monkeypatch.setattr(subprocess, "Popen", Stuck)
    with notice.compiled_aside("pass"):
        pass
    assert waited == [notice.HELPER_WAIT_S] and killed == [True]
