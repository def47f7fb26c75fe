"""Whether each sample's fit can be trusted: a status per sample, a flag per parameter at a bound, and one warning
line per call that names the failed samples and the advice that matches the cause (issue 37).

A sample's ``fit_status`` is the most severe of (codes in :data:`FIT_STATUS`, in increasing severity):

* ``not_converged``: the least squares stopped after their last round (sweep.fit.levenberg.STATUS 0);
* ``at_bound``: a free parameter rests on a bound that the data push against: the misfit would fall by more than
  :data:`PUSH` (units of the noise variance) beyond it, by the quadratic model of the Jacobian at the best fit with
  the other parameters re-optimised (gradient g_j = sum_i J_ij r_i: a fall of g_j^2 C_jj/s^4, C the covariance
  s^2 (J^T J)^-1; g_j^2/(H_jj s^2), H_jj = sum_i J_ij^2, where C_jj is not finite). A bound that is a
  physical limit (:data:`PHYSICAL_LIMITS`: m2 = 0, below which there is no finite relaxed slip) is no failure: the
  parameter is flagged ``at_physical_limit`` in ``<name>_at_bound`` and the sample stays ``ok``;
* ``singular``: an infinite standard error (J^T J singular: the data do not determine some combination of the free
  parameters);
* ``failed_solves``: the forward model gave no number for some datum at the best fit (no finite relaxed slip there,
  or a solve that failed). Its covariance, intervals, profiles, noise, misfit and the fitted values of those data
  are not computed: NaN;
* ``poor_fit`` (code 5, the least severe failure, reported only where nothing else failed): with the noise given,
  the misfit chi^2 lies more than :data:`POOR_FIT_Z` standard deviations sqrt(2 dof) above its degrees of freedom
  dof: no parameter set describes the data (a wrong model: a wrong history, a trend not modelled, a parameter held
  at a wrong value), or the noise given is too small. With the noise estimated the misfit is dof by construction
  and says nothing;
* ``events_missed`` (code 6, a record fit's, as severe as poor_fit and named instead of it where both apply): a
  record shows slip events (the sharp drops of a stick-slip sawtooth, sweep.fit.events) and the model at the best
  fit a different number of them (a stable model sliding through a sawtooth has none), or one far from a record's
  event, or a fall that differs from its by more than sweep.fit.events.DROP noise scales of the record, or the same
  events a sample or two off, or the same events with serially correlated residuals (a local minimum that describes
  the sawtooth another way): an estimated noise absorbs each of these (issue 34). The warning names the reason per
  record (:data:`MISSED`).

``ok`` is 0; every other status is a failed fit (``sweep fit`` then exits 1).
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass

import numpy as np

from .local import LocalFit
from .space import ParamSpace

__all__ = ["BOUND_FLAGS", "FIT_STATUS", "PHYSICAL_LIMITS", "PUSH", "Verdict", "judge", "missed_events", "summary",
           "user_stacklevel"]

FIT_STATUS = {0: "ok", 1: "not_converged", 2: "at_bound", 3: "singular", 4: "failed_solves", 5: "poor_fit",
              6: "events_missed"}
"""Per sample (CF flag_meanings), 1..4 in increasing severity, 5 and 6 below 1: the reported one is the most severe
that applies."""
POOR_FIT_Z = 5.0
"""With the noise given, a misfit above dof + POOR_FIT_Z sqrt(2 dof) is a poor fit (chi^2 with dof degrees of
freedom: mean dof, standard deviation sqrt(2 dof); 5 of them is a p-value below ~1e-5 for dof >= 100)."""
BOUND_FLAGS = {0: "inside", 1: "at_physical_limit", 2: "pushed_against_bound", 3: "at_bound"}
"""Per free parameter and sample: inside its bounds; resting on a physical limit (no failure); on a bound that the data
push against (a failure: widen it); on a bound the data do not push against (the misfit rises beyond it too)."""
PHYSICAL_LIMITS = {("m2", "lower"): 0.0}
"""Bounds that are limits of the model, not choices: m2 < 0 has no finite relaxed slip (docs/physics.md 6)."""
PUSH = 1.0
"""Fall of the misfit beyond a bound [units of the noise variance] above which the data push against it (the
unconstrained optimum lies about one standard error or more beyond the bound)."""
BOUND_TOL = 1e-9
"""A parameter within this fraction of its bound interval of a bound rests on it."""


@dataclass
class Verdict:
    """One sample's verdict: ``status`` (key of FIT_STATUS), per free parameter its bound flag (key of BOUND_FLAGS),
    per datum whether the model gave no number at the best fit (``unsolved``), and the parameters that the data push
    beyond a bound as (name, value, side)."""

    status: int
    bound: np.ndarray
    unsolved: np.ndarray
    pushed: list[tuple[str, float, str]]
    misfit: tuple[float, int] | None = None
    """(chi^2, degrees of freedom) where the noise was given and the misfit is a poor fit's."""
    events: list[tuple[str, list[float], list[float], str, float]] | None = None
    """(record, the falls of its slip events, those of the best fit's, why, by how much: sweep.fit.events.record_events)
    of the records the best fit misses, where events_missed."""

    @property
    def failed(self) -> bool:
        return self.status != 0


