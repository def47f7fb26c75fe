"""Sphinx configuration of the API reference, built from the docstrings, offline:

    python -m pip install ".[docs]"
    python -m sphinx -W --keep-going -b html docs/api build/docs-api

(-W: a warning fails the build; tests/test_docs.py runs the same build.)
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # the checkout's sweep, installed or not

from sweep import __version__  # noqa: E402

project = "sweep"
author = "sweep developers"
copyright = "sweep developers, MIT licence"
release = version = __version__
extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon"]
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_default_options = {"undoc-members": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
html_theme = "alabaster"
html_static_path: list[str] = []
exclude_patterns = ["_build"]
