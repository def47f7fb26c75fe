"""Steppers as data: validated Butcher tableaux (the compiled kernels use their coefficients)."""

from .tableau import DOP853, DP5, METHODS, RK4, ButcherTableau

__all__ = ["ButcherTableau", "DOP853", "DP5", "METHODS", "RK4"]
