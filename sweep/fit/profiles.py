"""Profile likelihoods: the least misfit at fixed values of one parameter, the others free (sweep.fit.local).

Each free parameter of each problem is profiled at best +- OFFSETS standard errors (from the covariance), cut at
its bounds (the bound itself then being the last point). Where the misfit is quadratic the square root of its rise is
linear in the parameter, with the slope 1/standard error that the covariance predicts: a side whose first point
rises within QUADRATIC_TOL of that prediction has its threshold crossing interpolated between the best value and
that point, exactly so for a quadratic misfit. A side that rose otherwise gets the point INNER standard errors out
(the bracket of a near-quadratic but skewed profile); a side whose profile has not crossed the 95 % threshold and
has not reached its bound is extended to EXTEND standard errors, both in a second round. Then, up to REFINE_ROUNDS
times, a side whose threshold crossing lies in a bracket wider than REFINE_FRACTION x its distance from the best
value gets the bracket's midpoint (the bracket [best, first point] of a side that passed the quadratic test
excepted): the interval interpolates the crossing linearly in sqrt(misfit increase), far off where a profile is
flat and then steep (a parameter traded against others inside their bounds; the standard error is then useless and
the points are (upper - lower)/6 apart).

Every profile point of every parameter of every problem is one least-squares task over the other parameters: a
round of profile points runs them all in lockstep, one engine round per iteration (sweep.fit.levenberg,
sweep.fit.stack). Each starts from the best fit moved along the covariance's regression line
(theta_k = best_k + C_kj/C_jj (value - best_j)) with the best fit's Jacobian, which Broyden's secants then update:
one forward solve an iteration, a few iterations a point (the intervals of benchmarks/fit.py's curves agree to 4e-6
of their half-widths with forward-difference Jacobians at every iteration, which cost p solves an iteration).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .levenberg import HOLD, solve
from .problem import Problem
from .stack import ProblemStack

__all__ = ["EXTEND", "INNER", "OFFSETS", "QUADRATIC_TOL", "REFINE_FRACTION", "REFINE_ROUNDS", "Profile",
           "profile_all"]

OFFSETS = (2.25,)
"""First round, in standard errors either side of the best value: one point a side. On a quadratic profile the
crossing lies at 1.96, inside [best, 2.25] with room for a rise QUADRATIC_TOL off the prediction (2.25 x 0.9 > 1.96).
Two points a side (1.5 and 2.25) cost twice the forward solves; on the 100 curves of benchmarks/fit.py every one of
the 600 sides rose within 5.4 % of the prediction at 2.25, and the crossings interpolated from [best, 2.25] agreed
with those from [1.5, 2.25] to 0.4 % of the interval's half-width."""
QUADRATIC_TOL = 0.1
"""A side is near-quadratic where sqrt(rise) at its first point lies within this fraction of |value - best|/stderr
(the covariance's prediction): the crossing interpolated from the best value is then off by ~QUADRATIC_TOL^2 of the
half-width at most (a rise that bends smoothly from the predicted slope)."""
INNER = 1.5
"""Second round, on the sides whose first point crossed the threshold but did not rise as predicted: the point that
brackets a near-quadratic crossing (1.96) with the first (REFINE_FRACTION then needs no more)."""
EXTEND = (3.0, 4.0, 6.0, 9.0, 14.0)
"""Second round, on the sides still below the threshold."""
REFINE_ROUNDS = 4
"""Bisection rounds at most, on the sides whose crossing is poorly bracketed."""
REFINE_FRACTION = 0.6
"""A crossing bracketed by [v_in, v_out] is refined where |v_out - v_in| > REFINE_FRACTION |v_in - best| (default
offsets on a quadratic profile: crossing at 1.96 in [1.5, 2.25] standard errors, 0.75 < 0.9: not refined; a
crossing in [best, 1.5] always is)."""


@dataclass
class Profile:
    """Profile of one parameter: its ``values`` (increasing, the best value included) and the least sum of squared
    weighted residuals ``rss`` at each."""

    values: np.ndarray
    rss: np.ndarray


def _side_values(best: float, sigma: float, sign: int, bound: float, offsets) -> list[float]:
    out = []
    for o in offsets:
        v = best + sign * o * sigma
        if (v - bound) * sign >= 0:
            if (best - bound) * sign < 0:
                out.append(bound)
            break
        out.append(v)
    return out


def _sigma(cov: np.ndarray, j: int, lo: float, hi: float) -> float:
    s = float(np.sqrt(cov[j, j])) if np.isfinite(cov[j, j]) and cov[j, j] > 0 else np.inf
    return min(s, (hi - lo) / 6.0)


