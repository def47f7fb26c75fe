"""Right-hand sides of the model, one per protocol x model, with the state laws composed into them.

A right-hand side (with its Jacobian and closed-form tails where it has them) knows nothing of steppers; the drivers
of :mod:`sweep.integrate` compose it with a stepper, a controller and what is recorded. The state laws are a registry
(:data:`sweep.integrate.models.state_laws.STATE_LAWS`); which (model, state law) pairs a protocol runs, each protocol
says (sweep.protocols.base.Protocol.models).
"""

from __future__ import annotations

import warnings


def __getattr__(name: str):
    """REGISTRY and available(), of an earlier layout: each protocol now says what it runs (Protocol.models)."""
    from ... import protocols

    if name == "REGISTRY":
        warnings.warn("sweep.integrate.models.REGISTRY is replaced by sweep.protocols.get(name).models and "
                      "sweep.integrate.models.state_laws.STATE_LAWS", FutureWarning, stacklevel=2)
        return {(p, m, law): protocols.CATALOGUE[p] for p in protocols.names() for (m, law) in protocols.get(p).models}
    if name == "available":
        warnings.warn("sweep.integrate.models.available(protocol, model, law) is replaced by "
                      "sweep.protocols.get(protocol).supports(model, law)", FutureWarning, stacklevel=2)
        return lambda protocol, model, state_law: protocols.get(protocol).supports(model, state_law)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
