"""Nothing lost: chunked runs journal their chunks (sweep/run/journal.py), survive SIGKILL and Ctrl-C, and resume to the
same numbers as an uninterrupted run, whatever the chunking."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from faults import interrupt_after

import sweep
from sweep.errors import InputError
from sweep.run.journal import journal_path
from sweep.write.netcdf import open_dataset

P2 = sweep.presets["sample2"]
M2ZERO = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0, D0=0.7e-6)


def stop_scene(**kw) -> sweep.Scene:
    # V up to 300 um/s: some points need inertia (model="auto"), some have no finite limit... all per point
    base = dict(protocol="stop", params=P2, K_over_M=np.logspace(3, 6, 23), V=np.logspace(-7, -3.5, 17))
    return sweep.Scene(**{**base, **kw})


def driven_scene(**kw) -> sweep.Scene:
    v = np.sqrt(np.array([2e-3, 5e-2]) * M2ZERO.g * M2ZERO.D0 * M2ZERO.A)
    base = dict(protocol="driven", params=M2ZERO, K_over_M=np.linspace(0.9, 1.2, 12) * M2ZERO.m1 * M2ZERO.g / M2ZERO.D0,
                V=v)
    return sweep.Scene(**{**base, **kw})


def assert_same_numbers(a: xr.Dataset, b: xr.Dataset) -> None:
    """Every data variable and coordinate bitwise equal (NaN where NaN); attrs such as history may differ."""
    assert set(a.data_vars) == set(b.data_vars)
    for name in list(a.data_vars) + list(a.coords):
        np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)


@pytest.mark.parametrize("make", [stop_scene, driven_scene], ids=["stop", "driven"])
def test_results_do_not_depend_on_the_chunking(make):
    scene = make()
    whole = sweep.run_sweep(scene, progress=False)
    for size in (1, 37):
        assert_same_numbers(whole, sweep.run_sweep(scene, progress=False, chunk_size=size))
    if scene.protocol == "stop":
        assert 0 < int(whole["model"].sum()) < scene.n_points  # both models inside the chunks


@pytest.mark.parametrize(("side", "observables", "model", "size"), [
    (141, ("xi_inf",), "auto", 141 * 141),  # the default scene's 20,000 points: one chunk (plan.ONE_CHUNK_POINTS)
    (1000, ("xi_inf",), "auto", 16384),  # 1e6 points: 61 chunks
    (800, ("xi_inf", "t50"), "auto", 8192),  # 640,000 points: 16384 would leave 40 chunks
    (1000, ("xi_inf", "trajectory"), "auto", 4096),  # a chunk's trajectories are held whole until journaled
    (141, ("xi_inf",), "quasistatic", 141 * 141),
    (182, ("xi_inf",), "auto", 4096),  # 33,124 points: beyond it
    (141, ("xi_inf", "trajectory"), "quasistatic", 4096),
    (141, ("xi_inf",), "inertial", 4096),  # an inertial point costs ~1 ms: the chunks are the progress
])
def test_default_chunks_grow_with_the_grid_and_leave_enough_chunks(side, observables, model, size):
    from sweep.plan.plan import make_plan
    from sweep.protocols.stop.protocol import CHUNKS_AT_LEAST, ONE_CHUNK_POINTS

    scene = stop_scene(K_over_M=np.logspace(3, 6, side), V=np.logspace(-7, -4, side), observables=observables,
                       model=model)
    plan = make_plan(scene)
    assert plan.chunk_size == size
    assert size in (4096, scene.n_points) or scene.n_points // size >= CHUNKS_AT_LEAST
    assert size < scene.n_points or scene.n_points <= ONE_CHUNK_POINTS


COLD_WARM = """
import sys
from pathlib import Path
import numpy as np
sys.path[:0] = [sys.argv[2], str(Path(sys.argv[2]).parent)]  # this test's folder, and tests/ (its support modules)
from test_resume import stop_scene
import sweep
ds = sweep.run_sweep(stop_scene(model="quasistatic"), progress=False)  # (no inertial kernels to compile)
np.savez(sys.argv[1], **{name: ds[name].values for name in ("xi_inf", "xi_inf_error", "steps", "status")})
"""


@pytest.mark.slow
def test_a_kernel_compiled_in_the_process_gives_the_bits_of_one_loaded_from_the_cache(tmp_path):
    """A first run on an empty numba cache (compiling) and a second one (loading what the first cached) give the same
    bits: a kernel whose callees ran as compiled on their own in the first process and as optimised into their caller
    in the second gave other numbers (docs/design.md, "Adaptive lanes"), and a resumed run or dask workers then
    disagreed with the run they continue."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba-cache")}
    for name in ("cold", "warm"):
        subprocess.run([sys.executable, "-c", COLD_WARM, str(tmp_path / f"{name}.npz"), str(Path(__file__).parent)],
                       env=env, check=True, timeout=600)
    cold, warm = np.load(tmp_path / "cold.npz"), np.load(tmp_path / "warm.npz")
    for name in cold.files:
        np.testing.assert_array_equal(cold[name], warm[name], err_msg=name)


