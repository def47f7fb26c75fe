"""Exceptions raised by the public API."""

__all__ = ["InputError"]


class InputError(ValueError):
    """Invalid user input, raised before any compilation or computation; the message names the field."""
