"""Nothing lost, nothing wrong (issue 20): a journal that can only hold its own run, outputs never destroyed without
a question, sizes and writability checked before any work, write failures as one line that keeps the journal.

Every fault is a test. The command line runs in a subprocess (tests/faults.py injects the faults there): exit code,
the one-line message, no traceback, what is on disk afterwards. After each fault, the run resumed (``--resume``)
gives the file an uninterrupted run gives, bitwise. Interrupted runs are built in this process (a stop scene of 60
points in chunks of 4, interrupted by a KeyboardInterrupt after some chunks, as test_resume.py does): cheap, and
exactly what a killed run leaves.
"""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import sweep
from sweep.errors import InputError, JournalWarning, OutputError
from sweep.run.journal import journal_path, rejected_path
from sweep.run.lock import lock_path

sys.path.insert(0, str(Path(__file__).parents[1]))
import faults  # noqa: E402

CHUNK = 4
SCENE = """protocol = "stop"
preset = "sample2"
model = "quasistatic"
rtol = {rtol}
[K_over_M]
start = 1e3
stop = 1e6
num = 15
[V]
start = 1e-7
stop = 1e-5
num = 4
"""
"""60 points, 15 chunks of 4, a V row each (chunk-000000 .. chunk-000014)."""


def scene(rtol: float = 1e-6) -> sweep.Scene:
    return sweep.load_scene(SCENE.format(rtol=rtol))


@pytest.fixture
def config(tmp_path) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(rtol=1e-6))
    return path


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> xr.Dataset:
    """The file of an uninterrupted run (through the journal, as every run with an output)."""
    out = tmp_path_factory.mktemp("reference") / "ref.nc"
    sweep.run_sweep(scene(), progress=False, output=out, chunk_size=CHUNK)
    return sweep.open(out)


def assert_same_file(path: Path, reference: xr.Dataset) -> None:
    """Bitwise the same variables, coordinates and attributes as the reference file (but the run's own history and
    elapsed time)."""
    ds = sweep.open(path)
    varying = ("history", "elapsed_seconds")
    xr.testing.assert_identical(ds.drop_attrs(deep=False).assign_attrs({k: v for k, v in ds.attrs.items()
                                                                        if k not in varying}),
                                reference.drop_attrs(deep=False).assign_attrs(
                                    {k: v for k, v in reference.attrs.items() if k not in varying}))
    for name in ds.variables:
        assert np.array_equal(ds[name].values, reference[name].values, equal_nan=ds[name].dtype.kind == "f"), name


def interrupted(monkeypatch, out: Path, chunks: int = 5, rtol: float = 1e-6) -> Path:
    """A journal of ``out`` holding ``chunks`` chunks of its 15, as a run killed at that moment leaves it."""
    from sweep.run.runner import Interrupted

    faults.interrupt_after(monkeypatch, chunks)
    with pytest.raises(Interrupted):
        sweep.run_sweep(scene(rtol), progress=False, output=out, chunk_size=CHUNK)
    monkeypatch.undo()
    assert len(list(journal_path(out).glob("chunk-*.npz"))) == chunks and not out.exists()
    assert not lock_path(out).exists()  # Ctrl-C releases the lock
    return journal_path(out)


def cli(*args, faults_: tuple[str, ...] = (), cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """``sweep ARGS`` in a subprocess, with the faults of tests/faults.py installed."""
    return subprocess.run(faults.command(list(faults_), [str(a) for a in args]), cwd=cwd, capture_output=True,
                          text=True, timeout=timeout)


def sweep_lines(proc) -> list[str]:
    """The lines of sweep on stderr (not the trace of the faults)."""
    assert "Traceback" not in proc.stderr, proc.stderr
    return [line for line in proc.stderr.splitlines() if line.startswith("sweep:")]


def refused(proc, code: int = 2) -> str:
    """The one line of a refused or failed command."""
    assert proc.returncode == code, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert "Traceback" not in proc.stderr and len(lines) == 1 and lines[0].startswith("sweep: error: "), proc.stderr
    return lines[0]


def resume(config: Path, out: Path, *extra, faults_=("trace-chunks",)) -> subprocess.CompletedProcess:
    """``sweep run CONFIG -o OUT --resume`` (chunks of 4, quiet) in a subprocess, computing chunks traced on stderr."""
    return cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", "--resume", *extra, faults_=faults_,
               cwd=out.parent)


