"""The plan of a driven scene: one simulation per point (sweep/integrate/driven.py), quasi-static or with inertia per V
(inertial where gamma/A > model_tol with model "auto", and where the quasi-static run breaks down)."""

from __future__ import annotations

import numpy as np

from ...accuracy import (
    DECAYED,
    GROWTH_RTOL,
    NEUTRAL_SPREAD,
    RUNAWAY_XI_DOT,
    STATIONARY_TOL,
    driven_stepper_rtol,
)
from ...plan.plan import Plan, common_fields, line_uses_inertia, point_params
from ...scene.scene import Scene

__all__ = ["driven_plan"]


def driven_plan(scene: Scene) -> Plan:
    """The plan of a driven scene: one simulation per point (sweep/integrate/driven.py)."""
    pts = point_params(scene)
    chi, mu1, G = pts.chi, pts.mu1, pts.G
    k, a, b = pts.reduced
    inertial = line_uses_inertia(G, scene.model, scene.model_tol)
    n = k.size
    return Plan(method="dp5", method_reason="adaptive, PI control; rodas3 where the inertial mode is stiff",
                point_methods=("dp5",), point_method=np.zeros(n, np.int8), adaptive=True, lanes=False,
                dtype=np.dtype(np.float64), step=np.full(n, np.nan), step_source="controller",
                ctrl_tol=driven_stepper_rtol(scene.rtol), rule="", tau_samples=np.empty(0), needs_tau=False,
                notes=tuple(_driven_notes(scene).items()),
                **common_fields(scene, chi, mu1, k, a, b, G, np.ones(n, bool), inertial))


W_TEXT = ", w = ln xi' with inertia"


def _driven_notes(scene: Scene) -> dict[str, str]:
    """What the driven run chose, for the Dataset attrs."""
    return {
        "model": scene.model if scene.model != "auto" else (
            f"auto (model_tol {scene.model_tol:g}): inertial where gamma/A > model_tol and where the quasi-static run "
            f"broke down (regime runaway), quasi-static elsewhere (variable model)"),
        "state_law": scene.state_law,
        "method": f"dp5 (adaptive, PI control) in tau on (z = tau - xi, u = ln psi"
                  f"{W_TEXT if scene.model != 'quasistatic' else ''}), local rtol "
                  f"{driven_stepper_rtol(scene.rtol):g} x max(perturbation, |z|)",
        "regime_rule": (f"runaway: slip velocity > {RUNAWAY_XI_DOT:g} V; steady: state below {DECAYED:g} x "
                        f"perturbation or 3 per-cycle growth rates < 0 agreeing to {GROWTH_RTOL:g}; stationary: "
                        f"|a_k/a_k-1 - 1| <= {STATIONARY_TOL:g} over 3 cycles, neutral within {NEUTRAL_SPREAD:g} "
                        f"of the first cycle's amplitude, else stick_slip; undecided after {scene.max_cycles} "
                        f"cycles or {scene.max_steps} steps"),
        "perturbation": f"z(0) = {scene.perturbation:g}, u(0) = 0",
    }
