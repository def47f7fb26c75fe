"""Plan: what to model and how to step, decided once per scene ("model only what the scene requires").

For the stop scene the model is the quasi-static one (the paper's), the state is xi alone (plus the
quadrature tau only when a time-resolved observable is asked for), the stepper is fixed-step RK4 in the
scaled log time sigma of :mod:`sweep.models.stop`, and the step count is chosen per point:

* the time map is scaled to the point: s_c = 1/(1 + (chi + |mu1|)/A) (stiff start) and the late step follows
  the local rate (mu1 + 2 m2 u)/A (:mod:`sweep.models.stop`), so that the RK4 error constant is nearly the
  same at every point;
* the step h in sigma then meets ``rtol`` at each point: h = min(H_MAX, (rtol / (SAFETY * C))^(1/4)), with C
  the largest error constant err/h^4 measured on a calibration set spanning chi/A 1e-2..1e3, mu1/A -3..3,
  m2/A 0..3 (benchmarks/calibrate_rk4.py): C_STABLE where steady sliding is stable (chi > mu1; measured
  max 4.4e-4 as h -> 0, 7.4e-4 at h = 0.7) and C_UNSTABLE on the stick-slip side, where the stop starts on an
  unstable fixed point and the error constant is ~3x larger (measured max 1.7e-3); C is multiplied by
  TIME_RESOLVED_FACTOR when values inside the transient are asked for; tests/test_accuracy.py checks the
  rule against an independent scipy reference;
* each point stops when its closed-form tail is accurate to 0.1 * (rtol xi + atol), so its number of steps
  (sigma_end / h) follows from its own dynamics: a few tens on most of the grid, thousands in the costly
  corner (small chi/A with mu1 < 0 and small m2, where the slider creeps along a slow manifold).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

from . import physics
from .models.stop import RATE_FLOOR, TAIL_SAFETY
from .scene import Scene

__all__ = ["Plan", "make_plan", "STEP_RULE"]

C_STABLE = 6.0e-4
"""Bound on the RK4 error constant |err/xi_inf| / h^4 where steady sliding is stable (chi > mu1)."""
C_UNSTABLE = 2.0e-3
"""Bound on the RK4 error constant where steady sliding is unstable (chi <= mu1)."""
SAFETY = 3.0
TIME_RESOLVED_FACTOR = 10.0
"""Time-resolved observables (values inside the transient, not only its limit) have error constants up to
~6x those of xi_inf (tests/test_accuracy.py); when they are asked for, C is multiplied by this factor."""
H_MAX = 0.7
"""Upper bound on the step in sigma (keeps RK4 stable along the slow creep manifold, h |mu1 + 2 m2 u|/(A r) < 1)."""
STEP_RULE = (
    f"RK4, fixed step h in sigma (ds/dsigma = 1/(1/(s + s_c) + r), s = int dtau/psi, u = ln psi = s - xi, "
    f"r = sqrt(((mu1 + 2 m2 u)/A)^2 + |m2|/(4 A)) + {RATE_FLOOR}); h = min({H_MAX}, (rtol/({SAFETY} C))**0.25), "
    f"C = {C_STABLE} where chi > mu1 (stable sliding) else {C_UNSTABLE}, times {TIME_RESOLVED_FACTOR:g} when "
    f"trajectory, slip_at, t50 or t90 are asked for; "
    f"per point s_c = 1/(1 + (chi + |mu1|)/A); stop when the closed-form tail is accurate to "
    f"{TAIL_SAFETY}*(rtol*xi + atol); steps per point = sigma_end/h"
)


def time_scale(k, a):
    """Per-point scale s_c of the early log time, from k = chi/A and a = mu1/A (see module doc)."""
    return 1.0 / (1.0 + k + np.abs(a))


def rk4_step_for(rtol: float, stable_sliding, time_resolved: bool = False):
    """Step in sigma that meets ``rtol`` at each point (the rule of :data:`STEP_RULE`), on xi_inf alone or,
    if ``time_resolved``, also on the trajectory, slip_at, t50 and t90."""
    error_constant = np.where(stable_sliding, C_STABLE, C_UNSTABLE) * (TIME_RESOLVED_FACTOR if time_resolved else 1.0)
    return np.minimum(H_MAX, (rtol / (SAFETY * error_constant)) ** 0.25)


@dataclass(frozen=True, eq=False)
class Plan:
    """The resolved plan of a scene; per-point arrays are flat in C order over (K_over_M, V)."""

    model: str
    stepper: str
    step: np.ndarray
    step_source: str
    rule: str
    max_steps: int
    chi: np.ndarray
    mu1: np.ndarray
    k: np.ndarray
    a: np.ndarray
    b: np.ndarray
    s_c: np.ndarray
    finite: np.ndarray
    tau_samples: np.ndarray
    needs_tau: bool

    @property
    def n_points(self) -> int:
        return self.k.size

    def describe(self) -> dict[str, str]:
        """Human-readable summary, also stored in the Dataset attrs."""
        return {
            "model": self.model,
            "state": "xi (u = s - xi)" + (" + tau quadrature" if self.needs_tau else ""),
            "stepper": self.stepper,
            "step": (f"{self.step.min():.6g}..{self.step.max():.6g} in sigma" if self.step.min() < self.step.max()
                     else f"{self.step[0]:.6g} in sigma") + f" ({self.step_source})",
            "step_rule": self.rule,
            "max_steps": str(self.max_steps),
            "horizon": "per point: until the closed-form tail is accurate (and all requested times are passed)",
            "points": str(self.n_points),
            "points_without_finite_limit": str(int(np.count_nonzero(~self.finite))),
        }

    def text(self) -> str:
        return "\n".join(f"{k:>28}: {v}" for k, v in self.describe().items())

    def hash(self) -> str:
        """Digest of everything that determines the numbers (compared on resume)."""
        h = hashlib.sha256()
        h.update(repr(sorted(self.describe().items())).encode())
        for arr in (self.k, self.a, self.b, self.s_c, self.step, self.finite, self.tau_samples):
            h.update(np.ascontiguousarray(arr).tobytes())
        return h.hexdigest()[:16]


def make_plan(scene: Scene) -> Plan:
    """Decide model, state, stepper and per-point step parameters for ``scene``."""
    p = scene.params
    chi_axis = physics.reduced_stiffness(scene.K_over_M, p.D0, p.g)
    mu1_axis = physics.mu1(scene.V, p.m1, p.m2, p.V0)
    chi, mu1 = (x.ravel() for x in np.meshgrid(chi_axis, mu1_axis, indexing="ij"))
    k, a, b = chi / p.A, mu1 / p.A, np.full(chi.size, p.m2 / p.A)
    # PHYSICS.md 6: finite relaxed slip iff m2 > 0, or m2 = 0 and mu1 > 0
    finite = (b > 0) | ((b == 0) & (a > 0))
    if scene.step is not None:
        step, source = np.full(k.size, scene.step), "override"
    else:
        stable = physics.stable_sliding(chi, mu1, p.A)
        step, source = rk4_step_for(scene.rtol, stable, scene.time_resolved), "rule"
    return Plan(
        model="quasistatic",
        stepper="rk4",
        step=step,
        step_source=source,
        rule=STEP_RULE,
        max_steps=int(scene.max_steps),
        chi=chi,
        mu1=mu1,
        k=k,
        a=a,
        b=b,
        s_c=time_scale(k, a),
        finite=finite,
        tau_samples=scene.tau_samples,
        needs_tau=scene.time_resolved,
    )
