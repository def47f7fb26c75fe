"""The driven protocol over a (K/M, V) grid: one simulation per point (sweep/integrate/driven.py), quasi-static or
with inertia (the plan's per-point model policy)."""

from __future__ import annotations

from collections.abc import Callable

import numba
import numpy as np

from ...accuracy import driven_stepper_rtol
from ...integrate.batch import driven_batch
from ...integrate.driven import DrivenOutputs, DrivenSettings, Regime
from ...integrate.lanes_driven import LANES, DrivenJob, DrivenPoints, driven_lanes
from ...integrate.lanes_driven_inertial import InertialPoints, inertial_lanes
from ...plan.plan import Plan
from ...scene.scene import Scene

__all__ = ["LANE_LAWS", "driven_chunk"]

LANE_LAWS = frozenset({"aging"})
"""State laws whose points run in lanes (quasi-static: sweep/integrate/lanes_driven.py, inertial:
sweep/integrate/lanes_driven_inertial.py); the others run one point per thread (sweep/integrate/driven.py)."""


def lane_groups(n: int) -> int:
    """Groups of points for the lanes (each stepped by one thread, LANES in flight): up to 4 per thread for the
    load balance (a driven point costs 100 to 1e6 steps), at least 4 x LANES points a group."""
    threads = numba.get_num_threads()
    return max(1, min(4 * threads, max(threads, n // (4 * LANES))))


def driven_chunk(scene: Scene, plan: Plan) -> Callable[[np.ndarray], dict[str, np.ndarray]]:
    """compute(points) -> per-point arrays of a driven ``scene`` (points: indices into ``plan``, a chunk's share or
    the whole plan): one simulation per point with the plan's model (in lanes where the state law has them,
    :data:`LANE_LAWS`), and with model="auto" a second one with inertia where the quasi-static run broke
    down (regime runaway)."""
    settings = DrivenSettings(scene.perturbation, driven_stepper_rtol(scene.rtol), scene.max_cycles, scene.max_steps)

    def simulate(points: np.ndarray, inertial: np.ndarray) -> dict[str, np.ndarray]:
        out = DrivenOutputs.empty(points.size)
        k, a, b, g = plan.k[points], plan.a[points], plan.b[points], plan.G[points] * inertial
        for with_inertia in (False, True):  # each kernel variant compiled only where a point needs it
            where = np.flatnonzero((g > 0.0) == with_inertia)
            if not where.size:
                continue
            if scene.state_law in LANE_LAWS:
                # nearest the line first (|mu1 - chi| small: slow transients, the longest points), so that they do
                # not run alone at the end of a lane batch; a point's numbers do not depend on its lane or order
                first = DrivenJob(where[np.argsort(np.abs(a[where] - k[where]), kind="stable")], *settings)
                if with_inertia:  # on the slow manifold where inertia is small, as the one-point driver's below
                    inertial_lanes()[1](InertialPoints(k, a, b, g), first, lane_groups(where.size), out)
                else:
                    driven_lanes()[1](DrivenPoints(k, a, b), first, lane_groups(where.size), out)
            else:
                driven_batch(scene.state_law, with_inertia, with_inertia)(where, k, a, b, g, settings, out)
            if with_inertia:
                # inertial points ran on the slow manifold where inertia is small (sweep/integrate/driven.py); one
                # left undecided there again with the full system (the one-point driver): on the manifold the cycles
                # of a long period (stick phases of 700-6,000 tau) jitter by ~1e-6 and never pass STATIONARY_TOL
                # (hopf.py's grid: 4 points)
                again = where[out.regime[where] == Regime.UNDECIDED]
                if again.size:
                    driven_batch(scene.state_law, True, False)(again, k, a, b, g, settings, out)
        return out._asdict()

    def compute(points: np.ndarray) -> dict[str, np.ndarray]:
        inertial = plan.inertial[points].copy()
        out = simulate(points, inertial)
        if scene.model == "auto":  # the quasi-static model broke down: inertia is needed there
            again = np.flatnonzero((out["regime"] == Regime.RUNAWAY) & ~inertial & (plan.G[points] > 0.0))
            if again.size:
                inertial[again] = True
                for name, value in simulate(points[again], inertial[again]).items():
                    out[name][again] = value
        out["inertial"] = inertial
        return out

    return compute
