"""The figures of Baumberger & Gauthier (1996) reproduced from the presets (``sweep reproduce``)."""

from .registry import FIGURES, Figure, Written, reproduce

__all__ = ["FIGURES", "Figure", "Written", "reproduce"]
