"""The ``sweep`` logger: what the package says while it works (compiling kernels, progress notes), through the
standard :mod:`logging` module.

The package only logs; it configures nothing (a :class:`logging.NullHandler` keeps it silent by default, as a
library should). From Python, ``logging.basicConfig(level="INFO")`` shows the messages; the command line
configures the logger with :func:`configure` (``-q``: warnings and errors only, ``--verbose``: debug details).
"""

from __future__ import annotations

import logging
import sys

__all__ = ["LOGGER", "configure"]

LOGGER = logging.getLogger("sweep")
LOGGER.addHandler(logging.NullHandler())


def configure(verbose: bool = False, quiet: bool = False, stream=None) -> None:
    """Send the ``sweep`` logger's messages to ``stream`` (default stderr) as ``sweep: message`` lines, at level
    DEBUG (``verbose``), WARNING (``quiet``) or INFO; replaces a handler set by an earlier call."""
    for handler in list(LOGGER.handlers):
        if getattr(handler, "_sweep_cli", False):
            LOGGER.removeHandler(handler)
    handler = logging.StreamHandler(stream or sys.stderr)
    handler.setFormatter(logging.Formatter("sweep: %(message)s"))
    handler._sweep_cli = True
    LOGGER.addHandler(handler)
    LOGGER.setLevel(logging.DEBUG if verbose else logging.WARNING if quiet else logging.INFO)
    LOGGER.propagate = False
