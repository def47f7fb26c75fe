"""What the package derives from the model beyond a sweep: the Hopf line located by simulation, its type from the
first Lyapunov coefficient (lyapunov.py) and the bistable band on its inverted side (bistable.py)."""

from __future__ import annotations

from .._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {
    "locate_hopf": "hopf", "with_simulated_line": "hopf", "hopf_summary": "hopf", "lyapunov_line": "lyapunov",
    "bautin_points": "lyapunov", "bistable_band": "bistable"})
__all__ = ["bautin_points", "bistable_band", "hopf_summary", "locate_hopf", "lyapunov_line", "with_simulated_line"]