def main_run(config: Path, out: Path, *extra, monkeypatch, capsys) -> subprocess.CompletedProcess:
    """The same command through sweep.cli.main in this process (the kernels are loaded already: seconds saved where
    the subprocess itself is not what is tested), computing chunks traced on stderr; as a CompletedProcess."""
    from sweep.cli import main

    capsys.readouterr()
    with monkeypatch.context() as patch:
        faults.trace_chunks(patch)
        code = main(["run", str(config), "-o", str(out), "--chunk-size", str(CHUNK), "-q", *extra])
    captured = capsys.readouterr()
    return subprocess.CompletedProcess([], code, captured.out, captured.err)


def checked_before_computing(proc, *names: str) -> list[str]:
    """The lines of ``proc`` that name each of ``names``, all printed before the first chunk was computed."""
    lines = proc.stderr.splitlines()
    first = lines.index(faults.TRACE) if faults.TRACE in lines else len(lines)
    found = [next((line for line in lines[:first] if name in line), None) for name in names]
    assert None not in found, (names, proc.stderr)
    return found


def computed(proc) -> int:
    """Chunks computed by a traced command."""
    return proc.stderr.splitlines().count(faults.TRACE)


# --- the journal can only hold its own run ---------------------------------------------------------------------

def test_a_misplaced_chunk_is_moved_aside_before_computing_and_recomputed(tmp_path, config, monkeypatch, reference):
    """Issue 20's reproduction: chunk-000000.npz copied to chunk-000014.npz; --resume consolidated it (other points'
    values, status ok everywhere)."""
    out = tmp_path / "s.nc"
    journal = interrupted(monkeypatch, out)
    shutil.copy(journal / "chunk-000000.npz", journal / "chunk-000014.npz")
    proc = resume(config, out)
    assert proc.returncode == 0, proc.stderr
    (line,) = checked_before_computing(proc, "chunk-000014.npz")
    assert line == (f"sweep: warning: {journal / 'chunk-000014.npz'} holds chunk 0, not chunk 14: moved to "
                    f"{rejected_path(out) / 'chunk-000014.npz'}; chunk 14 will be computed again"), line
    assert len(sweep_lines(proc)) == 1 and computed(proc) == 15 - 5
    assert_same_file(out, reference)
    assert (rejected_path(out) / "chunk-000014.npz").is_file() and not journal.exists() and not lock_path(out).exists()


def test_from_python_a_refused_chunk_is_a_journal_warning(tmp_path, monkeypatch, reference):
    out = tmp_path / "s.nc"
    journal = interrupted(monkeypatch, out)
    shutil.copy(journal / "chunk-000000.npz", journal / "chunk-000014.npz")
    with pytest.warns(JournalWarning, match="chunk-000014.npz holds chunk 0, not chunk 14: moved to"):
        sweep.run_sweep(scene(), progress=False, output=out, chunk_size=CHUNK, resume=True)
    assert_same_file(out, reference)


def test_chunks_of_another_scene_are_refused(tmp_path, config, monkeypatch, capsys, reference):
    out, other = tmp_path / "s.nc", tmp_path / "other.nc"
    journal = interrupted(monkeypatch, out, chunks=3)
    foreign = interrupted(monkeypatch, other, chunks=8, rtol=1e-5)
    for i in (5, 6, 7):  # indices this run has not computed yet, so that only their record can tell
        shutil.copy(foreign / f"chunk-00000{i}.npz", journal)
    proc = main_run(config, out, "--resume", monkeypatch=monkeypatch, capsys=capsys)
    assert proc.returncode == 0, proc.stderr
    lines = checked_before_computing(proc, *(f"chunk-00000{i}.npz" for i in (5, 6, 7)))
    assert all("belongs to another run (plan hash" in line for line in lines), lines
    assert computed(proc) == 15 - 3
    assert_same_file(out, reference)