def test_a_journaled_run_writes_the_file_and_removes_its_journal(tmp_path):
    out = tmp_path / "s.nc"
    ds = sweep.run_sweep(stop_scene(), progress=False, output=out, chunk_size=50)
    assert out.is_file() and not journal_path(out).exists()
    assert_same_numbers(ds, open_dataset(out))


TIME_RESOLVED = dict(observables=("xi_inf", "trajectory", "t50", "t90", "slip_at"), t_obs=(0.05, 2.0),
                     trajectory_tau=(1e-3, 1e5, 9))


@pytest.mark.parametrize("kw", [{}, TIME_RESOLVED], ids=["xi_inf", "trajectories"])
def test_resume_computes_only_the_missing_chunks_and_checks_the_scene(tmp_path, monkeypatch, kw):
    """A journal holding some chunks (as a killed run leaves it): resume computes the rest only, and the file
    equals an uninterrupted run; a different scene, or no --resume, is refused before any work."""
    import sweep.protocols.stop.chunk as stop_chunks
    import sweep.run.runner as runner

    scene, out = stop_scene(**kw), tmp_path / "s.nc"
    real_chunk = stop_chunks.stop_chunk
    calls = interrupt_after(monkeypatch, 3)
    n_chunks = len(runner.chunk_ranges(scene.shape, 50))  # blocks of 2 V rows (34 points)
    with pytest.raises(runner.Interrupted, match=f"3 of {n_chunks} chunks are saved"):
        sweep.run_sweep(scene, progress=False, output=out, chunk_size=50)
    monkeypatch.setattr(stop_chunks, "stop_chunk", real_chunk)
    assert len(list(journal_path(out).glob("chunk-*.npz"))) == 3 and not out.exists()
    with pytest.raises(InputError, match="resume"):
        sweep.run_sweep(scene, progress=False, output=out, chunk_size=50)
    with pytest.raises(InputError, match="differs in plan_hash, scene"):
        sweep.run_sweep(stop_scene(rtol=1e-5, **kw), progress=False, output=out, chunk_size=50, resume=True)
    with pytest.raises(InputError, match="differs in chunk_size"):
        sweep.run_sweep(scene, progress=False, output=out, chunk_size=60, resume=True)
    import sweep.api as api  # another version of sweep (its sources' digest) may give other numbers: refused

    with monkeypatch.context() as m:
        m.setattr(api, "source_digest", lambda: "0123456789abcdef")
        with pytest.raises(InputError, match="differs in sweep_source .*version of sweep"):
            sweep.run_sweep(scene, progress=False, output=out, chunk_size=50, resume=True)

    computed = []

    def counting_stop_chunk(sc, plan, progress=False):
        compute = real_chunk(sc, plan, progress)
        return lambda points: computed.append(points.size) or compute(points)

    monkeypatch.setattr(stop_chunks, "stop_chunk", counting_stop_chunk)
    resumed = sweep.run_sweep(scene, progress=False, output=out, chunk_size=50, resume=True)
    assert sum(computed) == scene.n_points - sum(calls)
    assert_same_numbers(resumed.load(), sweep.run_sweep(scene, progress=False))
    assert not journal_path(out).exists()


def driven_scene_40() -> sweep.Scene:
    """The driven scene on 40 stiffnesses (80 points, 40 chunks of 2): long enough to be interrupted mid-sweep."""
    return driven_scene(K_over_M=np.linspace(0.9, 1.2, 40) * M2ZERO.m1 * M2ZERO.g / M2ZERO.D0)


@pytest.fixture(scope="module")
def driven_40_reference() -> xr.Dataset:
    """The uninterrupted threads-backend run of driven_scene_40(), computed once for the tests that interrupt it
    (the same scene and the same call each test made on its own; it also warms numba's cache for the subprocesses)."""
    return sweep.run_sweep(driven_scene_40(), progress=False)