def judge(fit: LocalFit, cov: np.ndarray, s2: float, space: ParamSpace, model_failed: float,
          dof: int | None = None) -> Verdict:
    """The verdict of one sample (module docstring): ``fit`` its least squares (residuals where the model gave no
    number hold ``model_failed``, sweep.fit.problem.MODEL_FAILED), ``cov`` its covariance, ``s2`` its noise variance
    (1 with the noise given), ``dof`` its degrees of freedom where the noise was given (None: estimated)."""
    unsolved = fit.residuals == model_failed
    if getattr(fit, "failures", 0) and not unsolved.any():  # a residual equal to the stand-in by chance: impossible
        unsolved = np.ones_like(unsolved)
    flags = np.zeros(space.p, np.int8)
    pushed = []
    width = space.upper - space.lower
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        g = fit.jac.T @ fit.residuals
        H = np.einsum("ij,ij->j", fit.jac, fit.jac)
        c = np.diagonal(cov)
        # the others re-optimised (their gradient ~0 at the fit): g_j^2 (J^T J)^-1_jj; alone where that is not finite
        fall = np.where(np.isfinite(c) & (c > 0), g ** 2 * c / s2 ** 2, g ** 2 / (H * s2))
    for j, name in enumerate(space.names):
        for side, bound, outward in (("lower", space.lower[j], g[j] > 0), ("upper", space.upper[j], g[j] < 0)):
            if abs(fit.theta[j] - bound) > BOUND_TOL * width[j]:
                continue
            if PHYSICAL_LIMITS.get((name, side)) == bound:
                flags[j] = 1
            elif outward and (fall[j] > PUSH or not np.isfinite(fall[j])):
                flags[j] = 2
                pushed.append((name, float(fit.theta[j]), side))
            else:
                flags[j] = 3
    status, poor = 0, None
    if dof is not None and dof > 0 and fit.rss > dof + POOR_FIT_Z * np.sqrt(2.0 * dof):
        status, poor = 5, (float(fit.rss), int(dof))
    if fit.status == 0:
        status = 1
    if pushed:
        status = 2
    if not np.all(np.isfinite(np.diagonal(cov))):
        status = 3
    if unsolved.any():
        status = 4
    return Verdict(status, flags, unsolved, pushed, poor)


def missed_events(verdict: Verdict, missed: list[tuple[str, list[float], list[float], str, float]]) -> Verdict:
    """``verdict`` with status events_missed where nothing more severe than poor_fit failed and the best fit misses
    some record's slip events (``missed``: (record, the falls of its events, the model's, why, by how much), as
    sweep.fit.events.record_events gives them)."""
    if missed and verdict.status in (0, 5):
        verdict.status, verdict.events = 6, missed
    return verdict


MISSED = {
    "count": "the record slips {n} time(s) (falls {falls}), the best fit {n_model} ({model})",
    "place": "as many slips, but one {x:.0f} samples from the record's (falls {falls}; the best fit's {model})",
    "fall": "as many slips in place, but a fall {x:.3g} noise scales off the record's (falls {falls}; the best "
            "fit's {model})",
    "sample": "the same slips, one a sample or two off the record's (a residual of {x:.3g} noise scales at it; falls "
              "{falls})",
    "serial": "the same slips, but serially correlated residuals (lag-1 correlation {x:.3g}/sqrt(n), white noise's "
              "above 3/sqrt(n) once in ~1e3): a local minimum that describes the sawtooth another way",
}
"""What the warning says of each reason of sweep.fit.events.record_events for a record the best fit misses."""


