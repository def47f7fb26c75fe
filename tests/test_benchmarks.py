"""Smoke run of every benchmark script in benchmarks/ (issue 17: "every benchmark script runs at HEAD").

Each script runs in a subprocess with its smallest setting (--quick; compare_commits.py: --self-test, since its
--quick compiles every kernel into two fresh caches, ~6 min), --no-png where it draws, and --out in a temporary
directory; the test asserts exit code 0, the JSON's top-level keys, and that benchmarks/results/ and README.md
were left alone. The numbers of a smoke run mean nothing: a script that runs says only that it still works with the
package as it is. Optional peers of peers.py (jax/diffrax, numbalsoda: the [bench] extra) are used where
installed; the script must then say which were missing, which one test checks by hiding them. The whole file takes
~2-3 min on the 2-core development machine with the kernels in numba's cache (benchmarks/README.md).
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"
TIMEOUT_S = 600

DRAWS = {"end_to_end", "error_coverage", "fit", "hopf", "models", "out_of_core", "peers", "scaling", "throughput",
         "work_precision"}
"""Scripts that draw a PNG beside their JSON (run with --no-png)."""

SMOKE_FLAG = {"compare_commits": "--self-test"}
"""The smoke-run flag of a script whose --quick is not seconds (default --quick)."""

KEYS = {
    "axes": {"benchmark", "quick", "machine", "settings", "grids", "throughput_ratios", "target"},
    "auto_cost": {"benchmark", "quick", "machine", "rows", "two_threads_over_one", "machine_two_threads_over_one",
                  "targets"},
    "calibrate_rk4": {"benchmark", "points", "reference_failures", "rows", "plan_constants", "versions"},
    "calibrate_stiff": {"what", "quick", "points", "reference_failures", "rows"},
    "cold_start": {"benchmark", "quick", "machine", "scene", "command", "trees", "compile_by_function", "targets"},
    "compare_commits": {"benchmark", "self_test", "machine", "trees", "compile", "numbers", "speed", "verdict",
                        "commands"},
    "driven_scaling": {"benchmark", "quick", "machine", "settings", "figures", "date"},
    "driven_lanes": {"benchmark", "quick", "machine", "trees", "figures", "numbers", "targets"},
    "end_to_end": {"benchmark", "quick", "machine", "scene", "runs", "best", "ratio_total_over_kernel", "target"},
    "error_coverage": {"benchmark", "quick", "machine", "rows"},
    "fit": {"benchmark", "machine", "settings", "one_curve", "many_curves", "scipy", "ratio_per_curve", "side_by_side"},
    "fit_records": {"benchmark", "quick", "machine", "one_record_warm_s", "hundred_records_s",
                    "hundred_records_own_times_s", "scipy_least_squares_s", "speedup_vs_scipy", "targets"},
    "history": {"benchmark", "quick", "machine", "shs_point", "forward", "grid", "targets"},
    "history_axes": {"benchmark", "quick", "machine", "grids", "ratio_hold_axis_over_fixed_wall_per_point",
                     "ratio_ratio_axis_over_fixed_wall_per_point"},
    "hopf": {"benchmark", "quick", "machine", "line", "inertial_line", "inertial_driven_deep_stick_slip",
             "driven_grid", "driven_grid_auto"},
    "models": {"benchmark", "quick", "machine", "cost", "accuracy_inertia_scene_model_tol_1e-2",
               "model_tol_sweep_inertia_scene"},
    "out_of_core": {"benchmark", "quick", "machine", "runs"},
    "peers": {"benchmark", "machine", "versions", "peers_status", "tools_missing", "settings", "scenes"},
    "readme_numbers": {"numbers", "readme_spans", "readme_stale_keys", "readme_up_to_date"},
    "records_read": {"benchmark", "quick", "machine", "files", "targets"},
    "scaling": {"benchmark", "quick", "tools_missing", "machine", "threads", "dask", "memory", "memory_trajectories",
                "targets"},
    "structure": {"import_cycle", "modules", "longest_functions", "largest_positional_lists"},
    "throughput": {"benchmark", "machine", "versions", "scene", "engine", "scipy", "numpy_rk4", "cold_start",
                   "estimate", "targets"},
    "work_precision": {"quick", "machine", "problems", "reference", "engine", "scipy", "summary"},
}
"""Every script of benchmarks/ and the top-level keys its JSON must have."""

OPTIONAL_PEERS = {"numbalsoda": ("numbalsoda",), "diffrax": ("jax", "diffrax")}
"""peers.py's optional peers and the modules each needs."""


def scripts() -> list[str]:
    return sorted(p.stem for p in BENCH.glob("*.py") if not p.name.startswith("_"))


def fingerprint() -> dict[str, str]:
    """sha256 of every file under benchmarks/results/ and of README.md: a smoke run must write neither."""
    files = [*sorted((BENCH / "results").rglob("*")), ROOT / "README.md"]
    return {str(f.relative_to(ROOT)): hashlib.sha256(f.read_bytes()).hexdigest() for f in files if f.is_file()}


