"""Steppers as data: validated Butcher tableaux (the compiled kernels use their coefficients)."""

from .tableau import RK4, ButcherTableau

__all__ = ["ButcherTableau", "RK4"]