def _cli(args, **kw):
    return subprocess.Popen([sys.executable, "-m", "sweep.cli", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, **kw)


def _wait_for_chunks(out: Path, count: int, proc, timeout: float = 120.0) -> None:
    t0 = time.time()
    while len(list(journal_path(out).glob("chunk-*.npz"))) < count:
        assert proc.poll() is None, proc.communicate()
        assert time.time() - t0 < timeout, "the run did not journal chunks in time"
        time.sleep(0.01)


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT], ids=["SIGKILL", "Ctrl-C"])
def test_killed_or_interrupted_cli_run_resumes_to_the_uninterrupted_file(tmp_path, sig, driven_40_reference):
    """`sweep run` killed (SIGKILL) or interrupted (Ctrl-C: exit 130, a clear message) mid-sweep keeps its
    finished chunks; `sweep run --resume` completes them into the same numbers as an uninterrupted run.
    The run that is killed is a real process (what is tested is the signal); the resume is the same command line
    through sweep.cli.main in this process (a second subprocess would only pay the kernels' loading again, ~13 s)."""
    from sweep.cli import main

    scene = driven_scene_40()
    config = tmp_path / "scene.toml"
    config.write_text(scene.to_toml())
    reference = driven_40_reference
    out = tmp_path / "d.nc"
    args = ["run", str(config), "-o", str(out), "-q", "--chunk-size", "2"]
    proc = _cli(args)
    _wait_for_chunks(out, 3, proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    if sig == signal.SIGINT:
        assert proc.returncode == 130 and "--resume" in err, err
    else:
        assert proc.returncode == -signal.SIGKILL
    assert not out.exists() and journal_path(out).is_dir()
    done = len(list(journal_path(out).glob("chunk-*.npz")))
    assert 3 <= done < 40
    assert main(args + ["--resume"]) == 0
    assert_same_numbers(open_dataset(out), reference)
    assert not journal_path(out).exists()
    assert not list(tmp_path.glob("**/*.tmp")), os.listdir(tmp_path)


@pytest.mark.slow
def test_sigkill_at_random_moments_then_resume_gives_the_uninterrupted_numbers(tmp_path, driven_40_reference):
    """The file is written region by region while the chunks compute (sweep/write/regions.py) into a ``.part`` that
    a SIGKILL may leave torn; the journal is what survives. Killed three times at random moments (after a random
    number of chunks, plus a random delay: mid-chunk, mid-journal write, mid-region write), each time resumed by a
    new process, then resumed to the end: the file holds the uninterrupted run's numbers, no .part or .tmp is left.
    80 chunks of one point; the delays are drawn in units of this machine's chunk time (fixed delays of up to 0.3 s
    let a run finish before its kill once the driven chunks got faster)."""
    from sweep.cli import main

    t0 = time.perf_counter()
    sweep.run_sweep(driven_scene_40(), progress=False, chunk_size=1)
    chunk_s = (time.perf_counter() - t0) / 80
    rng = np.random.default_rng(33)
    config = tmp_path / "scene.toml"
    config.write_text(driven_scene_40().to_toml())
    out = tmp_path / "d.nc"
    args = ["run", str(config), "-o", str(out), "-q", "--chunk-size", "1"]
    done = 0
    for kill in range(3):
        proc = _cli(args + (["--resume"] if kill else []))
        _wait_for_chunks(out, min(36, done + int(rng.integers(1, 8))), proc)
        time.sleep(float(rng.uniform(0.0, 3.0)) * chunk_s)  # mid-chunk, mid-journal write, mid-region write
        proc.kill()
        proc.communicate(timeout=120)
        assert not out.exists()
        now = len(list(journal_path(out).glob("chunk-*.npz")))
        assert now >= done
        done = now
    assert main(args + ["--resume"]) == 0
    assert_same_numbers(open_dataset(out), driven_40_reference)
    assert not journal_path(out).exists()
    assert not list(tmp_path.glob("**/*.tmp")) and not list(tmp_path.glob("*.part")), os.listdir(tmp_path)


# --- dask.distributed ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("make, workers, size", [(stop_scene, 2, 29), (driven_scene, 2, 29), (stop_scene, 1, 50)],
                         ids=["stop", "driven", "stop-1-worker"])
@pytest.mark.slow
def test_dask_backend_gives_bitwise_the_same_numbers(make, workers, size):
    """A LocalCluster of one-thread workers, another chunking: the same numbers as the threads backend."""
    scene = make()
    threads = sweep.run_sweep(scene, progress=False)
    on_dask = sweep.run_sweep(scene, progress=False, backend="dask", workers=workers, chunk_size=size)
    assert_same_numbers(threads, on_dask)


def test_dask_workers_run_one_numba_thread_each():
    """NUMBA_NUM_THREADS reaches the worker processes of sweep.local_cluster before numba is imported there (the
    nanny's pre-spawn environment), and each worker has one thread."""
    from distributed import Client

    def numba_threads():
        import numba
        return numba.get_num_threads()

    with sweep.local_cluster(2) as address, Client(address) as client:
        assert set(client.run(numba_threads).values()) == {1}
        assert {w["nthreads"] for w in client.scheduler_info()["workers"].values()} == {1}


