"""Steppers as data: validated Butcher and Rosenbrock tableaux (the compiled kernels use their coefficients)."""

from collections.abc import Mapping
from types import MappingProxyType

from .rosenbrock import RODAS3, ROS4, RosenbrockTableau
from .tableau import DOP853, DP5, EXPLICIT_METHODS, RK4, ButcherTableau

METHODS: Mapping[str, ButcherTableau | RosenbrockTableau] = MappingProxyType({**EXPLICIT_METHODS, ROS4.name: ROS4})
"""Every built-in method by name: explicit Runge-Kutta (rk4, dp5, dop853) and linearly implicit (ros4)."""

__all__ = ["ButcherTableau", "DOP853", "DP5", "EXPLICIT_METHODS", "METHODS", "RK4", "RODAS3", "ROS4",
           "RosenbrockTableau"]
