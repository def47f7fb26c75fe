"""The ``sweep`` logger: what the package says while it works (compiling kernels, progress notes), through the
standard :mod:`logging` module.

The package only logs; it configures nothing (a :class:`logging.NullHandler` keeps it silent by default, as a
library should). From Python, ``logging.basicConfig(level="INFO")`` shows the messages; the command line
configures the logger with :func:`configure` (``-q``: warnings and errors only, ``--verbose``: debug details).
"""

from __future__ import annotations

import contextlib
import logging
import sys
from collections.abc import Iterator

__all__ = ["LOGGER", "configure", "configured"]

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


@contextlib.contextmanager
def configured(verbose: bool = False, quiet: bool = False, stream=None) -> Iterator[None]:
    """:func:`configure` for the duration of a ``with`` block, then the logger's handlers, level and propagation as
    they were: ``sweep.cli.main`` called from Python (a notebook, a test) leaves no handler bound to a stream that
    may be closed later, and the caller's own logging set-up sees the package's messages again afterwards."""
    saved = (list(LOGGER.handlers), LOGGER.level, LOGGER.propagate)
    configure(verbose=verbose, quiet=quiet, stream=stream)
    try:
        yield
    finally:
        LOGGER.handlers[:] = saved[0]
        LOGGER.setLevel(saved[1])
        LOGGER.propagate = saved[2]