def test_orphan_chunks_without_a_manifest_are_never_adopted(tmp_path, config, monkeypatch, capsys, reference):
    """A fresh run adopted the chunks of another scene once manifest.json was gone (6000 points up to 143 % off)."""
    out = tmp_path / "s.nc"
    journal = interrupted(monkeypatch, out, chunks=6, rtol=1e-5)
    (journal / "manifest.json").unlink()
    proc = cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", faults_=("trace-chunks",), cwd=tmp_path)
    line = refused(proc)
    assert f"{journal} holds 6 file(s) but no readable manifest.json, so they cannot be checked" in line, line
    assert "--overwrite" in line and "--resume" in line
    assert len(list(journal.glob("chunk-*.npz"))) == 6 and not out.exists()
    proc = main_run(config, out, "--resume", monkeypatch=monkeypatch, capsys=capsys)
    assert proc.returncode == 0, proc.stderr
    (line,) = checked_before_computing(proc, "manifest.json")
    assert f"{journal / 'manifest.json'} is missing" in line, line
    assert f"moved it to {rejected_path(out) / journal.name}" in line, line
    assert computed(proc) == 15
    assert_same_file(out, reference)
    assert len(list((rejected_path(out) / journal.name).glob("chunk-*.npz"))) == 6


def test_truncated_flipped_and_stray_files_are_moved_aside_before_computing(tmp_path, config, monkeypatch, capsys,
                                                                              reference):
    """A truncated chunk gave a BadZipFile traceback, only after all missing chunks were recomputed, forever."""
    out = tmp_path / "s.nc"
    journal = interrupted(monkeypatch, out, chunks=6)
    faults.truncate(journal / "chunk-000001.npz")
    faults.flip_byte(journal / "chunk-000003.npz")
    (journal / "notes.txt").write_text("a stray file")
    shutil.copy(journal / "chunk-000000.npz", journal / "chunk-000099.npz")  # beyond the layout of 15 chunks
    (journal / "chunk-000002.npz.tmp").write_bytes(b"PK torn")  # a write killed before its rename
    proc = main_run(config, out, "--resume", monkeypatch=monkeypatch, capsys=capsys)
    assert proc.returncode == 0, proc.stderr
    truncated, flipped, stray, beyond = checked_before_computing(
        proc, "chunk-000001.npz", "chunk-000003.npz", "notes.txt", "chunk-000099.npz")
    assert "is unreadable (" in truncated and "chunk 1 will be computed again" in truncated
    assert "is unreadable (" in flipped or "does not match its checksum" in flipped, flipped
    assert "is not a file of a sweep journal" in stray and "is not a chunk of this run" in beyond
    assert len(sweep_lines(proc)) == 4 and computed(proc) == 15 - 6 + 2
    assert_same_file(out, reference)
    assert sorted(p.name for p in rejected_path(out).iterdir()) == [
        "chunk-000001.npz", "chunk-000003.npz", "chunk-000099.npz", "notes.txt"]


def test_a_chunk_damaged_during_the_run_is_never_consolidated(tmp_path, monkeypatch, reference):
    """Checked again when read for the file: a chunk that changed on disk after the check at resume is an
    OutputError naming it, moved aside; the next resume computes it again."""
    import sweep.run.journal as journal_module

    out = tmp_path / "s.nc"
    journal = interrupted(monkeypatch, out, chunks=6)
    real_check = journal_module.Journal._check_files

    def check_then_damage(self):
        real_check(self)
        faults.flip_byte(journal / "chunk-000002.npz", at=0.9)

    monkeypatch.setattr(journal_module.Journal, "_check_files", check_then_damage)
    with pytest.raises(OutputError, match="chunk-000002.npz (is unreadable|does not match its checksum)"):
        sweep.run_sweep(scene(), progress=False, output=out, chunk_size=CHUNK, resume=True)
    monkeypatch.undo()
    assert not out.exists() and (rejected_path(out) / "chunk-000002.npz").is_file()
    sweep.run_sweep(scene(), progress=False, output=out, chunk_size=CHUNK, resume=True)
    assert_same_file(out, reference)


