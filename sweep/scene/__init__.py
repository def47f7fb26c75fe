"""What to study: the Scene, its TOML form, friction parameters, presets and plausibility checks."""

from __future__ import annotations

from .._lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "Scene": "scene",
        "OBSERVABLES": "scene",
        "DRIVEN_OBSERVABLES": "scene",
        "PROTOCOLS": "scene",
        "DEFAULT_ATOL": "scene",
        "EXTRA_AXES": "scene",
        "AXIS_UNITS": "scene",
        "default_scene": "scene",
        "load_scene": "scene",
        "FrictionParams": "params",
        "provenance": "presets",
        "PlausibilityWarning": "plausibility",
    },
    fallback="scene",
)
__all__ = [
    "AXIS_UNITS",
    "DEFAULT_ATOL",
    "DRIVEN_OBSERVABLES",
    "EXTRA_AXES",
    "FrictionParams",
    "OBSERVABLES",
    "PROTOCOLS",
    "PlausibilityWarning",
    "Scene",
    "default_scene",
    "load_scene",
    "provenance",
]
