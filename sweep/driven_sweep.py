"""The driven protocol over a (K/M, V) grid: one simulation per point (sweep/models/driven.py), quasi-static or
with inertia (Scene.model)."""

from __future__ import annotations

import numpy as np

from . import physics
from .accuracy import DECAYED, GROWTH_RTOL, NEUTRAL_SPREAD, RUNAWAY_XI_DOT, STATIONARY_TOL, driven_stepper_rtol
from .integrate.driven import DrivenOutputs, DrivenSettings, Regime, driven_batch
from .model_choice import line_uses_inertia
from .scene import Scene

__all__ = ["driven_chunk", "stepper_rtol"]

W_TEXT = ", w = ln xi' with inertia"
CHUNK = 1024
"""Points per chunk of a driven sweep (one progress update, one journal entry)."""


stepper_rtol = driven_stepper_rtol


def describe(scene: Scene) -> dict[str, str]:
    """What the driven run chose, for the Dataset attrs."""
    return {
        "model": {"auto": f"auto (model_tol {scene.model_tol:g}): inertial where gamma/A > model_tol and where the "
                          f"quasi-static run broke down (regime runaway), quasi-static elsewhere (variable model)",
                  "inertial": "inertial (gamma = V^2/(g D0) per V)", "quasistatic": "quasistatic"}[scene.model],
        "method": f"dp5 (adaptive, PI control) in tau on (z = tau - xi, u = ln psi"
                  f"{W_TEXT if scene.model != 'quasistatic' else ''}), local rtol "
                  f"{stepper_rtol(scene.rtol):g} x max(perturbation, |z|)",
        "regime_rule": (f"runaway: slip velocity > {RUNAWAY_XI_DOT:g} V; steady: state below {DECAYED:g} x "
                        f"perturbation or 3 per-cycle growth rates < 0 agreeing to {GROWTH_RTOL:g}; stationary: "
                        f"|a_k/a_k-1 - 1| <= {STATIONARY_TOL:g} over 3 cycles, neutral within {NEUTRAL_SPREAD:g} "
                        f"of the first cycle's amplitude, else stick_slip; undecided after {scene.max_cycles} "
                        f"cycles or {scene.max_steps} steps"),
        "perturbation": f"z(0) = {scene.perturbation:g}, u(0) = 0",
    }


def driven_chunk(scene: Scene):
    """compute(points) -> per-point arrays of a driven ``scene`` (sweep/runner.py): one simulation per point, and
    with model="auto" a second one with inertia where the quasi-static run broke down (regime runaway)."""
    p = scene.params
    n_v = scene.V.size
    k_k = physics.reduced_stiffness(scene.K_over_M, p.D0, p.g) / p.A  # per K/M; flat index i_K n_V + i_V
    a_v = physics.mu1(scene.V, p.m1, p.m2, p.V0) / p.A  # per V
    G_v = physics.inertia_number(scene.V, p.D0, p.g) / p.A
    inertial_v = line_uses_inertia(G_v, scene.model, scene.model_tol)
    settings = DrivenSettings(scene.perturbation, stepper_rtol(scene.rtol), scene.max_cycles, scene.max_steps)

    def simulate(g: np.ndarray, inertial: np.ndarray) -> dict[str, np.ndarray]:
        out = DrivenOutputs.empty(g.size)
        driven_batch(scene.state_law)(k_k[g // n_v], a_v[g % n_v], np.full(g.size, p.m2 / p.A),
                                      G_v[g % n_v] * inertial, settings, out)
        return out._asdict()

    def compute(points: np.ndarray) -> dict[str, np.ndarray]:
        inertial = inertial_v[points % n_v]
        out = simulate(points, inertial)
        if scene.model == "auto":  # the quasi-static model broke down: inertia is needed there
            again = np.flatnonzero((out["regime"] == Regime.RUNAWAY) & ~inertial & (G_v[points % n_v] > 0.0))
            if again.size:
                inertial[again] = True
                for name, value in simulate(points[again], inertial[again]).items():
                    out[name][again] = value
        out["inertial"] = inertial
        return out

    return compute
