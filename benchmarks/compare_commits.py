#!/usr/bin/env python
"""Compare two sweep trees (an old commit and a new one) for speed, first-call compile time and numbers.

    python benchmarks/compare_commits.py [--old REV] [--new REV | --new-tree DIR] [--repeats N] [--compile-repeats N]
                                         [--quick | --self-test] [--out benchmarks/results/compare_commits.json]

Defaults: old = ee0f86c (the release before the core restructure), new = the tree this script is run from. A REV
is checked out with ``git worktree add --detach`` and removed afterwards.

Everything that touches sweep runs in a fresh subprocess of this same script (``--worker``) with
``PYTHONPATH=<tree>``, so each tree's own package is measured; a worker checks that ``import sweep`` resolved
into its tree. Workers use only the public API both trees share (sweep.Scene, default_scene, run_sweep,
solve_point, locate_hopf, presets, FrictionParams, Status names in the Dataset) and tests/cases.py of the tree
this script is run from (the same case parameters go to both trees). The parent process never imports sweep.

1. compile  first-call time from an empty numba cache (NUMBA_CACHE_DIR = a new empty directory; the kernels use
            cache=True and numba then writes there, not into sweep/__pycache__): ``import sweep``, then the first
            and second call of a workload; compile_s = first - second. Families: the default scene (model
            "auto": everything it needs), quasi-static relaxed slip, time-resolved stop, driven, inertial stop;
            --compile-repeats runs per tree (default 1), alternated, the smallest compile_s kept.
            Trees whose Scene has ``simulated_hopf_line`` (off by default there) run with it on, as the older trees
            always did, so that both compile and run the same work.
2. numbers  xi_inf (and status, steps) at rtol 1e-6 on the default scene (model quasistatic and auto) and on
            every case of tests/cases.py (solve_point as tests/plan/test_accuracy.py calls it, model auto and
            quasistatic; and quasi-static with t50/t90, the per-point path), saved per tree as .npz and
            compared: max relative difference (NaN == NaN), statuses that differ (PASS: <= 1e-12, none), steps
            that differ (reported only).
3. speed    per workload, one warm-up call then --timed-calls timed calls in each subprocess; old and new alternate
            (old, new, old, new, ...) --repeats times; min wall per tree; ratio new/old (PASS: <= 1.05). The
            load average is recorded before and after each figure.

Timing workers use a numba cache that persists between runs (under the temp dir, one per tree; a REV tree is
checked out at a fixed path with its files' mtimes set to the commit time, so numba finds its cache again), so
warm-ups load kernels instead of compiling them. Compile measurements never use it.

Writes --out (JSON: machine, versions, the exact worker commands, every timing) and prints a summary.
--quick: tiny grids, one repeat, only the driven compile family (the cheapest): checks that the script works
(~6 min the first time a commit is measured: every kernel compiles into the trees' kept caches).

--self-test: the script's own machinery in seconds (the smoke run of tests/test_benchmarks.py): --old (default
HEAD) checked out as a worktree as above, the new tree as it is, one worker per tree for each part, on the
SELF_TEST workload instead of the real ones: every workload's inputs built in both trees (scenes made, not run),
one small kernel of the tree compiled into the empty cache (sweep.integrate.models.stop.tail_is_accurate: the compile
part),
the analytic Hopf line timed (the speed part), and as numbers the closed-form xi_inf (m2 = 0) of every case of
tests/cases.py. The timing caches live in the scratch directory. Checks, in the JSON under self_test (exit 1 if one
fails): each compile worker wrote its kernel into its empty cache, the numbers of both trees are equal, the worktree
was removed.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import datetime as _dt
import fcntl
import hashlib
import json
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
from _machine import cpu_model, loadavg, usable_cpus

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
DEFAULT_OLD = "ee0f86c"
DEFAULT_OUT = HERE / "results" / "compare_commits.json"
SPEED_LIMIT = 1.05
"""A figure passes if new / old wall time <= this."""
NUMBERS_LIMIT = 1e-12
"""Numbers pass if the max relative difference is <= this (and no status differs)."""
RTOL = 1e-6
CACHE_ROOT = Path(tempfile.gettempdir()) / "sweep-compare-commits"

WORKLOADS = {
    "default_quasistatic": "default scene (200 x 100), model quasistatic: relaxed slip, lane kernels",
    "default_auto": "default scene as is (model auto: model choice, inertial points)",
    "time_resolved": "stop 40 x 40, quasistatic, trajectory + t50 + t90: per-point path",
    "dp5": "stop 100 x 100, quasistatic, method dp5 (adaptive)",
    "dop853": "stop 100 x 100, quasistatic, method dop853 (adaptive)",
    "inertial_stop": "stop 20 x 20, model inertial",
    "driven_quasistatic": "driven 24 x 24 around the Hopf line (K/M 1e4..1e6, V 0.1..10 um/s), quasistatic",
    "driven_inertial": "driven 8 x 8 (K/M 1e4..1e6, V 0.1..10 um/s), model inertial",
    "hopf_quasistatic": "locate_hopf, sample2, 20 velocities 0.1..5 um/s, quasistatic, with bifurcation type",
    "hopf_inertial": "locate_hopf, sample2 with m2 = 0, 20 velocities (gamma/A 1e-3..10), inertial, no type",
}
COMPILE_FAMILIES = {  # family -> workload whose first call compiles it (the quick size where the run is long)
    "default_auto": ("default_auto", False),
    "quasistatic_relaxed": ("default_quasistatic", False),
    "time_resolved": ("time_resolved", True),
    "driven": ("driven_quasistatic", True),
    "inertial_stop": ("inertial_stop", True),
}
QUICK_COMPILE_FAMILIES = ("driven",)
"""--quick measures the cheapest family to compile (~10-20 s a tree), only to check that the step works."""
NUMBER_SETS = ("default_quasistatic", "default_auto", "cases_auto", "cases_quasistatic", "cases_time_resolved")
SELF_TEST = "self_test"
SELF_TEST_WORKLOADS = {SELF_TEST: "--self-test: every workload's inputs built (not run), one small kernel compiled "
                                  "(sweep.integrate.models.stop.tail_is_accurate), the analytic Hopf line over 20 "
                                  "velocities"}
SELF_TEST_COMPILE_FAMILIES = {SELF_TEST: (SELF_TEST, True)}
SELF_TEST_NUMBER_SETS = (SELF_TEST,)


# ================================================================================ worker side (imports sweep)

def make_workload(name: str, quick: bool) -> tuple[Callable[[], object], dict]:
    """The call of workload ``name`` (see WORKLOADS) and its inputs (:func:`describe`d, for checking that both
    trees ran the same scene); quick: every grid axis and velocity list 4x shorter."""
    import sweep

    def n(size: int) -> int:
        return max(3, size // 4) if quick else size

    def grid(nk: int, nv: int, k: tuple[float, float] = (3, 6), v: tuple[float, float] = (-7, -4)) -> dict:
        return {"K_over_M": np.logspace(*k, n(nk)), "V": np.logspace(*v, n(nv))}

    def run(**changes: object) -> tuple[Callable[[], object], dict]:
        base = sweep.default_scene()
        if "simulated_hopf_line" in type(base).__dataclass_fields__:  # like for like: older trees always located it
            base = dataclasses.replace(base, simulated_hopf_line=True)
        scene = derive_scene(base, changes)
        return (lambda: sweep.run_sweep(scene, progress=False)), describe(scene)

    def hopf(params, v: np.ndarray, **kw: object) -> tuple[Callable[[], object], dict]:
        return (lambda: sweep.locate_hopf(params, v, **kw)), describe({"params": params, "V": v, **kw})

    qs = {"model": "quasistatic"}
    driven = {"protocol": "driven", "observables": None, **grid(24, 24, k=(4, 6), v=(-7, -5))}
    p2 = sweep.presets["sample2"]
    default_grid = grid(200, 100) if quick else {}
    if name == SELF_TEST:
        built = {w: make_workload(w, True)[1] for w in WORKLOADS}  # the scenes made (checked by the tree), not run
        from sweep import physics
        try:
            from sweep.integrate.models.stop import tail_is_accurate  # numba cache=True: compiles into the empty cache
        except ImportError:  # a tree without it: nothing compiles
            tail_is_accurate = None
        v = np.logspace(-7, np.log10(5e-6), 20)

        def call() -> object:
            if tail_is_accurate is not None:
                tail_is_accurate(1.0, 0.5, 0.1, 3.0, 1e-3, 1e-6)
            return physics.hopf_K_over_M(v, p2.A, p2.m1, p2.m2, p2.D0, p2.V0, p2.g)

        return call, {**built, "self_test_V": describe(v)}
    if name == "default_quasistatic":
        return run(**default_grid, **qs)
    if name == "default_auto":
        return run(**default_grid)
    if name == "time_resolved":
        return run(**grid(40, 40), **qs, observables=("xi_inf", "trajectory", "t50", "t90"))
    if name in ("dp5", "dop853"):
        return run(**grid(100, 100), **qs, method=name)
    if name == "inertial_stop":
        return run(**grid(20, 20), model="inertial")
    if name == "driven_quasistatic":
        return run(**driven, **qs)
    if name == "driven_inertial":
        return run(**{**driven, **grid(8, 8, k=(4, 6), v=(-7, -5))}, model="inertial")
    if name == "hopf_quasistatic":
        v = np.logspace(-7, np.log10(5e-6), n(20))
        return hopf(p2, v, model="quasistatic")
    if name == "hopf_inertial":
        p = dataclasses.replace(p2, m2=0.0)
        v = np.sqrt(np.logspace(-3, 1, n(20)) * p.g * p.D0 * p.A)
        return hopf(p, v, model="inertial", bifurcation=False)
    raise ValueError(f"unknown workload {name!r}; known: {list(WORKLOADS)}")


def describe(value: object) -> object:
    """A JSON-able copy of a workload's inputs (Scene, FrictionParams, arrays, mappings, sequences)."""
    if dataclasses.is_dataclass(value):
        return {f.name: describe(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, dict) or hasattr(value, "keys"):
        return {str(k): describe(value[k]) for k in value.keys()}
    if isinstance(value, (np.ndarray, tuple, list)):
        return [describe(v) for v in value]
    return value.item() if isinstance(value, np.generic) else value


def derive_scene(base, changes: dict):
    """dataclasses.replace(base, **changes), after checking that this tree's Scene has every field changed."""
    missing = sorted(set(changes) - set(type(base).__dataclass_fields__))
    if missing:
        raise TypeError(f"this tree's sweep.Scene has no field(s) {missing}")
    return dataclasses.replace(base, **changes)


def status_names(ds) -> np.ndarray:
    """The status of every point as its name (flag_meanings), so that a renumbering does not count as a change."""
    names = ds["status"].attrs["flag_meanings"].split()
    codes = dict(zip((int(v) for v in ds["status"].attrs["flag_values"]), names))
    return np.array([codes[int(v)] for v in np.ravel(ds["status"].values)])


def number_set(name: str, quick: bool, cases_file: Path) -> tuple[dict[str, np.ndarray], dict]:
    """Arrays of one number set (NUMBER_SETS) at rtol 1e-6: xi_inf, status (names), steps (and t50, t90); and
    the inputs."""
    import sweep

    if name == SELF_TEST:  # closed form where m2 = 0 (NaN elsewhere): no kernel runs
        from sweep import physics

        cases = load_cases(cases_file)
        with np.errstate(all="ignore"):
            xi = np.array([float(physics.xi_inf_m2zero(c["chi"], c["A"], c["mu1"])) if c["m2"] == 0 else np.nan
                           for c in map(cases.case_params, cases.ALL_CASES)])
        return {"case": np.array([c.name for c in cases.ALL_CASES]), "xi_inf": xi,
                "status": np.where(np.isfinite(xi), "ok", "no_value"), "steps": np.zeros(xi.size, np.int64)}, {
                    "closed_form": "sweep.physics.xi_inf_m2zero on the m2 = 0 cases of tests/cases.py"}
    if name.startswith("default_"):
        call, inputs = make_workload(name, quick)
        ds = call()
        return {"xi_inf": ds["xi_inf"].values.ravel(), "status": status_names(ds),
                "steps": ds["steps"].values.ravel()}, inputs
    cases = load_cases(cases_file)
    kwargs = {"cases_auto": {"observables": ("xi_inf",)},
              "cases_quasistatic": {"observables": ("xi_inf",), "model": "quasistatic"},
              "cases_time_resolved": {"observables": ("xi_inf", "t50", "t90"), "model": "quasistatic"}}[name]
    points = []
    for case in cases.ALL_CASES:
        c = cases.case_params(case)
        params = sweep.FrictionParams(A=c["A"], m1=c["m1"], m2=c["m2"], D0=c["D0"])
        points.append(sweep.solve_point(params, K_over_M=c["K_over_M"], V=c["V"], rtol=RTOL, **kwargs))
    out = {"case": np.array([c.name for c in cases.ALL_CASES]),
           "status": np.concatenate([status_names(p) for p in points])}
    for var in ("xi_inf", "steps", "t50", "t90"):
        if var in points[0]:
            out[var] = np.array([p[var].values for p in points])
    return out, {"solve_point": describe(kwargs), "rtol": RTOL}


def load_cases(path: Path):
    """tests/cases.py of the tree this script runs from, imported by path."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("sweep_compare_cases", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def worker(spec: dict) -> dict:
    """One measurement in this process (PYTHONPATH = the tree): kind "time", "compile" or "numbers"."""
    import numba

    t0 = time.perf_counter()
    import sweep

    import_s = time.perf_counter() - t0
    where = Path(sweep.__file__).resolve()
    if Path(spec["tree"]).resolve() not in where.parents:
        raise RuntimeError(f"import sweep found {where}, not the tree {spec['tree']}")
    out = {"sweep_file": str(where), "sweep_version": getattr(sweep, "__version__", None),
           "numba_cache_dir": numba.config.CACHE_DIR, "numba_threads": numba.get_num_threads()}
    if spec["kind"] == "numbers":
        arrays, inputs = {}, {}
        for s in spec.get("sets", NUMBER_SETS):
            values, inputs[s] = number_set(s, spec["quick"], Path(spec["cases_file"]))
            arrays.update({f"{s}__{k}": v for k, v in values.items()})
        np.savez(spec["npz"], **arrays)
        return {**out, "inputs": inputs}
    call, inputs = make_workload(spec["workload"], spec["quick"])
    walls, cpus = [], []
    for _ in range(2 if spec["kind"] == "compile" else 1 + spec["timed_calls"]):
        t, c = time.perf_counter(), time.process_time()
        call()
        walls.append(time.perf_counter() - t)
        cpus.append(time.process_time() - c)
    out["inputs"] = inputs
    if spec["kind"] == "compile":
        files = sum(len(f) for _, _, f in os.walk(numba.config.CACHE_DIR))
        return {**out, "import_s": import_s, "first_call_s": walls[0], "second_call_s": walls[1],
                "compile_s": walls[0] - walls[1], "cache_files_written": files}
    try:
        layer = numba.threading_layer()
    except ValueError:  # no parallel kernel ran
        layer = None
    return {**out, "warmup_s": walls[0], "timed_s": walls[1:], "timed_cpu_s": cpus[1:], "threading_layer": layer}


# ================================================================================ parent side (no sweep import)

@dataclasses.dataclass
class Tree:
    """A sweep source tree to measure: its label, root, commit, and the numba cache of its timing workers."""
    label: str
    root: Path
    commit: str
    dirty: bool
    timing_cache: Path
    checked_out: bool = False
    """A REV checked out by :func:`checkout` (its worktree is removed at the end)."""


def git(*args: str, cwd: Path = ROOT) -> str:
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True, text=True).stdout.strip()


@contextlib.contextmanager
def checkout(label: str, rev: str) -> Iterator[Tree]:
    """REV checked out (detached worktree) at a fixed temp path named by its commit, with every file's mtime set to
    the commit time, so that numba's cache (keyed by source path and mtime) is found again on the next run;
    removed on exit. If another run holds that path, a fresh temp path is used (its cache starts empty)."""
    sha = git("rev-parse", "--verify", f"{rev}^{{commit}}")
    CACHE_ROOT.mkdir(parents=True, exist_ok=True)
    lock = open(CACHE_ROOT / f"tree-{sha}.lock", "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        path = CACHE_ROOT / f"tree-{sha}"
        if path.exists():  # left by an interrupted run of ours
            subprocess.run(["git", "worktree", "remove", "--force", str(path)], cwd=ROOT, capture_output=True)
            shutil.rmtree(path, ignore_errors=True)
    except BlockingIOError:  # another run compares the same commit
        path = Path(tempfile.mkdtemp(prefix=f"sweep-compare-{sha[:10]}-")) / "tree"
    git("worktree", "add", "--detach", str(path), sha)
    try:
        stamp = int(git("show", "-s", "--format=%ct", sha))
        for f in path.rglob("*"):
            if f.is_file():
                os.utime(f, (stamp, stamp))
        # byte-compile now, as a used tree is: else the first import in a worker pays for it
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(path / "sweep")], check=True)
        yield Tree(label, path, sha, False, CACHE_ROOT / f"numba-{sha}-{hashlib.sha1(bytes(path)).hexdigest()[:10]}",
                   checked_out=True)
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(path)], cwd=ROOT, capture_output=True)
        if path.parent != CACHE_ROOT:
            shutil.rmtree(path.parent, ignore_errors=True)
        lock.close()


def working_tree(label: str, root: Path) -> Tree:
    """A directory as it is (uncommitted changes under sweep/ recorded as dirty)."""
    root = root.resolve()
    commit = git("rev-parse", "HEAD", cwd=root)
    dirty = bool(git("status", "--porcelain", "sweep", cwd=root))
    # keyed by the sources too: numba checks only the timestamp of the file that defines each cached kernel, so a
    # cache kept across edits of a module that a cached kernel calls into would run the old code
    digest = hashlib.sha1(bytes(root))
    for source in sorted((root / "sweep").rglob("*.py")):
        digest.update(source.read_bytes())
    return Tree(label, root, commit, dirty, CACHE_ROOT / f"numba-tree-{digest.hexdigest()[:10]}")


class Runner:
    """Starts the worker subprocesses and keeps the exact command of each kind of measurement."""

    def __init__(self, quick: bool, timed_calls: int, scratch: Path):
        self.quick, self.timed_calls, self.scratch = quick, timed_calls, scratch
        self.commands: dict[str, str] = {}
        self.count = 0

    def run(self, tree: Tree, kind: str, key: str, cache: Path, **spec: object) -> dict:
        """One worker: ``kind`` in tree, NUMBA_CACHE_DIR=cache; returns its result dict."""
        self.count += 1
        result = self.scratch / f"result-{self.count}.json"
        spec = {"kind": kind, "tree": str(tree.root), "quick": self.quick, "timed_calls": self.timed_calls, **spec}
        env = {"PYTHONPATH": str(tree.root), "NUMBA_CACHE_DIR": str(cache)}
        argv = [sys.executable, str(Path(__file__).resolve()), "--worker", json.dumps(spec), "--result", str(result)]
        self.commands[f"{kind}:{key}:{tree.label}"] = " ".join(
            [*(f"{k}={shlex.quote(v)}" for k, v in env.items()), *map(shlex.quote, argv)])
        proc = subprocess.run(argv, env={**os.environ, **env}, cwd=tree.root, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"worker {kind} {key} in {tree.label} failed:\n{proc.stderr[-3000:]}")
        return json.loads(result.read_text())


def same_inputs(old: dict, new: dict) -> dict:
    """Which inputs (top-level fields of the scene or call) the two trees ran differently ("same" judges only the
    fields both have: a field one tree added, at its default, is listed under only_old / only_new)."""
    differ = sorted(k for k in old.keys() & new.keys() if old[k] != new[k])
    only_old, only_new = sorted(old.keys() - new.keys()), sorted(new.keys() - old.keys())
    return {"same": not differ, "differ": differ, "only_old": only_old, "only_new": only_new}


def pop_inputs(runs: dict[str, list[dict]]) -> dict:
    """Remove the inputs from every run (they are the same run after run) and compare old's with new's."""
    inputs = {label: [r.pop("inputs") for r in rs][0] for label, rs in runs.items()}
    return same_inputs(inputs["old"], inputs["new"])


def alternate(trees: list[Tree], repeats: int) -> Iterator[Tree]:
    """old, new, old, new, ... (``repeats`` rounds)."""
    for _ in range(repeats):
        yield from trees


def measure_compile(runner: Runner, trees: list[Tree], families: dict[str, tuple[str, bool]], repeats: int) -> dict:
    """First-call times from an empty numba cache, per family (``families``: family -> (workload, quick size)) and
    tree: ``repeats`` runs per tree, trees alternated, each in a new empty cache; per tree the run with the smallest
    compile_s is kept (all under runs)."""
    out = {}
    for family, (workload, small) in families.items():
        rows = {"workload": workload, "quick_size": small or runner.quick, "loadavg_before": loadavg(),
                "runs": {t.label: [] for t in trees}}
        for tree in alternate(trees, repeats):
            cache = Path(tempfile.mkdtemp(prefix="numba-empty-", dir=runner.scratch))
            run = runner.run(tree, "compile", family, cache, workload=workload, quick=small or runner.quick)
            rows["runs"][tree.label].append(run)
            print(f"  compile {family:20s} {tree.label}: import {run['import_s']:.2f} s, compile "
                  f"{run['compile_s']:.1f} s", flush=True)
        rows["loadavg_after"] = loadavg()
        rows["inputs"] = pop_inputs(rows["runs"])
        for label, runs in rows["runs"].items():
            rows[label] = min(runs, key=lambda r: r["compile_s"])
        rows["ratio_compile_new_over_old"] = ratio(rows["new"]["compile_s"], rows["old"]["compile_s"])
        out[family] = rows
    return out


def ratio(new: float, old: float) -> float | None:
    """new / old, None where old is not positive (a compile_s of ~0: nothing compiled)."""
    return new / old if old > 0 else None


def measure_speed(runner: Runner, trees: list[Tree], repeats: int, workloads: dict[str, str] = WORKLOADS,
                  only: list[str] | None = None) -> dict:
    """Per workload (``only``: those named): alternate old/new ``repeats`` times, min wall per tree, ratio new/old
    and PASS/MISS."""
    out = {}
    for name, what in workloads.items():
        if only and name not in only:
            continue
        row = {"what": what, "loadavg_before": loadavg(), "runs": {t.label: [] for t in trees}}
        for tree in alternate(trees, repeats):
            row["runs"][tree.label].append(runner.run(tree, "time", name, tree.timing_cache, workload=name))
        row["loadavg_after"] = loadavg()
        row["inputs"] = pop_inputs(row["runs"])
        for label, runs in row["runs"].items():
            row[f"{label}_min_s"] = min(t for r in runs for t in r["timed_s"])
            row[f"{label}_min_cpu_s"] = min(t for r in runs for t in r["timed_cpu_s"])
        row["ratio_new_over_old"] = row["new_min_s"] / row["old_min_s"]
        row["ratio_cpu_new_over_old"] = row["new_min_cpu_s"] / row["old_min_cpu_s"]
        row["result"] = "PASS" if row["ratio_new_over_old"] <= SPEED_LIMIT else "MISS"
        print(f"  {name:20s} old {row['old_min_s']:.3f} s  new {row['new_min_s']:.3f} s  "
              f"x{row['ratio_new_over_old']:.3f} {row['result']}", flush=True)
        out[name] = row
    return out


def relative_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a - b| / max(|a|, |b|) per element; 0 where equal (NaN == NaN), inf where only one is NaN."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(a - b) / np.maximum(np.abs(a), np.abs(b))
    return np.where(same, 0.0, np.where(np.isnan(rel), np.inf, rel))


def compare_numbers(old: Path, new: Path, sets: tuple[str, ...] = NUMBER_SETS) -> dict:
    """Per number set: max relative difference of every float variable, statuses and steps that differ."""
    a, b = np.load(old), np.load(new)
    out = {}
    for s in sets:
        row = {"points": int(a[f"{s}__xi_inf"].size)}
        for var in ("xi_inf", "t50", "t90"):
            if f"{s}__{var}" in a.files:
                rel = relative_difference(a[f"{s}__{var}"], b[f"{s}__{var}"])
                row[f"max_rel_diff_{var}"] = float(rel.max())
                row[f"points_differing_{var}"] = int(np.count_nonzero(rel))
        row["status_differs"] = int(np.count_nonzero(a[f"{s}__status"] != b[f"{s}__status"]))
        row["steps_differ"] = int(np.count_nonzero(a[f"{s}__steps"] != b[f"{s}__steps"]))
        worst = max(v for k, v in row.items() if k.startswith("max_rel_diff_"))
        row["result"] = "PASS" if worst <= NUMBERS_LIMIT and row["status_differs"] == 0 else "MISS"
        out[s] = row
    return out


def measure_numbers(runner: Runner, trees: list[Tree], sets: tuple[str, ...] = NUMBER_SETS) -> dict:
    """Each tree writes its arrays to an .npz in the scratch dir; then compared old vs new."""
    paths, inputs = {}, {}
    for tree in trees:
        paths[tree.label] = runner.scratch / f"numbers-{tree.label}.npz"
        inputs[tree.label] = runner.run(tree, "numbers", "all", tree.timing_cache, npz=str(paths[tree.label]),
                                        cases_file=str(HERE.parent / "tests" / "cases.py"), sets=list(sets))["inputs"]
    out = compare_numbers(paths["old"], paths["new"], sets)
    for name, row in out.items():
        row["inputs"] = same_inputs(inputs["old"][name], inputs["new"][name])
    return out


def machine() -> dict:
    """CPU, CPUs, platform, versions (numpy and numba are the parent's: the workers run the same interpreter)."""
    import numba

    return {"cpu": cpu_model(), "logical_cpus": os.cpu_count(), "usable_cpus": usable_cpus(),
            "platform": platform.platform(), "python": platform.python_version(), "python_executable": sys.executable,
            "numpy": np.__version__, "numba": numba.__version__,
            "NUMBA_NUM_THREADS": os.environ.get("NUMBA_NUM_THREADS"),
            "numba_default_threads": numba.config.NUMBA_NUM_THREADS}


def fmt(x: float | None, f: str = "{:.2f}", width: int = 0) -> str:
    return f"{'-':>{width}s}" if x is None else f.format(x)


def print_summary(r: dict) -> None:
    """One screen: trees, compile times, speed ratios, numbers."""
    t = r["trees"]
    mode = "  (SELF-TEST)" if r.get("self_test") else "  (QUICK)" if r["quick"] else ""
    print(f"\n== compare_commits {r['date']}{mode}  {r['machine']['cpu']}, "
          f"numba {r['machine']['numba']}, numpy {r['machine']['numpy']}")
    for label in ("old", "new"):
        print(f"{label}: {t[label]['commit'][:10]}{' (dirty)' if t[label]['dirty'] else ''}  {t[label]['root']}")
    print(f"\nfirst call from an empty numba cache [s]   {'old':>8s}{'new':>8s}{'new/old':>9s}")
    for family, row in r["compile"].items():
        print(f"  {family + ' compile':40s}{row['old']['compile_s']:8.1f}{row['new']['compile_s']:8.1f}"
              f"{fmt(row['ratio_compile_new_over_old'], '{:9.3f}', 9)}")
        if family == next(iter(r["compile"])):
            print(f"  {'import sweep':40s}{row['old']['import_s']:8.2f}{row['new']['import_s']:8.2f}"
                  f"{row['new']['import_s'] / row['old']['import_s']:9.3f}")
    print(f"\nwall time, min of {r['repeats']} alternated runs [s]    {'old':>8s}{'new':>8s}{'new/old':>9s}"
          f"{'':7s}{'cpu new/old':>12s}")
    for name, row in r["speed"].items():
        print(f"  {name:40s}{row['old_min_s']:8.3f}{row['new_min_s']:8.3f}{row['ratio_new_over_old']:9.3f}  "
              f"{row['result']}{row['ratio_cpu_new_over_old']:12.3f}   load {row['loadavg_before'][0]:.1f}->"
              f"{row['loadavg_after'][0]:.1f}")
    print(f"\nnumbers at rtol 1e-6                     {'points':>7s}{'max rel diff':>14s}{'status':>8s}{'steps':>7s}")
    for name, row in r["numbers"].items():
        worst = max(v for k, v in row.items() if k.startswith("max_rel_diff_"))
        print(f"  {name:38s}{row['points']:7d}{worst:14.2e}{row['status_differs']:8d}{row['steps_differ']:7d}  "
              f"{row['result']}")
    rows = [(f"{part}/{name}", row["inputs"]) for part in ("compile", "numbers", "speed")
            for name, row in r[part].items()]
    for where, inputs in rows:
        if not inputs["same"]:
            print(f"WARNING: {where}: the trees ran different values of {inputs['differ']}")
    only = {f"{k}: {v}" for _, inputs in rows for k in ("only_old", "only_new") for v in inputs[k]}
    if only:
        print(f"note: input fields of one tree only (left at their defaults): {', '.join(sorted(only))}")
    print(f"\nverdict: speed {r['verdict']['speed']}, numbers {r['verdict']['numbers']} "
          f"(compile new/old: {', '.join(f'{k} {fmt(v)}' for k, v in r['verdict']['compile_ratio'].items())})")
    if r.get("self_test"):
        st = r["self_test"]
        print(f"self-test: {'PASS' if st['passed'] else 'FAIL'} "
              + ", ".join(f"{k} {'ok' if v else 'FAILED'}" for k, v in st["checks"].items()))


def self_test_checks(compile_: dict, numbers: dict, trees: list[Tree]) -> dict:
    """--self-test's checks: each compile worker wrote its kernel into its empty cache; both trees' numbers equal;
    a checked-out REV's worktree removed afterwards."""
    checks = {f"compile_wrote_cache_{label}": all(r["cache_files_written"] > 0 for r in row["runs"][label])
              for row in compile_.values() for label in ("old", "new")}
    checks["numbers_equal"] = all(row["result"] == "PASS" for row in numbers.values())
    checks["worktrees_removed"] = all(not t.root.exists() for t in trees if t.checked_out)
    return {"checks": checks, "passed": all(checks.values())}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--old", default=None, help=f"old revision (default {DEFAULT_OLD}; HEAD with --self-test)")
    new = ap.add_mutually_exclusive_group()
    new.add_argument("--new", help="new revision (checked out in a temporary worktree)")
    new.add_argument("--new-tree", type=Path, default=ROOT, help="new tree as it is (default: this script's tree)")
    ap.add_argument("--repeats", type=int, default=None,
                    help="alternated timed runs per tree and workload (default 3; 1 with --quick)")
    ap.add_argument("--compile-repeats", type=int, default=1,
                    help="alternated first-call runs per tree and compile family (default 1; a compile takes 10-60 s)")
    ap.add_argument("--timed-calls", type=int, default=3,
                    help="timed calls per run after its warm-up (default 3; the smallest counts): a single call per "
                         "process left dp5 at 1.077 on one run and 1.03 on the next")
    ap.add_argument("--only", type=lambda v: v.split(","), default=None,
                    help="comma-separated speed workloads to time again, skipping compile times and numbers "
                         f"(known: {', '.join(WORKLOADS)})")
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--quick", action="store_true", help="tiny grids, 1 repeat, only the driven compile family")
    mode.add_argument("--self-test", action="store_true",
                      help="the machinery only, on a workload that compiles one small kernel (seconds; a smoke run)")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--result", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        args.result.write_text(json.dumps(worker(json.loads(args.worker))))
        return 0
    unknown = sorted(set(args.only or ()) - set(WORKLOADS))
    if unknown:
        ap.error(f"--only: unknown workload(s) {unknown}; known: {', '.join(WORKLOADS)}")
    if args.only and args.self_test:
        ap.error("--only times real workloads again; --self-test runs none")
    self_test = args.self_test
    old_rev = args.old or ("HEAD" if self_test else DEFAULT_OLD)
    repeats = args.repeats or (1 if args.quick or self_test else 3)
    if self_test:
        families, sets, workloads = SELF_TEST_COMPILE_FAMILIES, SELF_TEST_NUMBER_SETS, SELF_TEST_WORKLOADS
    else:
        families = {f: COMPILE_FAMILIES[f] for f in (QUICK_COMPILE_FAMILIES if args.quick else COMPILE_FAMILIES)}
        sets, workloads = NUMBER_SETS, WORKLOADS
    t_start = time.perf_counter()
    with contextlib.ExitStack() as stack:
        scratch = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="sweep-compare-")))
        old = stack.enter_context(checkout("old", old_rev))
        new = stack.enter_context(checkout("new", args.new)) if args.new else working_tree("new", args.new_tree)
        trees = [old, new]
        if self_test:  # no cache kept between runs: the timing caches in the scratch directory
            trees = [dataclasses.replace(t, timing_cache=scratch / f"numba-timing-{t.label}") for t in trees]
        runner = Runner(args.quick or self_test, timed_calls=1 if args.quick or self_test else args.timed_calls,
                        scratch=scratch)
        print(f"old {old.commit[:10]} ({old.root}), new {new.commit[:10]} ({new.root}); repeats {repeats}"
              + ("; SELF-TEST" if self_test else ""), flush=True)
        compile_, numbers = {}, {}
        if not args.only:
            print("[1/3] first-call compile time, empty numba caches", flush=True)
            compile_ = measure_compile(runner, trees, families, args.compile_repeats)
            print("[2/3] numbers at rtol 1e-6", flush=True)
            numbers = measure_numbers(runner, trees, sets)
        print("[3/3] speed, old and new alternated", flush=True)
        speed = measure_speed(runner, trees, repeats, workloads, args.only)
    result = {
        "benchmark": "benchmarks/compare_commits.py" + (
            " --self-test (the script's machinery on a tiny workload: a check, not a result)" if self_test else
            " --quick (tiny grids: a check of the script, not a result)" if args.quick else ""),
        "command": shlex.join([sys.executable, *sys.argv]), "quick": args.quick,
        "self_test": self_test_checks(compile_, numbers, trees) if self_test else None,
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"), "machine": machine(), "repeats": repeats,
        "compile_repeats": args.compile_repeats,
        "trees": {t.label: {"root": str(t.root), "commit": t.commit, "dirty": t.dirty,
                            "timing_numba_cache": str(t.timing_cache)} for t in trees},
        "limits": {"speed_ratio_max": SPEED_LIMIT, "numbers_max_rel_diff": NUMBERS_LIMIT, "rtol": RTOL},
        "compile": compile_, "numbers": numbers, "speed": speed,
        "verdict": {"speed": "PASS" if all(r["result"] == "PASS" for r in speed.values()) else "MISS",
                    "numbers": ("not measured (--only)" if not numbers else
                                "PASS" if all(r["result"] == "PASS" for r in numbers.values()) else "MISS"),
                    "compile_ratio": {k: r["ratio_compile_new_over_old"] for k, r in compile_.items()}},
        "commands": runner.commands, "benchmark_wall_s": time.perf_counter() - t_start,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print_summary(result)
    print(f"\nwrote {args.out} ({result['benchmark_wall_s']:.0f} s)")
    return 0 if not self_test or result["self_test"]["passed"] else 1


if __name__ == "__main__":
    sys.exit(main())
