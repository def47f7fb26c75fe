"""A user's code keeps working across the restructuring: every module path of the earlier layout imports, as the
module now at its new path (one object, not a copy), with a FutureWarning that names the new path; the names the
documentation showed resolve."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from sweep._moved import MOVED

DOCUMENTED = {  # old spelling -> the object it must be now
    "sweep.plausibility.PlausibilityWarning": "sweep.scene.plausibility.PlausibilityWarning",
    "sweep.io.save": "sweep.write.netcdf.save",
    "sweep.io.open_dataset": "sweep.write.netcdf.open_dataset",
    "sweep.files.read_sweep_file": "sweep.write.read.read_sweep_file",
    "sweep.files.file_kind": "sweep.write.read.file_kind",
    "sweep.hopf.locate_hopf": "sweep.analysis.hopf.locate_hopf",
    "sweep.backends.local_cluster": "sweep.run.backends.local_cluster",
    "sweep.params.FrictionParams": "sweep.scene.params.FrictionParams",
    "sweep.presets.provenance": "sweep.scene.presets.provenance",
    "sweep.solvers.METHODS": "sweep.integrate.solvers.METHODS",
    "sweep.compile_notice.announce_if_cold": "sweep.run.compile_notice.announce_if_cold",
}
UNMOVED = ["sweep.api.run_sweep", "sweep.api.solve_point", "sweep.scene.Scene", "sweep.scene.load_scene",
           "sweep.scene.default_scene", "sweep.plan.stiff_points", "sweep.plan.make_plan", "sweep.plot.plot_file",
           "sweep.physics.xi_inf_m2zero", "sweep.status.Status", "sweep.accuracy.TAIL_SHARE", "sweep.figures.reproduce",
           "sweep.errors.InputError", "sweep.errors.OutputError", "sweep.errors.JournalWarning", "sweep.log.LOGGER",
           "sweep.cli.main"]


def run(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-W", "error::FutureWarning", "-c", textwrap.dedent(code)],
                          capture_output=True, text=True, timeout=300)


def test_every_old_module_path_imports_the_new_module_with_a_warning_naming_it():
    proc = run(f"""
        import importlib, warnings
        for old, new in {dict(MOVED)!r}.items():
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                module = importlib.import_module(old)
            assert module is importlib.import_module(new), old
            assert module.__spec__.name == new, (old, module.__spec__.name)
            assert any(issubclass(w.category, FutureWarning) and new in str(w.message) for w in caught), old
        print("ok")
    """)
    assert proc.stdout.strip() == "ok", proc.stderr


def test_the_names_the_documentation_showed_resolve():
    proc = run(f"""
        import importlib, warnings
        warnings.simplefilter("ignore", FutureWarning)
        def resolve(path):
            module, _, name = path.rpartition(".")
            return getattr(importlib.import_module(module), name)
        for old, new in {DOCUMENTED!r}.items():
            assert resolve(old) is resolve(new), old
        for path in {UNMOVED!r}:
            resolve(path)
        print("ok")
    """)
    assert proc.stdout.strip() == "ok", proc.stderr


def test_the_new_paths_import_without_a_warning():
    """The package itself uses the new paths only (-W error::FutureWarning)."""
    proc = run("""
        import numpy as np
        import sweep
        from sweep import fit, plot, protocols
        scene = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=[1e4, 1e5], V=[1e-6, 1e-5])
        sweep.run_sweep(scene, progress=False)
        print("ok")
    """)
    assert proc.stdout.strip() == "ok", proc.stderr
