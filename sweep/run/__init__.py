"""Running a scene: the public entry points, the chunk loop, its backends, the journal, the lock, progress and size."""

from __future__ import annotations

from .._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(__name__, {"run_sweep": "api", "solve_point": "api", "local_cluster": "backends"})
__all__ = ["local_cluster", "run_sweep", "solve_point"]
