"""Exceptions raised by the public API."""

__all__ = ["InputError", "JournalWarning", "OutputError"]


class InputError(ValueError):
    """Invalid user input, raised before any compilation or computation; the message names the field."""


class OutputError(OSError):
    """A file of a run could not be written, or a journal chunk read back did not match what was written (disk
    full, permission denied, a folder in the way, a chunk damaged during the run). Raised during the run, after the
    checks made before any work (sweep/write/targets.py); the message is one line naming the file, the cause and what to
    do. The finished chunks stay in the journal, so that the same command with ``--resume`` (``resume=True``)
    finishes the run once the cause is fixed. ``errno`` is that of the failed operation, where there was one."""


class JournalWarning(UserWarning):
    """A file found in a run's journal was refused (damaged, of another run, a stray file) and moved aside, or the
    journal as a whole could not be attributed to the run: the run goes on and computes what was refused again
    (sweep/run/journal.py). The command line prints it as one line ``sweep: warning: ...``."""
