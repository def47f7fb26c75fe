"""sweep.fit(...): fit the friction parameters to relaxation curves and relaxed slips, with their uncertainty.

Stages (docs/fit.md), each run over every problem at once (a sample's data sets sharing one parameter set;
sweep.fit.stack merges their engine runs, sweep.fit.levenberg iterates every task in lockstep):

1. checks before any work (sweep.fit.data, .space, .problem, .checks);
2. global stage (``search="global"``, the default): a coarse sweep of the free parameters over their bounds
   (sweep.fit.globalstage), engine at ``global_rtol``; with ``search="local"`` none: the least squares start from
   the given start (``params`` and ``start``), and nothing protects them from a local minimum;
3. least squares from the best grid point, or from the start (sweep.fit.local), engine at ``rtol``;
4. covariance from the Jacobian, profile likelihoods, 95 % intervals and labels (sweep.fit.profiles,
   sweep.fit.uncertainty);
5. a verdict per sample (sweep.fit.verdict): ``fit_status`` ok, or why the fit failed (failed forward solves at the
   best point, infinite standard errors, a bound the data push against, no convergence, with the noise given a
   misfit far above its degrees of freedom, a record's slip events missed by the best fit), with one warning line per
   call (a PlausibilityWarning) naming the failed samples and the advice that matches the cause.

The optimisations' forward solves carry no error estimate (the engine's fine twins cost ~0.6x more, and an
optimisation only needs values far more accurate than the noise): the best fits are solved once more with their
estimates, and ``engine_error`` reports the largest, in units of the noise, with a warning above ENGINE_ERROR_LIMIT.
"""

from __future__ import annotations

import contextlib
import difflib
import logging
import time
import warnings
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import xarray as xr

from ..errors import InputError
from ..run.compile_notice import announce_if_cold, compiled_aside
from ..scene.params import FrictionParams
from ..scene.plausibility import PlausibilityWarning
from ..scene.presets import presets
from . import local
from .checks import check_problems
from .data import Data
from .globalstage import grid_sets, search_all
from .local import refine_all
from .outcome import FitOutcome
from .problem import MODEL_FAILED, make_problems
from .profiles import profile_all
from .result import build_fit_dataset, trend_count
from .space import make_space
from .stack import ProblemStack
from .uncertainty import NOT_COMPUTED, Interval, covariance, interval, label, noise_variance, threshold
from .verdict import judge, missed_events, summary, user_stacklevel

__all__ = ["fit", "run_fit"]

log = logging.getLogger("sweep")

RTOL_RANGE = (1e-10, 1e-4)
SEARCHES = {"global": "a coarse grid over the bounds first, the least squares from its best point",
            "local": "the least squares from the given start alone (no grid: no protection from local minima)"}
"""The values of ``search`` (sweep.fit, the TOML key ``search``, ``sweep fit --search``) and what each runs."""
ENGINE_ERROR_LIMIT = 0.01
"""Largest engine error at a best fit, in units of the data's noise, below which it is negligible (it shifts the
misfit by ~2e-2 of one unit of chi^2 on 200 samples at most); above it the fit warns (a smaller ``rtol`` helps)."""