@pytest.mark.slow
def test_a_cluster_without_this_sweep_is_refused_before_any_work(monkeypatch):
    """Workers that cannot import sweep, or run other sources (which may give other numbers): one line, before any
    chunk is sent (here the probe each worker evaluates is replaced by one that fails, and by another digest)."""
    from distributed import Client

    import sweep.run.backends as backends

    with sweep.local_cluster(1) as address, Client(address) as client:
        backends.check_workers_run_this_sweep(client)  # this process's own sources: accepted
        monkeypatch.setattr(backends, "WORKER_PROBE", "__import__('no_sweep_here')")
        with pytest.raises(InputError, match=r"1 of 1 dask workers cannot import sweep \(ModuleNotFoundError"):
            backends.check_workers_run_this_sweep(client)
        monkeypatch.setattr(backends, "WORKER_PROBE", "'0123456789abcdef'")
        with pytest.raises(InputError, match="the dask workers run other sweep sources .digest 0123456789abcdef"):
            backends.check_workers_run_this_sweep(client)


@pytest.mark.slow
def test_sweep_run_on_an_existing_cluster_started_elsewhere(tmp_path):
    """`sweep run --scheduler ADDRESS` on a cluster of separate processes (`dask scheduler`, `dask worker` with one
    thread and NUMBA_NUM_THREADS=1, as a user would start them): the same file as the threads backend."""
    from distributed import Client

    from sweep.run.backends import WORKER_ENV

    scheduler_file = tmp_path / "scheduler.json"
    common = ["--scheduler-file", str(scheduler_file), "--no-dashboard"]
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--port", "0", *common],
                              **quiet)]
    try:
        with Client(scheduler_file=str(scheduler_file), timeout=60) as client:
            procs.append(subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", "--nworkers", "2",
                                           "--nthreads", "1", *common], env={**os.environ, **WORKER_ENV}, **quiet))
            client.wait_for_workers(2, timeout=120)
            address = client.scheduler.address
        scene = stop_scene()
        config, out = tmp_path / "scene.toml", tmp_path / "s.nc"
        config.write_text(scene.to_toml())
        run = _cli(["run", str(config), "-o", str(out), "-q", "--chunk-size", "40", "--scheduler", address])
        _, err = run.communicate(timeout=600)
        assert run.returncode == 0, err
        assert_same_numbers(open_dataset(out), sweep.run_sweep(scene, progress=False))
    finally:
        for proc in procs[::-1]:
            proc.terminate()
            proc.wait(timeout=60)


@pytest.mark.slow
def test_a_worker_killed_mid_sweep_is_retried_and_the_run_completes(tmp_path, driven_40_reference):
    """SIGKILL of one dask worker process while chunks are in flight: the nanny restarts it, dask reruns its
    chunks, and the journaled run completes to the same numbers."""
    import threading

    from distributed import Client, LocalCluster

    scene = driven_scene_40()
    reference = driven_40_reference
    out = tmp_path / "d.nc"
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        pids = client.run(os.getpid)
        result = {}
        run = threading.Thread(target=lambda: result.setdefault("ds", sweep.run_sweep(
            scene, progress=False, output=out, chunk_size=2, backend="dask", scheduler=cluster.scheduler_address)))
        run.start()
        t0 = time.time()
        while len(list(journal_path(out).glob("chunk-*.npz"))) < 3:
            assert run.is_alive() and time.time() - t0 < 120
            time.sleep(0.05)
        os.kill(next(iter(pids.values())), signal.SIGKILL)
        run.join(timeout=300)
        assert not run.is_alive()
        assert set(client.run(os.getpid).values()) != set(pids.values())  # a new worker process took over
    assert_same_numbers(result["ds"], reference)
    assert_same_numbers(open_dataset(out), reference)


def test_a_local_cluster_leaves_the_drivers_environment_as_it_was():
    """The nannies of a LocalCluster run in this process and set the workers' variables in os.environ; they are put
    back (numba would refuse to compile here with a NUMBA_NUM_THREADS that differs from its thread pool)."""
    from sweep.run.backends import WORKER_ENV

    before = {key: os.environ.get(key) for key in WORKER_ENV}
    with sweep.local_cluster(1):
        assert {key: os.environ.get(key) for key in WORKER_ENV} == before
    assert {key: os.environ.get(key) for key in WORKER_ENV} == before


@pytest.mark.parametrize("kw, name", [(dict(backend="mpi"), "backend"), (dict(workers=2), "workers"),
                                      (dict(backend="dask", workers=0), "workers"),
                                      (dict(backend="dask", workers=2, scheduler="tcp://x:1"), "scheduler")])
def test_bad_backend_arguments_name_the_parameter(kw, name, tmp_path):
    with pytest.raises(InputError, match=name):
        sweep.run_sweep(stop_scene(), progress=False, output=tmp_path / "x.nc", **kw)
    assert not journal_path(tmp_path / "x.nc").exists()  # refused before any work