def _missed(record: str, falls: list[float], model: list[float], why: str, x: float) -> str:
    stable = ": it slides through the sawtooth stably" if why == "count" and not model else ""
    return f"record {record!r}: " + MISSED[why].format(n=len(falls), n_model=len(model), falls=_falls(falls),
                                                         model=_falls(model), x=x) + stable


def _falls(falls: list[float]) -> str:
    return ", ".join(f"{f:.3g}" for f in falls[:4]) + (", ..." if len(falls) > 4 else "") if falls else "none"


def _names(items: list[str]) -> str:
    return ", ".join(items[:8]) + (f" and {len(items) - 8} more" if len(items) > 8 else "")


def summary(names: list[str], verdicts: list[Verdict], max_rounds: int) -> str | None:
    """One line naming the failed samples by cause, each cause with its advice; None when every fit is ok."""
    failed = [(n, v) for n, v in zip(names, verdicts) if v.failed]
    if not failed:
        return None
    parts = []
    by = {code: [(n, v) for n, v in failed if v.status == code] for code in (4, 3, 2, 1, 5, 6)}
    if by[4]:
        which = _names([f"{n} ({int(v.unsolved.sum())} of {v.unsolved.size} data)" for n, v in by[4]])
        parts.append(f"failed_solves: the model gives no number for some data at the best point ({which}), even "
                     f"though the search ranked such points last: no parameter set inside the bounds solves them "
                     f"(e.g. no finite relaxed slip where m2 = 0 and mu1 < 0); check the data's units, K_over_M and "
                     f"V, and the bounds; their standard errors, intervals and fitted values are NaN")
    if by[3]:
        parts.append(f"singular: infinite standard errors ({_names([n for n, _ in by[3]])}): the data do not "
                     f"determine every free parameter; fix one of them or add data at other K/M or V")
    if by[2]:
        which = _names([f"{n}: " + ", ".join(f"{p} = {x:.4g} at its {s} bound" for p, x, s in v.pushed)
                        for n, v in by[2]])
        parts.append(f"at_bound: the misfit would fall beyond a bound ({which}); widen those bounds (a parameter "
                     f"outside any plausible range points to a unit mistake in the data)")
    if by[1]:
        parts.append(f"not_converged: the least squares stopped after {max_rounds} rounds "
                     f"({_names([n for n, _ in by[1]])}); give a start nearer the data or narrower bounds")
    if by[5]:
        which = _names([f"{n}: chi^2 = {v.misfit[0]:.4g} for {v.misfit[1]} degrees of freedom" for n, v in by[5]])
        parts.append(f"poor_fit: with the noise given, the misfit is far above its degrees of freedom ({which}): no "
                     f"parameter set describes the data, or the noise given is too small; check the noise, the load "
                     f"history (steps) and whether a trend needs a detrend")
    if by[6]:
        which = _names([f"{n}: {_missed(*e)}" for n, v in by[6] for e in v.events])
        stable = any(why == "count" and not m for _, v in by[6] for _, _, m, why, _ in v.events)
        parts.append(f"events_missed: the model at the best fit misses the record's slip events ({which}), and an "
                     f"estimated noise absorbs the difference; start nearer the truth"
                     + (" (with k below (b - a)/Dc the model can slip)" if stable else "") + ", or give the noise")
    return (f"the fit failed for {len(failed)} of {len(verdicts)} sample(s) ({_names([n for n, _ in failed])}): "
            + "; ".join(parts) + " (fit_status in the output)")


def user_stacklevel() -> int:
    """The ``stacklevel`` of a warning issued by the caller that points at the first frame outside sweep/fit (the
    user's call of sweep.fit, however it was reached)."""
    here = os.path.dirname(os.path.abspath(__file__))
    frame, level = sys._getframe(1), 1
    while frame is not None and os.path.dirname(os.path.abspath(frame.f_code.co_filename)) == here:
        frame, level = frame.f_back, level + 1
    return level
