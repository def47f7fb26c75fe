"""Right-hand sides of the model, one per protocol x model x state law, and the registry that names them.

A right-hand side (with its Jacobian and closed-form tails where it has them) knows nothing of steppers; the drivers
of :mod:`sweep.integrate` compose it with a stepper, a controller and what is recorded. :data:`REGISTRY` is the
single table of what exists: the scene accepts exactly these combinations (a second state law is one more entry
here and one function in :mod:`sweep.integrate.models.state_laws`).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

__all__ = ["REGISTRY", "Entry"]

Entry = tuple[str, str]
"""(module of the right-hand side, module of the driver that integrates it), both under sweep."""

REGISTRY: Mapping[tuple[str, str, str], Entry] = MappingProxyType({
    ("stop", "quasistatic", "aging"): ("integrate.models.stop", "integrate.stop_point / integrate.lanes"),
    ("stop", "quasistatic", "slip"): ("integrate.models.stop_slip", "integrate.stop_slip"),
    ("stop", "inertial", "aging"): ("integrate.models.stop_inertial", "integrate.stop_inertial"),
    ("driven", "quasistatic", "aging"): ("integrate.models.driven", "integrate.driven"),
    ("driven", "quasistatic", "slip"): ("integrate.models.driven", "integrate.driven"),
    ("driven", "inertial", "aging"): ("integrate.models.driven", "integrate.driven"),
})
"""(protocol, model, state law) -> (right-hand side, driver). model="auto" chooses per point between the
quasi-static and inertial entries of its protocol and law, so it needs both."""


def available(protocol: str, model: str, state_law: str) -> bool:
    """Whether the scene's combination exists (model "auto" needs both models of the protocol and law)."""
    models = ("quasistatic", "inertial") if model == "auto" else (model,)
    return all((protocol, m, state_law) in REGISTRY for m in models)
