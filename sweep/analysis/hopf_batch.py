"""Many driven runs at once for the searches along the Hopf line (sweep/analysis/hopf.py, bistable.py).

A search at one velocity (bracketing the line, deciding its type, the bistable band's edge) is a sequence of rounds,
each needing a few driven simulations (sweep/integrate/driven.py) whose outcome decides the next round. Written as a
generator, a search yields each round's runs (a list of :class:`Run`) and receives their results (a list of
:class:`sweep.integrate.driven.DrivenResult`, in the same order), and returns its answer. :func:`drive` advances the
searches of all velocities in lockstep: the runs of one round of every search go to the driven batch entry points in
one call, grouped by their settings: the points of the aging law in SIMD lanes, 16 in flight per thread
(quasi-static: sweep/integrate/lanes_driven.py; inertial, the runs that end in a regime, from
:data:`INERTIAL_LANES_FROM` a call: sweep/integrate/lanes_driven_inertial.py, on the slow manifold where inertia is
small, and a point left undecided there again with the full system, as the driven scene does); the others one after
the other with the one-point driver (:func:`sweep.integrate.driven.simulate_point`; the threaded
:func:`sweep.integrate.batch.driven_batch` compiled its parallel loop for the inertial model in every process). A
point's numbers do not depend on the others in its batch. The lanes' numbers differ from the one-point driver's at
the stepper's tolerance (their own method, exponential and controller; sweep/integrate/lanes_driven.py).
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Sequence
from typing import Any, NamedTuple

import numpy as np

from ..accuracy import SIGN_CYCLES, STEPPER_RTOL
from ..integrate.driven import DrivenOutputs, DrivenParams, DrivenResult, DrivenSettings, Regime, simulate_point
from ..integrate.lanes_driven import LANES, DrivenJob, DrivenPoints, driven_lanes
from ..integrate.lanes_driven_inertial import InertialPoints, inertial_lanes
from ..protocols.driven.chunk import LANE_LAWS, lane_groups

__all__ = ["INERTIAL_LANES_FROM", "MAX_STEPS", "TYPE_RTOL", "Run", "Search", "drive", "run_many"]

MAX_STEPS = 20_000_000
"""Step budget of every run of the searches."""
TYPE_RTOL = 1e-9
"""Stepper tolerance of the runs that end in a regime (the type of the line, the bistable band): the driven scene's
own (:func:`sweep.accuracy.driven_stepper_rtol`), far below the stationarity test's STATIONARY_TOL. The runs that
measure a growth rate at the line, where it vanishes, keep STEPPER_RTOL (1e-10). Against 1e-10: the same regimes and
cycle counts, limit-cycle amplitudes within 8e-8 relative (sample2, 45 velocities at 0.4 and 1.6 % below the line),
1.6x fewer steps."""


INERTIAL_LANES_FROM = LANES // 4
"""Inertial runs that end in a regime (a cycle budget above SIGN_CYCLES: the type, the bistable band) go to the lanes
from this many in one call on, fewer to the one-point driver: a lone long inertial run costs about twice as much in
a quarter-width lane attempt (the bistable band's searches, one or two runs a round: 5 velocities 10.4 s in lanes,
5.7 s on the one-point driver); the type's searches over many velocities fill them. The runs that measure a growth
rate over SIGN_CYCLES end undecided by design, and a point left undecided in the inertial lanes runs again with the
full system: those stay on the one-point driver."""


class Run(NamedTuple):
    """One driven simulation asked for by a search (reduced parameters, docs/physics.md 3b)."""

    k: float
    """chi/A."""
    a: float
    """mu1(V)/A."""
    b: float
    """m2/A."""
    g: float
    """gamma/A (0: the quasi-static model)."""
    perturbation: float
    """Initial spring stretch z(0) [1]."""
    max_cycles: int
    rtol: float = STEPPER_RTOL
    """Local tolerance of the stepper."""


Search = Generator[list[Run], list[DrivenResult], Any]
"""A search: yields rounds of runs, receives their results, returns its answer."""


def run_many(runs: Sequence[Run], law: str = "aging") -> list[DrivenResult]:
    """The results of ``runs`` (in order), each with MAX_STEPS steps: one batch call per distinct (perturbation,
    max_cycles, rtol, model) (module docstring)."""
    n = len(runs)
    if not n:
        return []
    k, a, b, g = (np.array([r[i] for r in runs], dtype=float) for i in range(4))
    out = DrivenOutputs.empty(n)
    for pert, cycles, rtol in sorted({(r.perturbation, r.max_cycles, r.rtol) for r in runs}):
        mine = np.array([(r.perturbation, r.max_cycles, r.rtol) == (pert, cycles, rtol) for r in runs])
        settings = DrivenSettings(pert, rtol, cycles, MAX_STEPS)
        for with_inertia in (False, True):
            where = np.flatnonzero(mine & ((g > 0.0) == with_inertia))
            if not where.size:
                continue
            if law in LANE_LAWS and (not with_inertia or (where.size >= INERTIAL_LANES_FROM and cycles > SIGN_CYCLES)):
                # the slowest transients first (growth rate ~ |a - k|/2 per tau), so that none runs alone at the end
                first = DrivenJob(where[np.argsort(np.abs(a[where] - k[where]), kind="stable")], *settings)
                if not with_inertia:
                    driven_lanes()[1](DrivenPoints(k, a, b), first, lane_groups(where.size), out)
                    continue
                inertial_lanes()[1](InertialPoints(k, a, b, g), first, lane_groups(where.size), out)
                # as the driven scene (sweep/protocols/driven/chunk.py): a point left undecided on the slow manifold
                # runs again with the full system
                where = where[out.regime[where] == Regime.UNDECIDED]
            for i in where:  # the one-point driver in turn (its parallel batch would add ~5 s of compiling a process)
                for field, value in zip(out, simulate_point(DrivenParams(k[i], a[i], b[i], g[i]), settings, law)):
                    field[i] = value
    return [DrivenResult(*(field[i] for field in out)) for i in range(n)]


def drive(searches: Sequence[Search], law: str = "aging", done: Callable[[int], None] | None = None) -> list:
    """The answers of ``searches`` (generators, module docstring), advanced in lockstep: every round, the runs that
    all unfinished searches ask for in one :func:`run_many`. ``done(i)`` is called as search i returns."""
    answers: list = [None] * len(searches)
    asked: dict[int, list[Run]] = {}

    def step(i: int, results: list[DrivenResult] | None) -> None:
        try:
            asked[i] = searches[i].send(results)  # (None starts the generator)
        except StopIteration as end:
            answers[i] = end.value
            asked.pop(i, None)
            if done is not None:
                done(i)

    for i in range(len(searches)):
        step(i, None)
    while asked:
        order = list(asked)
        results = run_many([run for i in order for run in asked[i]], law)
        start = 0
        for i in order:
            count = len(asked[i])
            step(i, results[start:start + count])
            start += count
    return answers
