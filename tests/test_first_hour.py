"""What a new user meets in the first hour (issue 16): packaging, one-line errors instead of tracebacks, warnings on
implausible units, logging and progress. The CLI is run through a subprocess: exit code and the one-line message."""

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import sweep

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