def test_an_empty_manifest_is_refused_then_moved_aside(tmp_path, config, monkeypatch, capsys, reference):
    out = tmp_path / "s.nc"
    journal = interrupted(monkeypatch, out, chunks=4)
    (journal / "manifest.json").write_text("")
    line = refused(cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", cwd=tmp_path))
    assert f"{journal} holds 5 file(s) but no readable manifest.json" in line, line
    proc = main_run(config, out, "--resume", monkeypatch=monkeypatch, capsys=capsys)
    assert proc.returncode == 0, proc.stderr
    (line,) = checked_before_computing(proc, "manifest.json")
    assert "manifest.json is empty: nothing in" in line and "computing every chunk afresh" in line, line
    assert computed(proc) == 15
    assert_same_file(out, reference)


def test_a_run_without_resume_never_consumes_a_journal(tmp_path, config, monkeypatch, capsys, reference):
    out = tmp_path / "s.nc"
    journal = interrupted(monkeypatch, out, chunks=5)
    line = refused(cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", cwd=tmp_path))
    assert line == (f"sweep: error: {journal} holds 5 chunk(s) of an earlier run that did not finish: continue it "
                    "with --resume (resume=True), or start over with --overwrite (overwrite=True), which deletes them")
    assert len(list(journal.glob("chunk-*.npz"))) == 5
    proc = main_run(config, out, "--overwrite", monkeypatch=monkeypatch, capsys=capsys)
    assert proc.returncode == 0 and computed(proc) == 15, proc.stderr
    assert_same_file(out, reference)


# --- one run per output ----------------------------------------------------------------------------------------

def test_two_runs_on_one_output(tmp_path, config, monkeypatch, capsys, reference):
    """A run going on in this process (held in its first chunk) holds the lock: a second run, with or without
    --resume (the advice of the first refusal), is refused naming it, before doing anything; once the first ends,
    its file is the uninterrupted one. A lock left by a process that is gone is removed with one line."""
    import sweep.protocols.stop.chunk as stop_chunks

    out = tmp_path / "s.nc"
    real, started, release = stop_chunks.stop_chunk, threading.Event(), threading.Event()

    def held(sc, plan, progress=False):
        compute = real(sc, plan, progress)
        return lambda points: started.set() or release.wait(120) and compute(points)

    monkeypatch.setattr(stop_chunks, "stop_chunk", held)
    first = threading.Thread(target=sweep.run_sweep, args=(scene(),),
                             kwargs=dict(progress=False, output=out, chunk_size=CHUNK))
    first.start()
    try:
        assert started.wait(60)
        for extra in ((), ("--resume",)):
            line = refused(cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", *extra, cwd=tmp_path))
            assert f"{out} is being written by another run (pid {os.getpid()} on host " in line, line
            assert f"delete {lock_path(out)}" in line
        assert len(list(journal_path(out).glob("chunk-*.npz"))) == 0  # the refused runs touched nothing
    finally:
        release.set()
        first.join(120)
    monkeypatch.undo()
    assert_same_file(out, reference)
    assert not lock_path(out).exists()

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    lock_path(out).write_text(json.dumps({"pid": gone.pid, "host": socket.gethostname(), "started": "earlier"}))
    proc = main_run(config, out, "--overwrite", monkeypatch=monkeypatch, capsys=capsys)
    assert proc.returncode == 0, proc.stderr
    assert sweep_lines(proc) == [f"sweep: removed the stale lock {lock_path(out)} of a run that is gone (pid "
                                 f"{gone.pid} on host {socket.gethostname()}, started earlier)"]
    assert not lock_path(out).exists()


# --- outputs never destroyed without a question ----------------------------------------------------------------

@pytest.mark.parametrize("args, words", [
    (("-o", "scene.toml"), "the data output scene.toml is the scene file the command reads"),
    (("-o", "out.png"), "the picture output out.png is also the data output"),
    (("-o", "s.nc", "--png", "scene.toml"), "the picture output scene.toml is the scene file the command reads"),
    (("-o", "."), "the data output . is a folder")])
def test_an_output_equal_to_an_input_or_to_the_picture_is_refused(tmp_path, config, args, words):
    """`-o s.toml` replaced the scene file with the netCDF; `-o out.png` wrote the netCDF, then the picture over it."""
    before = config.read_bytes()
    line = refused(cli("run", "scene.toml", *args, "-q", cwd=tmp_path))
    assert words in line, line
    assert config.read_bytes() == before and sorted(os.listdir(tmp_path)) == ["scene.toml"]


@pytest.mark.slow
def test_an_existing_output_is_replaced_only_with_overwrite(tmp_path, config, monkeypatch, capsys, reference):
    out = tmp_path / "s.nc"
    out.write_text("precious")
    line = refused(cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", cwd=tmp_path))
    assert line == (f"sweep: error: {out} exists: add --overwrite to replace it (overwrite=True from Python), or "
                    "choose another name")
    assert out.read_text() == "precious" and not journal_path(out).exists()
    (tmp_path / "h.nc").write_text("precious")
    line = refused(cli("hopf", config, "-o", "h.nc", cwd=tmp_path))
    assert "h.nc exists: add --overwrite" in line
    (tmp_path / "figs").mkdir()
    (tmp_path / "figs" / "fig4b.txt").write_text("precious")
    assert "fig4b.txt exists: add --overwrite" in refused(cli("reproduce", "fig4b", "-o", "figs", cwd=tmp_path))
    (tmp_path / "p.png").write_text("precious")
    assert main_run(config, out, "--overwrite", monkeypatch=monkeypatch, capsys=capsys).returncode == 0
    assert_same_file(out, reference)
    line = refused(cli("plot", out, "-o", "p.png", cwd=tmp_path))
    assert "p.png exists: add --overwrite" in line and (tmp_path / "p.png").read_text() == "precious"


def test_the_api_replaces_an_existing_file_only_with_overwrite(tmp_path, reference):
    out = tmp_path / "s.nc"
    out.write_text("precious")
    with pytest.raises(InputError, match="exists: add --overwrite to replace it"):
        sweep.run_sweep(scene(), progress=False, output=out, chunk_size=CHUNK)
    with pytest.raises(InputError, match="exists"):
        sweep.save(reference, out)
    assert out.read_text() == "precious"
    sweep.save(reference, out, overwrite=True)
    assert_same_file(out, reference)
    sweep.run_sweep(scene(), progress=False, output=out, chunk_size=CHUNK, overwrite=True)
    assert_same_file(out, reference)
    assert sweep.run_sweep(scene(), progress=False)["xi_inf"].size == 60  # no output: nothing to check


@pytest.mark.parametrize("command", ["hopf", "reproduce"])
def test_hopf_and_reproduce_refuse_a_wrong_kind_of_output_before_computing(tmp_path, config, command):
    (tmp_path / "d").mkdir()
    (tmp_path / "f.nc").write_text("precious")
    t0 = time.perf_counter()
    if command == "hopf":
        line = refused(cli("hopf", config, "-o", "d", cwd=tmp_path))
        assert "the data output d is a folder" in line, line
    else:
        line = refused(cli("reproduce", "all", "-o", "f.nc", cwd=tmp_path))
        assert "the output of reproduce is a folder, and f.nc is a file" in line, line
    assert time.perf_counter() - t0 < 30  # before the computation (hopf ~1 min here, reproduce all several)
    assert sorted(os.listdir(tmp_path)) == ["d", "f.nc", "scene.toml"] and not os.listdir(tmp_path / "d")


# --- writability, free space, write failures during the run -----------------------------------------------------

def test_a_read_only_folder_is_refused_before_any_work(tmp_path, config):
    """As root chmod stops no write: the test then injects EACCES into every file created under the folder."""
    folder = tmp_path / "ro"
    folder.mkdir()
    injected = () if faults.writes_blocked_by_chmod(folder) else (f"eacces-dir:{folder}",)
    try:
        proc = cli("run", config, "-o", folder / "s.nc", "-q", faults_=(*injected, "trace-chunks"), cwd=tmp_path)
    finally:
        folder.chmod(0o755)
    line = refused(proc)
    assert line == (f"sweep: error: cannot write in {folder} (Permission denied), where {folder / 's.nc'} goes: "
                    "choose another output folder or make it writable"), line
    assert not os.listdir(folder) and computed(proc) == 0


@pytest.mark.parametrize("fault, cause, fix", [
    ("enospc-chunk:5", "No space left on device", "free some space on that disk"),
    ("eacces-chunk:5", "Permission denied", "make the folder writable")])
def test_a_chunk_write_failing_mid_run_keeps_the_journal_for_resume(tmp_path, config, reference, fault, cause, fix):
    from sweep.cli import main

    out = tmp_path / "s.nc"
    proc = cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", faults_=(fault,), cwd=tmp_path)
    line = refused(proc, code=3)
    journal = journal_path(out)
    # chunks may finish, and be journaled, in any order (computed side by side: sweep/run/concurrent_chunks.py)
    kept = sorted(p.name for p in journal.iterdir() if p.name != "manifest.json")
    failed = re.fullmatch(rf"sweep: error: could not write {re.escape(str(journal))}/(chunk-\d{{6}}\.npz) \(.*", line)
    assert failed and line == (f"sweep: error: could not write {journal / failed[1]} ({cause}); the 5 finished chunks "
                               f"are kept in {journal}: {fix}, then run the same command with --resume (resume=True) "
                               "to finish"), line
    assert len(kept) == 5 and failed[1] not in kept and all(re.fullmatch(r"chunk-\d{6}\.npz", k) for k in kept), kept
    assert not out.exists() and not lock_path(out).exists()
    assert main(["run", str(config), "-o", str(out), "--chunk-size", str(CHUNK), "-q", "--resume"]) == 0
    assert_same_file(out, reference)


@pytest.mark.parametrize("fault, cause", [("enospc-netcdf", "No space left on device"),
                                          ("mkdir-output:{out}", "Is a directory")])
def test_a_netcdf_write_failing_keeps_the_journal_for_resume(tmp_path, config, monkeypatch, capsys, reference, fault,
                                                             cause):
    """ENOSPC while the file is written (after three blocks), or a folder put where the file goes (EISDIR, at the
    end): one line, exit 3, no .part left, every chunk computed kept in the journal (all of them where the failure
    came at the end); --resume then computes only the others and writes the file."""
    out = tmp_path / "s.nc"
    proc = cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", faults_=(fault.format(out=out),), cwd=tmp_path)
    line = refused(proc, code=3)
    assert line.startswith(f"sweep: error: could not write {out} ({cause}") and "--resume" in line, line
    kept = len(list(journal_path(out).glob("chunk-*.npz")))
    assert kept == 15 if out.is_dir() else 3 <= kept <= 15, kept
    assert not list(tmp_path.glob("*.part")) and not list(tmp_path.glob("**/*.tmp"))
    if out.is_dir():
        out.rmdir()  # the cause fixed
    proc = main_run(config, out, "--resume", monkeypatch=monkeypatch, capsys=capsys)
    assert proc.returncode == 0 and computed(proc) == 15 - kept, proc.stderr
    assert_same_file(out, reference)


def test_a_kill_between_a_region_write_and_its_journal_record_resumes_to_the_same_file(tmp_path, config, monkeypatch,
                                                                                       capsys, reference):
    """SIGKILL right after a block reached the file, before the journal stored its chunk: the torn .part is never
    trusted; --resume computes the chunks the journal lacks (that one included) and writes the file afresh."""
    out = tmp_path / "s.nc"
    proc = cli("run", config, "-o", out, "--chunk-size", CHUNK, "-q", faults_=("kill-after-region:6",), cwd=tmp_path)
    assert proc.returncode == -9, (proc.returncode, proc.stderr)
    kept = len(list(journal_path(out).glob("chunk-*.npz")))
    assert kept < 6 and not out.exists(), kept
    proc = main_run(config, out, "--resume", monkeypatch=monkeypatch, capsys=capsys)
    assert proc.returncode == 0 and computed(proc) == 15 - kept, proc.stderr
    assert_same_file(out, reference)
    assert not list(tmp_path.glob("*.part"))


def test_too_little_free_space_is_refused_before_any_work(tmp_path, monkeypatch):
    import sweep.write.targets

    monkeypatch.setattr(sweep.write.targets, "free_bytes", lambda folder: 1000)
    with pytest.raises(InputError, match=r"not enough free space for .*s\.nc: the run needs ~[\d.]+ kB .*, 1 kB free"):
        sweep.run_sweep(scene(), progress=False, output=tmp_path / "s.nc")
    assert os.listdir(tmp_path) == []


def fill(disk: Path) -> Path:
    """Fill the file system of ``disk`` with one file, as another program would; returns that file."""
    ballast = disk / "ballast"
    fd = os.open(ballast, os.O_WRONLY | os.O_CREAT, 0o644)
    try:
        while os.write(fd, b"\0" * 4096):
            pass
    except OSError as exc:
        assert exc.errno == errno.ENOSPC
    finally:
        os.close(fd)
    return ballast


def chunks_on_disk(out: Path, n: int, timeout: float = 60.0) -> None:
    """Wait until the journal of ``out`` holds ``n`` chunk files (written by the run's helper thread)."""
    t0 = time.perf_counter()
    while len(list(journal_path(out).glob("chunk-*.npz"))) < n:
        assert time.perf_counter() - t0 < timeout, f"{n} chunks not journaled after {timeout} s"
        time.sleep(0.005)


@pytest.mark.parametrize("when", ["chunks", "netcdf"])
def test_a_full_disk_on_a_real_file_system_then_resume(tmp_path, config, monkeypatch, capsys, reference, when):
    """A tmpfs just large enough for the checks, filled by another file after 5 chunks, or just before the netCDF
    file is written (where the HDF5 library says only "HDF error"): the run stops with one line naming the full disk
    (exit 3), and --resume finishes once the space is freed. Needs a tmpfs to mount (root on Linux); the same faults
    injected are test_a_chunk_write_failing_mid_run_keeps_the_journal_for_resume and
    test_a_netcdf_write_failing_keeps_the_journal_for_resume."""
    import sweep.protocols.stop.chunk as stop_chunks
    import sweep.write.netcdf as netcdf
    from sweep.cli import main

    disk = tmp_path / "disk"
    disk.mkdir()
    if sys.platform != "linux" or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=400k", "tmpfs", str(disk)],
                                                 capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here (the injected ENOSPC tests cover the same paths)")
    try:
        out, computed_ = disk / "s.nc", []
        if when == "chunks":
            real = stop_chunks.stop_chunk

            def filling(sc, plan, progress=False):
                compute = real(sc, plan, progress)
                # the disk fills once the first 5 chunks are on disk (journaled in a helper thread: waited for)
                return lambda points: (computed_.append(1), len(computed_) == 6
                                       and (chunks_on_disk(out, 5), fill(disk)), compute(points))[-1]

            monkeypatch.setattr(stop_chunks, "stop_chunk", filling)
        else:  # the disk fills as the file takes its first block
            real_put, puts = netcdf.NetCDFRegions.put, []
            monkeypatch.setattr(netcdf.NetCDFRegions, "put", lambda self, block: (
                not puts and fill(disk), puts.append(1), real_put(self, block))[-1])
        args = ["run", str(config), "-o", str(out), "--chunk-size", str(CHUNK), "-q"]
        capsys.readouterr()
        assert main(args) == 3
        (line,) = capsys.readouterr().err.splitlines()
        assert line.startswith("sweep: error: could not write ") and "(No space left on device" in line, line
        assert "free some space on that disk, then run the same command with --resume" in line, line
        monkeypatch.undo()
        kept = len(list(journal_path(out).glob("chunk-*.npz")))
        # with chunks computed side by side (sweep/run/concurrent_chunks.py), the other thread's chunk may reach the
        # disk
        # while the 6th fills it
        assert (5 <= kept < 15 if when == "chunks" else kept < 15) and not list(disk.glob("**/*.tmp"))
        assert not list(disk.glob("*.part"))
        (disk / "ballast").unlink()
        assert main(args + ["--resume"]) == 0
        assert_same_file(out, reference)
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=True)


def test_a_bad_scheduler_fails_in_seconds_and_leaves_nothing(tmp_path, config):
    t0 = time.perf_counter()
    line = refused(cli("run", config, "-o", "s.nc", "--scheduler", "tcp://127.0.0.1:9", cwd=tmp_path, timeout=60))
    assert time.perf_counter() - t0 < 15, time.perf_counter() - t0  # ~2 s idle; the broken one waited 30 s
    assert "could not connect to the dask scheduler at 'tcp://127.0.0.1:9'" in line
    assert sorted(os.listdir(tmp_path)) == ["scene.toml"]  # no journal, no lock, no file


# --- size before work; every command checks its whole configuration ---------------------------------------------

HUGE = ('preset = "sample2"\n[K_over_M]\nstart = 1e3\nstop = 1e6\nnum = 100000\n'
        '[V]\nstart = 1e-7\nstop = 1e-4\nnum = 100000\n')


def test_a_grid_too_large_for_the_disk_or_the_memory_is_refused_in_under_a_second(tmp_path, capsys):
    """A 1e10-point grid: its dry run says at once what it would need (memory flat with an output: the chunks in
    flight and the picture's lattice; the disk of its file and journal), then that the disk cannot hold it; a run
    to a file is refused for its disk before any work, one in memory (no output) for its memory."""
    from sweep.cli import main

    (tmp_path / "huge.toml").write_text(HUGE)
    out = tmp_path / "huge.nc"
    assert main(["run", str(tmp_path / "huge.toml"), "--dry-run", "-o", str(out)]) == 2
    printed, err = capsys.readouterr()
    assert "10,000,000,000 points" in printed and "estimated memory: ~" in printed and "estimated time" in printed
    memory = re.search(r"estimated memory: ~([\d.]+) (MB|GB)", printed)
    assert memory and float(memory.group(1)) * (1e3 if memory.group(2) == "GB" else 1) < 1500, printed
    assert re.search(r"~[\d.]+ TB with the journal while running, [\d.]+ \w+ free in ", printed), printed
    assert err.startswith(f"sweep: error: not enough free space for {out}: the run needs ~"), err
    t0 = time.perf_counter()
    line = refused(cli("run", "huge.toml", "-o", "huge.nc", cwd=tmp_path, timeout=60))
    assert "not enough free space for huge.nc" in line and time.perf_counter() - t0 < 2.0, line
    t0 = time.perf_counter()
    with pytest.raises(InputError, match="needs ~.* of memory .* or give it an output file"):
        sweep.run_sweep(sweep.load_scene(tmp_path / "huge.toml"))
    assert time.perf_counter() - t0 < 5  # ~0.1 s idle; the margin is for a shared machine
    assert sorted(os.listdir(tmp_path)) == ["huge.toml"]


def test_the_dry_run_of_a_large_grid_plans_a_subsample(tmp_path, capsys):
    from sweep.cli import main

    (tmp_path / "large.toml").write_text(HUGE.replace("100000", "2000"))
    assert main(["run", str(tmp_path / "large.toml"), "--dry-run", "-q"]) == 0
    out = capsys.readouterr().out
    assert "4,000,000 points" in out and "a subsample of 500 K/M x 500 V" in out and "estimated time" in out, out


@pytest.mark.parametrize("chunk_size", [0, -5, np.int64(0), 2.5, True])
def test_the_api_checks_what_the_cli_checks(chunk_size):
    with pytest.raises(InputError, match=r"chunk_size must be an integer >= 1 \(points per chunk\)") as info:
        sweep.run_sweep(scene(), progress=False, chunk_size=chunk_size)
    assert str(info.value).endswith(f"got {chunk_size!r}" if not isinstance(chunk_size, np.generic) else "got 0")
    with pytest.raises(InputError, match="resume=True continues the journal of an output file"):
        sweep.run_sweep(scene(), progress=False, resume=True)


def test_hopf_refuses_unknown_keys(tmp_path, config):
    config.write_text(config.read_text().replace("rtol = 1e-06", "rtoll = 1e-3"))
    line = refused(cli("hopf", config, "-o", "h.nc", cwd=tmp_path))
    assert "unknown key(s) ['rtoll'] in scene" in line, line
    assert not (tmp_path / "h.nc").exists()
