"""Sphinx configuration of the whole documentation (docs/: markdown through myst-parser, and the API reference from
the docstrings), built offline:

    python -m pip install ".[docs]"
    python -m sphinx -W --keep-going -b html docs build/docs

(-W: a warning fails the build; tests/test_docs.py runs the same build.)
"""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the checkout's sweep, installed or not

from sweep import __version__  # noqa: E402

project = "sweep"
author = "sweep developers"
copyright = "sweep developers, MIT licence"
release = version = __version__
extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "**/*.txt", "**/*.toml"]
myst_heading_anchors = 4  # "page.md#a-heading" links, as on GitHub
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_default_options = {"undoc-members": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
html_theme = "alabaster"
html_static_path: list[str] = []
html_title = f"sweep {__version__}"