def _starts(best: np.ndarray, covs: np.ndarray, q: np.ndarray, j: np.ndarray, value: np.ndarray) -> np.ndarray:
    """Start of each profile point (task i: problem q[i], parameter j[i] at value[i]): the best fit moved along the
    covariance's regression line, theta_k = best_k + C_kj/C_jj (value - best_j) (the best fit itself where that
    column of the covariance is not finite)."""
    i = np.arange(q.size)
    col = covs[q, :, j]  # (T, p): column j of each task's covariance
    cjj = col[i, j]
    with np.errstate(invalid="ignore", divide="ignore"):
        shift = col / cjj[:, None] * (value - best[q, j])[:, None]
    usable = np.all(np.isfinite(col), axis=1) & (cjj > 0)
    theta = best[q] + np.where(usable[:, None], shift, 0.0)
    theta[i, j] = value
    return theta


def profile_all(problems: list[Problem], best: list[np.ndarray], best_rss: list[float], covs: list[np.ndarray],
                s2: list[float], crit: float | list[float], stack: ProblemStack, jacs: list[np.ndarray]
                ) -> list[list[Profile]]:
    """Profiles of every free parameter of every problem (problem x parameter); ``crit`` the threshold per problem
    (uncertainty.threshold), ``s2`` the noise variance per problem, ``jacs`` the Jacobian at each best fit (the
    profile points' first Jacobian, updated by Broyden's secants: sweep.fit.levenberg)."""
    crits = crit if isinstance(crit, list) else [crit] * len(problems)
    points: dict[tuple[int, int], list[tuple[float, float]]] = {}

    p = problems[0].space.p
    best_all, covs_all = np.array(best), np.array(covs)
    jacs_all = np.zeros((len(problems), stack.n_max, p))  # each padded with zero rows to n_max
    for q, jac in enumerate(jacs):
        jacs_all[q, :jac.shape[0]] = jac

    def run(tasks):
        q, j = (np.array([t[k] for t in tasks], dtype=np.intp) for k in (0, 1))
        value = np.array([t[2] for t in tasks], dtype=float)
        hold = np.zeros((len(tasks), p), bool)
        hold[np.arange(len(tasks)), j] = True
        sol = solve(stack, q, _starts(best_all, covs_all, q, j, value), hold=hold, tol=HOLD, jac0=jacs_all)
        for (q, j, value), rss in zip(tasks, sol.rss):
            points.setdefault((q, j), []).append((value, float(rss)))

    sigmas = {}
    tasks = []
    for q, pr in enumerate(problems):
        sp = pr.space
        for j in range(sp.p):
            sigmas[q, j] = _sigma(covs[q], j, sp.lower[j], sp.upper[j])
            points[q, j] = [(float(best[q][j]), best_rss[q])]
            for sign, bound in ((-1, sp.lower[j]), (1, sp.upper[j])):
                tasks += [(q, j, v) for v in _side_values(best[q][j], sigmas[q, j], sign, bound, OFFSETS)]
    run(tasks)

    def side(q, j, sign):
        """The points of one side, nearest first, as (value, misfit rise in noise-variance units)."""
        b = float(best[q][j])
        return sorted(((v, (r - best_rss[q]) / s2[q]) for v, r in points[q, j] if (v - b) * sign > 0),
                      key=lambda vr: abs(vr[0] - b))

    def quadratic(q, j, v, delta):
        """Whether sqrt(delta) at v rose as the covariance predicts, |v - best|/stderr, within QUADRATIC_TOL."""
        cjj = covs[q][j, j]
        if not (np.isfinite(cjj) and cjj > 0 and np.isfinite(delta)):
            return False
        return abs(np.sqrt(max(delta, 0.0)) * np.sqrt(cjj) / abs(v - float(best[q][j])) - 1.0) <= QUADRATIC_TOL

    tasks = []
    for q, j in points:
        sp = problems[q].space
        b = float(best[q][j])
        for sign, bound in ((-1, sp.lower[j]), (1, sp.upper[j])):
            pts = side(q, j, sign)
            reached = any(v == bound for v, _ in pts)
            crossed = any(d >= crits[q] for _, d in pts)
            if not (reached or crossed):
                tasks += [(q, j, v) for v in _side_values(b, sigmas[q, j], sign, bound, EXTEND)]
            elif pts and pts[0][1] >= crits[q] and not quadratic(q, j, *pts[0]):
                inner = b + sign * INNER * sigmas[q, j]
                if abs(inner - b) < abs(pts[0][0] - b):
                    tasks.append((q, j, inner))
    if tasks:
        run(tasks)
    for _ in range(REFINE_ROUNDS):
        tasks = []
        for q, j in points:
            b = float(best[q][j])
            for sign in (-1, 1):
                v_in = b
                for v, delta in side(q, j, sign):
                    if delta >= crits[q]:
                        exempt = v_in == b and quadratic(q, j, v, delta)
                        if not exempt and abs(v - v_in) > REFINE_FRACTION * abs(v_in - b):
                            tasks.append((q, j, 0.5 * (v + v_in)))
                        break
                    v_in = v
        if not tasks:
            break
        run(tasks)
    out = []
    for q, pr in enumerate(problems):
        row = []
        for j in range(pr.space.p):
            pts = sorted(points[q, j])
            row.append(Profile(np.array([v for v, _ in pts]), np.array([r for _, r in pts])))
        out.append(row)
    return out
