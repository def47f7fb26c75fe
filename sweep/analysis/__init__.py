"""What the package derives from the model beyond a sweep: the Hopf line located by simulation and its type."""

from __future__ import annotations

from .._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {"locate_hopf": "hopf", "with_simulated_line": "hopf"})
__all__ = ["locate_hopf", "with_simulated_line"]
