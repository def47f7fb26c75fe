"""pytest's configuration of the suite: the ``slow`` marker, and the support modules of this folder (references,
fault injection, the test protocol) importable from every test folder.

The folders mirror sweep/ (scene, integrate, plan, protocols, run, write, plot, analysis, fit); what spans the
package (structure, docs, the command line, benchmarks, the first hour of a new user) sits here. A quick local run
leaves out the tests marked slow (a compile in a fresh process, a dask cluster, a long reference integration):

    python -m pytest -m "not slow"
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))  # cases.py, faults.py, reference*.py, fit_reference.py, protocol_echo.py


def pytest_configure(config) -> None:
    config.addinivalue_line("markers", "slow: a test over ~4 s on two cores (a compile in a fresh process, a dask "
                                       "cluster, a long reference integration); -m 'not slow' leaves them out")