def _params(params: FrictionParams | str) -> FrictionParams:
    if isinstance(params, str):
        if params not in presets:
            close = difflib.get_close_matches(params, sorted(presets), n=1)
            raise InputError(f"params must be a sweep.FrictionParams or a preset name {sorted(presets)}, got "
                             f"{params!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
        return presets[params]
    return params


def _rtol(name: str, value: float) -> float:
    v = float(value)
    if not RTOL_RANGE[0] <= v <= RTOL_RANGE[1]:
        raise InputError(f"{name} must be in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}] (engine accuracy, far below "
                         f"the data's noise), got {value!r}")
    return v


def _search(value: str) -> str:
    if not (isinstance(value, str) and value in SEARCHES):
        raise InputError(f"search must be one of {', '.join(repr(k) for k in SEARCHES)} ("
                         + "; ".join(f"{k}: {v}" for k, v in SEARCHES.items()) + f"), got {value!r}")
    return value


def run_fit(data: Data | Sequence[Data], free: Sequence[str] = ("A", "m1", "m2"),
            params: FrictionParams | str = "sample2", bounds: Mapping[str, Sequence[float]] | None = None,
            start: Mapping[str, float] | None = None, per_data_set: bool = False, poor: float = 0.25,
            rtol: float = 1e-6, global_rtol: float = 1e-4, profiles: bool = True,
            progress: Callable[[str], None] | None = None, search: str = "global", g: float | None = None
            ) -> FitOutcome:
    """The stages of :func:`fit`, returning the raw :class:`FitOutcome`."""
    say = progress or log.info
    search = _search(search)
    records = _records(data)
    if records:  # the third kind of data: its own space and forward model (sweep.fit.record_forward)
        from .record_forward import (
            RECORD_FREE,
            RecordStack,
            inertia_report,
            make_record_space,
            record_k,
            with_machine_g,
        )

        if tuple(free) == ("A", "m1", "m2"):  # the default of stop data: a record fit's is a, b, Dc
            free = ("a", "b", "Dc")
        data = with_machine_g(data, g, _params(params))
        records = _records(data)
        space = make_record_space(free, _params(params), record_k(records), bounds, start)
    elif g is not None:
        raise InputError(f"g (a machine's N/M [m/s^2]) applies to laboratory records only, got g = {g!r} for "
                         f"relaxation curves or relaxed slips (give their g in params)")
    else:
        space = make_space(free, _params(params), bounds, start)
    problems = make_problems(data, space, per_data_set)
    rtol, global_rtol = _rtol("rtol", rtol), _rtol("global_rtol", global_rtol)
    if not (isinstance(poor, (int, float)) and 0 < poor):
        raise InputError(f"poor must be > 0 (relative half-width of a 95 % interval above which a parameter is "
                         f"poorly constrained), got {poor!r}")
    if not records:
        check_problems(problems)
    # the forward model's kernels (the sampled lanes; the per-point path for parameter sets without a finite relaxed
    # slip): on a machine without numba's cache, ~1 min of compiling before the first round, said at once
    if not records:
        announce_if_cold(families=["time-resolved lanes", "time-resolved stop"])
    rounds, seconds = {}, {}
    t0 = time.perf_counter()
    stack = (RecordStack if records else ProblemStack)(problems, global_rtol, estimates=False)
    globals_ = None
    if search == "global":
        say(f"global stage: {len(problems)} problem(s), {len(grid_sets(space, stack.offset))} parameter sets each")
        # a cold cache: the per-point path (the grid's sets without a finite relaxed slip) compiles in a second
        # process while this one compiles the sampled lanes (~45 s and ~18 s on 2 cores, one after the other)
        aside = "" if records else (f"from sweep.fit.forward import warm_up_per_point; "
                                    f"warm_up_per_point({global_rtol!r}, {rtol!r})")
        with compiled_aside(aside) if aside else contextlib.nullcontext():
            globals_ = search_all(stack)
        rounds["global"], seconds["global"] = stack.rounds, time.perf_counter() - t0
        say(f"least squares from the best grid points ({time.perf_counter() - t0:.1f} s so far)")
    else:
        say(f"least squares of {len(problems)} problem(s) from the start (search = local: no global stage)")
    t1 = time.perf_counter()
    stack = stack.with_settings(rtol, estimates=False)
    theta0 = [g.theta for g in globals_] if globals_ else [space.start] * len(problems)
    if records:  # a stick-slip record's starts in the basin of its slip events (sweep.fit.event_fit)
        from .event_fit import event_start

        theta0 = event_start(stack, theta0, space.start if globals_ else None)
    fits = refine_all(stack, theta0)
    rounds["least_squares"], seconds["least_squares"] = stack.rounds, time.perf_counter() - t1
    unsolved = [f.residuals == MODEL_FAILED if f.failures else np.zeros(f.residuals.size, bool) for f in fits]
    check = stack.with_settings(rtol, estimates=True)
    engine_error = _check_engine_error(check, fits, progress, [u.any() for u in unsolved])
    inertia = {}
    if records:  # what each record's inertia was (sweep.fit.record_forward), said in fit_settings
        inertia, line = inertia_report(problems, check.inertial, space)
        if line is not None:
            warnings.warn(line, PlausibilityWarning, stacklevel=user_stacklevel())

    # the noise variance over the data the model solved (all of them but where a fit failed its solves)
    # a detrended record's trend slope is fitted too (sweep.fit.record_forward): one parameter more per such record
    n_par = space.p + trend_count(problems)
    s2 = [noise_variance(f.rss, pr.n_residuals, p, pr.noise_given) if not u.any() else
          _solved_noise_variance(f.residuals[~u], p, pr.noise_given)
          for pr, f, u, p in zip(problems, fits, unsolved, n_par)]
    covs = [covariance(f.jac, s) if not u.any() else np.full((space.p, space.p), np.nan)
            for f, s, u in zip(fits, s2, unsolved)]
    verdicts = [judge(f, c, s, space, MODEL_FAILED, pr.n_residuals - p if pr.noise_given else None)
                for f, c, s, pr, p in zip(fits, covs, s2, problems, n_par)]
    if records:  # a sawtooth's slip events missed by the best fit (a stable model through it: issue 34)
        from .events import record_events

        verdicts = [missed_events(v, record_events(pr.data, f.residuals, pr.weights)) if not u.any() else v
                    for v, pr, f, u in zip(verdicts, problems, fits, unsolved)]
    crit = [threshold(pr.noise_given, pr.n_residuals - p) for pr, p in zip(problems, n_par)]
    profs = ivs = labels = None
    if profiles:
        say(f"profile likelihoods of {space.p} parameter(s) x {len(problems)} problem(s) "
            f"({time.perf_counter() - t0:.1f} s so far)")
        t2 = time.perf_counter()
        stack.rounds = 0
        s2_profiles = [1.0 if u.any() else s for s, u in zip(s2, unsolved)]  # (a failed fit's profile is dropped)
        profs = profile_all(problems, [f.theta for f in fits], [f.rss for f in fits], covs, s2_profiles, crit, stack,
                            [f.jac for f in fits])
        rounds["profiles"], seconds["profiles"] = stack.rounds, time.perf_counter() - t2
        ivs, labels = [], []
        for q, f in enumerate(fits):
            if unsolved[q].any():  # no profile of a fit that failed its solves
                profs[q] = [type(pf)(pf.values, np.full(pf.rss.shape, np.nan)) for pf in profs[q]]
                ivs.append([Interval(np.nan, np.nan, False, False) for _ in range(space.p)])
                labels.append([NOT_COMPUTED] * space.p)
                continue
            row = [interval(f.theta[j], pf.values, (pf.rss - f.rss) / s2[q], crit[q]) for j, pf in enumerate(profs[q])]
            ivs.append(row)
            labels.append([label(f.theta[j], iv, poor) for j, iv in enumerate(row)])
    say(f"fit done in {time.perf_counter() - t0:.1f} s")
    line = summary([pr.name for pr in problems], verdicts, local.FIT.max_rounds)
    if line is not None:
        warnings.warn(line, PlausibilityWarning, stacklevel=user_stacklevel())
    settings = {"free": list(space.names), "search": search, "start": dict(zip(space.names, map(float, space.start))),
                "rtol": rtol, "global_rtol": global_rtol, "poor": poor,
                "per_data_set": bool(per_data_set), "params": _params(params).as_dict(),
                **({"kind": "records", "fixed": {n: space.values[n] for n in RECORD_FREE}, **inertia} if records
                   else {})}
    return FitOutcome(problems, space, globals_, fits, s2, covs, crit, profs, ivs, labels, rounds, seconds, settings,
                      engine_error, verdicts)


def _records(data) -> list:
    """The data's records (sweep.fit.records.Record), [] for stop data."""
    from .records import Record

    items = [data] if not isinstance(data, (list, tuple)) else list(data)
    return [d for d in items if isinstance(d, Record)]


def _solved_noise_variance(solved: np.ndarray, p: int, noise_given: bool) -> float:
    """The noise variance of a fit that failed some solves, from the residuals it solved (NaN where they are too few
    to estimate it from: the misfit map and the residuals of the output are then NaN)."""
    if noise_given:
        return 1.0
    return float(np.sum(solved ** 2)) / (solved.size - p) if solved.size > p else float("nan")


def _check_engine_error(check: ProblemStack, fits, progress: Callable[[str], None] | None,
                        failed: list[bool] | None = None) -> np.ndarray:
    """A bound on the engine's error in the model values each best fit used, in units of the noise: one more
    forward solve each, with estimates, and the difference from the values used (ProblemStack.engine_errors); a
    warning (the "sweep" logger, and ``progress``) where it exceeds ENGINE_ERROR_LIMIT, advising a smaller rtol, or
    where a fit that solved all its data got no estimate. ``failed``: per fit, whether the model gave no number for
    some of its data at the best fit (NaN there; the fit's verdict says so, sweep.fit.verdict: no rtol helps)."""
    failed = failed or [False] * len(fits)
    used = np.zeros((len(fits), check.n_max))  # the residuals the fit used (no estimates), padded
    for q, f in enumerate(fits):
        used[q, :f.residuals.size] = f.residuals
    err = check.engine_errors(np.arange(len(check.problems)), np.array([f.theta for f in fits]), used)
    err[np.array(failed, bool)] = np.nan
    over = [pr.name for pr, e in zip(check.problems, err) if e > ENGINE_ERROR_LIMIT]
    none = [pr.name for pr, e, bad in zip(check.problems, err, failed) if np.isnan(e) and not bad]
    parts = []
    if over:
        parts.append(f"the engine's error at the best fit exceeds {ENGINE_ERROR_LIMIT:g} of the noise for "
                     f"{len(over)} sample(s) ({', '.join(over[:5])}{', ...' if len(over) > 5 else ''}): largest "
                     f"{np.nanmax(err):.3g}; fit again with a smaller rtol (now {check.rtol:g})")
    if none:
        parts.append(f"the engine gave no error estimate at the best fit of {len(none)} sample(s) "
                     f"({', '.join(none[:5])}{', ...' if len(none) > 5 else ''}): a solve with estimates failed "
                     f"where the one without succeeded; their engine_error is NaN")
    if parts:
        msg = "; ".join(parts)
        log.warning(msg)
        if progress is not None:
            progress(msg)
    return err


def fit(data: Data | Sequence[Data], free: Sequence[str] = ("A", "m1", "m2"),
        params: FrictionParams | str = "sample2", bounds: Mapping[str, Sequence[float]] | None = None,
        start: Mapping[str, float] | None = None, per_data_set: bool = False, poor: float = 0.25,
        rtol: float = 1e-6, global_rtol: float = 1e-4, profiles: bool = True,
        progress: Callable[[str], None] | None = None, history: str = "sweep.fit", search: str = "global",
        g: float | None = None) -> xr.Dataset:
    """Fit the friction parameters to measured stop data; returns a Dataset (docs/fit.md, "Output").

    Parameters
    ----------
    data : Curve | RelaxedSlips | sequence of them
        Relaxation curves x(t) [m] vs t [s] at known K/M [s-2] and V [m s-1], relaxed slips Dx_inf [m] at
        (K/M, V) (sweep.fit.data); each names its ``sample``.
    free : names from ("A", "m1", "m2", "D0", "K_over_M_factor")
        The parameters to fit (eqs. 1, 2, 6; K_over_M_factor multiplies every nominal K/M of a sample).
    params : FrictionParams or preset name
        Values of the fixed parameters and starting values of the free ones (V0 [m s-1] and g [m s-2] too).
    bounds : {name: (lower, upper)}
        Bounds of free parameters (default :func:`sweep.fit.space.default_bounds`); the start must lie inside.
    start : {name: value}
        Starting values overriding ``params``.
    per_data_set : bool
        False: data sets with the same ``sample`` share one parameter set. True: each data set gets its own (a
        campaign of many samples in one call: all their engine runs are merged).
    poor : float
        A parameter is "poorly constrained" where its 95 % interval reaches further than poor x |best| from the
        best value (default 0.25, i.e. +-25 %).
    rtol, global_rtol : float
        Engine accuracy of the least-squares and profile stages (default 1e-6) and of the global stage (1e-4);
        both must lie far below the data's relative noise (1e-10..1e-4).
    profiles : bool
        Compute the profile likelihoods, 95 % intervals and labels (default True).
    progress : callable(str)
        Receives a line per stage (default: the "sweep" logger at INFO).
    search : "global" or "local"
        "global" (default): a coarse grid of the free parameters over their bounds first, the least squares from
        its best point (a start anywhere in the bounds will do). "local": the least squares from the start
        (``params``, ``start``) alone, without the grid: for many records of one material from a known start, or a
        refit; nothing then guards against a local minimum (the verdicts still say where a fit is poor: with the
        noise given, poor_fit). The Dataset's ``fit_settings`` name the search; a local fit has no
        ``misfit_landscape`` and no ``P_global``.
    g : float
        Laboratory records only: the machine's inertia g = N/M [m s-2] (normal load over moving mass; k = K/(M g) =
        K/N) of the records that do not give their own (``Record.g``). Default: ``params``' g where it is not
        FrictionParams' 9.81, else none: such records are modelled quasi-statically, with inertia (at params' g)
        only where the quasi-static run breaks down (stick-slip), and a warning where that decides the best fit
        (docs/fit.md, "The machine's inertia"); ``fit_settings`` say what each record got.
    """
    return build_fit_dataset(run_fit(data, free, params, bounds, start, per_data_set, poor, rtol, global_rtol,
                                     profiles, progress, search=search, g=g), history=history)
