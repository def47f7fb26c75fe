"""The plan of a scene: what to model and how to step ("model only what the scene requires")."""

from __future__ import annotations

from .._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "CHUNK_POINTS": "plan",
        "Plan": "plan",
        "PointParams": "plan",
        "chunk_size_for": "plan",
        "make_plan": "plan",
        "choose_method": "plan",
        "line_uses_inertia": "plan",
        "samples_in_lanes": "plan",
        "stop_plan_for_points": "plan",
        "stiff_points": "plan",
    },
    fallback="plan",
)
__all__ = [
    "CHUNK_POINTS",
    "Plan",
    "PointParams",
    "choose_method",
    "chunk_size_for",
    "line_uses_inertia",
    "make_plan",
    "samples_in_lanes",
    "stiff_points",
    "stop_plan_for_points",
]
