"""The API reference (docs/api, Sphinx autodoc) builds offline from the docstrings without a single warning."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_api_reference_builds_without_warnings(tmp_path):
    pytest.importorskip("sphinx", reason="the [docs] (and [test]) extra installs sphinx")
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                           str(ROOT / "docs" / "api"), str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    page = (tmp_path / "index.html").read_text()
    for name in ("run_sweep", "solve_point", "Scene", "locate_hopf", "PlausibilityWarning", "read_sweep_file"):
        assert name in page, name
