"""The documentation: docs/ builds offline with Sphinx (markdown through myst-parser, the API reference from the
docstrings) without a single warning; the README is a front page; measured numbers come from the results files.
"""

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
USER_DOCS = [README, *(ROOT / "docs" / name for name in ("index.md", "user-guide.md", "cli.md", "physics.md",
                                                        "design.md", "fit.md", "hopf-type.md", "gallery/index.md"))]
"""Pages for users: no dates, commit hashes or load averages (docs/benchmarks.md is where those belong)."""

DATE = re.compile(r"\b20\d\d-\d\d-\d\d\b")
COMMIT = re.compile(r"\b(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}\b")
"""A git hash: 7 to 40 hex digits with at least one letter and one digit (a DOI's 1996113 is none)."""
LOAD = re.compile(r"\bload(avg|[ _]average|\s*~?\s*\d)", re.IGNORECASE)


@pytest.mark.slow
def test_whole_documentation_builds_without_warnings(tmp_path):
    pytest.importorskip("sphinx", reason="the [docs] (and [test]) extra installs sphinx")
    pytest.importorskip("myst_parser", reason="the [docs] (and [test]) extra installs myst-parser")
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                           str(ROOT / "docs"), str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    index = (tmp_path / "index.html").read_text()
    for page in ("user-guide", "cli", "physics", "design", "fit", "benchmarks", "api/index", "gallery/index"):
        assert f'href="{page}.html' in index, page
        assert (tmp_path / f"{page}.html").is_file(), page
    api = (tmp_path / "api" / "index.html").read_text()
    for name in ("run_sweep", "solve_point", "Scene", "locate_hopf", "FrictionParams", "make_plan", "Plan",
                 "Status", "local_cluster", "InputError", "OutputError", "PlausibilityWarning", "read_sweep_file",
                 "Curve", "RelaxedSlips"):
        assert re.search(rf'id="sweep\.([\w.]+\.)?{name}"', api), name  # documented under a sweep.<...> name
    for name in ("sweep.open", "sweep.save", "sweep.fit.fit", "sweep.presets"):
        assert f'id="{name}"' in api, name


def test_measured_numbers_come_from_the_results_files():
    """docs/benchmarks.md and every marked span of the README and docs/ are what benchmarks/results/*.json say."""
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "readme_numbers.py"), "--check"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "<!-- n:" in README.read_text()  # the README's speed sentence is rendered, not typed


def test_readme_is_a_front_page():
    text = README.read_text()
    assert len(text.splitlines()) <= 150
    for command in ("python -m pip install . && sweep run", 'python -m pip install ".[test]" && python -m pytest'):
        assert command in text, command
    assert 'python -m pip install ".[test]" && python -m pytest' in (ROOT / ".ci" / "run").read_text()
    for link in re.findall(r"\]\(((?:docs|benchmarks)/[^)#]+)", text):
        assert (ROOT / link).exists(), link


@pytest.mark.parametrize("page", USER_DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_user_docs_hold_no_dates_commits_or_load_averages(page):
    text = page.read_text()
    for what, pattern in (("date", DATE), ("commit hash", COMMIT), ("load average", LOAD)):
        found = [m.group(0) for m in pattern.finditer(text)]
        assert not found, f"{page.name}: {what} {found[:3]}: measured figures go through docs/benchmarks.md"


def test_patterns_catch_what_they_are_for():
    assert DATE.search("measured 2026-11-27") and COMMIT.search("at d589fbd") and LOAD.search("load ~0.9")
    assert LOAD.search("load 0.6-1.3") and LOAD.search("loadavg")
    assert not COMMIT.search("doi:10.1051/jp1:1996113") and not LOAD.search("load them from numba's cache")
