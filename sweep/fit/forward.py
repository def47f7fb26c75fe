"""Forward model of the fit: many stop transients with per-point friction parameters, in one engine call.

Each point is a stop from steady sliding at V (docs/physics.md 3a, quasi-static model, aging law) with its own
(A, m1, m2, D0, K/M, V): the fit's parameter sets, perturbed sets and profile points of every curve go into one
flat batch. In reduced variables (docs/physics.md 2; paper section 4) a point is

    chi = (K/M) D0/g,   mu1 = m1 - 2 m2 ln(V/V0),   k = chi/A,  a = mu1/A,  b = m2/A,   tau = V t/D0,

and what it returns is the slip x(t) = D0 xi(tau) [m] at the point's own times and the relaxed slip
Dx_inf = D0 xi_inf [m] (eq. 10 when m2 = 0; the engine's closed-form tail otherwise: the limit, not a horizon).

The plan comes from :func:`sweep.plan.plan.stop_plan_for_points` (the step rule, horizon and error estimates of a
sweep, per point) and :func:`sweep.protocols.stop.engine.run_points` runs it: points with sampled times through the
sampled adaptive lanes (sweep/integrate/lanes_sampled.py; the per-point kernel for the few they do not cover), each
point with its own row of reduced times (``obs_tau``), relaxed-slip-only batches through the relaxed-slip lanes.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .. import physics
from ..plan.plan import PointParams, stop_plan_for_points
from ..protocols.stop.engine import mark_error_above_tol, run_points
from ..scene.params import FrictionParams
from ..scene.scene import Scene
from ..status import Status

__all__ = ["ForwardPoints", "ForwardResult", "forward", "stable_sliding", "warm_up_per_point"]

OK = int(Status.OK)


class ForwardPoints(NamedTuple):
    """Flat per-point inputs of :func:`forward` (SI units; every array of length n, ``t`` of shape (n, n_t))."""

    A: np.ndarray
    """Direct-effect coefficient [1] (eq. 1), > 0."""
    m1: np.ndarray
    """Slope of mu_d at V0 [1] (eq. 6)."""
    m2: np.ndarray
    """Curvature of mu_d [1] (eq. 6)."""
    D0: np.ndarray
    """Memory length [m], > 0."""
    K_over_M: np.ndarray
    """Spring stiffness over slider mass [s-2]."""
    V: np.ndarray
    """Driving velocity before the stop [m s-1]."""
    t: np.ndarray
    """Times after the stop at which x(t) is wanted [s], shape (n, n_t); n_t may be 0 (relaxed slip only)."""

    @property
    def n(self) -> int:
        return int(np.size(self.A))


@dataclass
class ForwardResult:
    """What :func:`forward` returns, per point: slip at the asked times and relaxed slip [m], their absolute error
    estimates [m], the engine's status code (:class:`sweep.Status`) and whether steady sliding before the stop was
    stable (chi > mu1, eq. 3)."""

    x: np.ndarray
    x_err: np.ndarray
    dx_inf: np.ndarray
    dx_inf_err: np.ndarray
    status: np.ndarray
    stable: np.ndarray


def stable_sliding(points: ForwardPoints, V0: float = 1e-6, g: float = 9.81) -> np.ndarray:
    """Per point: steady sliding at V is stable, chi > mu1(V) (eq. 3, quasi-static Hopf line)."""
    chi, mu1 = _chi_mu1(points, V0, g)
    return np.asarray(physics.stable_sliding(chi, mu1, points.A), dtype=bool)


def _chi_mu1(points: ForwardPoints, V0: float, g: float) -> tuple[np.ndarray, np.ndarray]:
    chi = np.asarray(physics.reduced_stiffness(points.K_over_M, points.D0, g), dtype=float)
    mu1 = np.asarray(physics.mu1(points.V, points.m1, points.m2, V0), dtype=float)
    return np.atleast_1d(chi), np.atleast_1d(mu1)


@functools.lru_cache(maxsize=8)
def _settings(rtol: float, sampled: bool) -> Scene:
    """The scene whose settings every forward batch uses: quasi-static stop, aging law, the engine's own method
    choice for ``rtol``; its grid and parameters are placeholders (the points bring their own)."""
    return Scene(protocol="stop", params=FrictionParams(A=1.0, m1=0.0, m2=0.0, D0=1.0), K_over_M=[1.0], V=[1.0],
                 rtol=rtol, observables=("xi_inf", "slip_at") if sampled else ("xi_inf",), t_obs=(1.0,),
                 model="quasistatic")


def forward(points: ForwardPoints, rtol: float = 1e-8, V0: float = 1e-6, g: float = 9.81, estimates: bool = True
            ) -> ForwardResult:
    """Solve every point of ``points`` in one engine call; see the module docstring for the equations.

    ``rtol`` is the engine's relative accuracy (1e-10..1e-2; pick it far below the data's relative noise).
    V0 [m s-1] and g [m s-2] as in :class:`sweep.FrictionParams`. ``estimates=False``: the points of the sampled
    lanes run once, without the fine twin that estimates their error (~half the cost; ``x_err`` and ``dx_inf_err``
    NaN there; ``x_err`` a read-only NaN view): the fit's iterations, whose best fits are checked with estimates
    (sweep.fit.core).
    """
    n = points.n
    t = np.asarray(points.t, dtype=float).reshape(n, -1)
    chi, mu1 = _chi_mu1(points, V0, g)
    A = np.broadcast_to(np.asarray(points.A, dtype=float), (n,))
    D0 = np.broadcast_to(np.asarray(points.D0, dtype=float), (n,))
    V = np.broadcast_to(np.asarray(points.V, dtype=float), (n,))
    G = np.asarray(physics.inertia_number(V, D0, g), dtype=float).reshape(n) / A
    m2 = np.broadcast_to(np.asarray(points.m2, dtype=float), (n,))
    scene = _settings(float(rtol), t.shape[1] > 0)
    plan = stop_plan_for_points(scene, PointParams(chi, mu1, A.copy(), m2.copy(), G))
    raw = run_points(scene, plan, np.arange(n), obs_tau=V[:, None] * t / D0[:, None] if t.shape[1] else None,
                     estimates=estimates)
    if estimates:  # without, the lanes' points have no estimate to compare (the per-point fallback's are kept)
        mark_error_above_tol(scene, raw)
    x_err = D0[:, None] * raw.xi_at_err if estimates else np.broadcast_to(np.nan, raw.xi_at.shape)
    return ForwardResult(x=D0[:, None] * raw.xi_at, x_err=x_err, dx_inf=D0 * raw.xi_inf,
                         dx_inf_err=D0 * raw.xi_inf_err, status=raw.status,
                         stable=np.asarray(physics.stable_sliding(chi, mu1, A), dtype=bool))


def warm_up_per_point(*rtols: float) -> None:
    """Compile (or load from numba's cache) the per-point path of :func:`forward` at each of ``rtols``: one point
    without a finite relaxed slip (m2 = 0, mu1 < 0: the slip grows without bound, docs/physics.md 6) and one sampled
    time. A fit's global grid holds such points (sweep.fit.core compiles this in a second process on a cold cache,
    beside the sampled lanes)."""
    one = np.ones(1)
    for rtol in rtols:
        forward(ForwardPoints(A=0.01 * one, m1=-0.001 * one, m2=0.0 * one, D0=1e-6 * one, K_over_M=1e5 * one,
                              V=1e-6 * one, t=np.ones((1, 1))), rtol=rtol)