def run_script(name: str, tmp: Path, *extra: str, pythonpath: tuple[str, ...] = ()) -> dict:
    """benchmarks/NAME.py with its smoke flag, --no-png where it draws, --out TMP/NAME.json: its JSON."""
    out = tmp / f"{name}.json"
    argv = [sys.executable, str(BENCH / f"{name}.py"), SMOKE_FLAG.get(name, "--quick"), "--out", str(out)]
    argv += ["--no-png"] if name in DRAWS else []
    env = {**os.environ, "MPLBACKEND": "Agg",
           "PYTHONPATH": os.pathsep.join([*pythonpath, str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    before = fingerprint()
    proc = subprocess.run([*argv, *extra], cwd=tmp, env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
    assert proc.returncode == 0, f"{' '.join(argv)} exited {proc.returncode}:\n{proc.stdout[-3000:]}\n" \
                                 f"{proc.stderr[-5000:]}"
    assert fingerprint() == before, f"{name}.py changed benchmarks/results/ or README.md"
    assert out.is_file(), f"{name}.py wrote no {out}"
    if name in DRAWS:
        assert not list(tmp.glob("*.png")), f"{name}.py drew a PNG despite --no-png"
    result = json.loads(out.read_text())
    assert KEYS[name] <= result.keys(), f"{name}.py's JSON lacks {sorted(KEYS[name] - result.keys())}"
    return result


def test_every_script_has_a_smoke_run():
    """A new script in benchmarks/ needs its entry in KEYS (and with it a smoke run below)."""
    assert scripts() == sorted(KEYS)


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in sorted(KEYS) if n != "peers"])
def test_script_runs(name, tmp_path):
    result = run_script(name, tmp_path)
    if name == "compare_commits":
        assert result["self_test"]["passed"], result["self_test"]
    if name == "scaling":
        has_dask = importlib.util.find_spec("distributed") is not None
        assert ("dask.distributed" in result["tools_missing"]) == (not has_dask)
        assert ("skipped" in result["dask"]) == (not has_dask)


def test_peers_with_the_peers_installed_here(tmp_path):
    """Every optional peer either ran (status ok, its rows in the JSON) or is recorded as missing, with the
    reason; one whose modules are not installed is never "ok"."""
    result = run_script("peers", tmp_path)
    tools = {t["family"] for scene in result["scenes"].values() for t in scene["tools"].values()}
    assert {"engine", "scipy"} <= tools
    for peer, modules in OPTIONAL_PEERS.items():
        status = result["peers_status"][peer]
        if status == "ok":
            assert peer in tools and peer not in result["tools_missing"]
        else:
            assert status.startswith("not installed") and result["tools_missing"][peer] == status
            assert peer not in tools
        if any(importlib.util.find_spec(m) is None for m in modules):
            assert status != "ok"


@pytest.mark.slow
def test_peers_driven_quasistatic(tmp_path):
    """peers.py --driven --quick on the quasi-static scene (~3 min): every optional peer ran or is missing with its
    reason; against the independent scipy Radau reference (resolved: its 1e-12 check within 1e-9 per cycle) the
    engine at its tightest rtol calls every regime of the subsample as the reference does, with growth rates within
    1e-8 per cycle and amplitudes within 1e-8."""
    result = run_script("peers", tmp_path, "--driven", "--models", "quasistatic")
    for peer in OPTIONAL_PEERS:
        assert result["peers_status"][peer] == "ok" or result["tools_missing"][peer].startswith("not installed")
    scene = result["scenes"]["quasistatic"]
    assert scene["reference"]["floor_growth_per_cycle"] < 1e-9
    tight = min(scene["tools"]["engine_1t"]["scopes"]["sub"], key=lambda r: r["rtol"])
    assert tight["regimes_differing_from_reference"] == 0
    assert tight["points_compared"] > 0 and tight["max_growth_err_per_cycle"] < 1e-8
    assert tight["max_amplitude_rel_err"] is None or tight["max_amplitude_rel_err"] < 1e-8


def test_peers_without_the_optional_peers(tmp_path):
    """jax and numbalsoda hidden (modules that raise ImportError ahead of them on sys.path): the run goes on with
    the engine and scipy and says which peers were missing."""
    hide = tmp_path / "hide"
    hide.mkdir()
    for module in ("jax", "numbalsoda"):
        (hide / f"{module}.py").write_text('raise ImportError("hidden by tests/test_benchmarks.py")\n')
    result = run_script("peers", tmp_path, "--no-corner", pythonpath=(str(hide),))
    assert set(result["tools_missing"]) == set(OPTIONAL_PEERS)
    assert all(result["peers_status"][p].startswith("not installed (ImportError") for p in OPTIONAL_PEERS)
    assert result["peers_status"]["scipy"] == "ok"
    tools = {t["family"] for t in result["scenes"]["default"]["tools"].values()}
    assert tools == {"engine", "scipy"}
