"""The Dataset of a fit (CF-1.11; docs/fit.md "Output"), and its netCDF file.

Dimensions: ``sample`` (one per problem: a sample's data sets sharing one parameter set), ``parameter`` and
``parameter_`` (the free parameters), ``profile_point``, ``grid_<name>`` (the global stage's level-1 grid of each
free parameter; none where the fit ran no global stage, ``search`` "local" in ``fit_settings``) and ``datum``
(every data value of every data set, in order).
"""

from __future__ import annotations

import datetime as _dt
import json
import os
from pathlib import Path

import numpy as np
import xarray as xr

from ..assemble.dataset import REFERENCES, versions
from .data import Curve
from .globalstage import grid_axes
from .levenberg import STATUS, STATUS_FLAGS
from .outcome import FitOutcome
from .space import UNITS
from .uncertainty import LABELS, NOT_COMPUTED
from .verdict import BOUND_FLAGS, FIT_STATUS

__all__ = ["build_fit_dataset", "save_fit", "LABEL_FLAGS"]

_LABELS = LABELS + (NOT_COMPUTED,)
LABEL_FLAGS = {"flag_values": np.arange(len(_LABELS), dtype=np.int8),
               "flag_meanings": " ".join(lab.replace(" ", "_") for lab in _LABELS)}
LONG = {"A": "direct-effect coefficient A (eq. 1)", "m1": "slope m1 of mu_d at V0 (eq. 6)",
        "m2": "curvature m2 of mu_d (eq. 6)", "D0": "memory length D0", "K_over_M_factor": "factor on the nominal K/M",
        # a record fit's (the laboratory's law, docs/physics.md 7b)
        "a": "direct effect a", "b": "evolution effect b", "Dc": "critical slip distance Dc",
        "mu0": "friction mu0 at V0", "k": "stiffness k = K/(M g)"}


def _v(dims, data, units: str | None, long_name: str, **attrs) -> xr.Variable:
    a = {"long_name": long_name, **attrs}
    if units is not None:
        a["units"] = units
    return xr.Variable(dims, data, a)


def _parameters(out: FitOutcome) -> dict[str, xr.Variable]:
    sp, nq = out.space, len(out.problems)
    v: dict[str, xr.Variable] = {}
    for j, name in enumerate(sp.names):
        u, ln = UNITS[name], LONG[name]
        v[name] = _v("sample", [f.theta[j] for f in out.fits], u, f"best fit of {ln}")
        v[f"{name}_stderr"] = _v("sample", [np.sqrt(c[j, j]) for c in out.covariances], u,
                                 f"standard error of {name} from the covariance (s^2 (J^T J)^-1)")
        if out.global_results is not None:  # (search "local": no global stage, the start is in fit_settings)
            v[f"{name}_global"] = _v("sample", [g.theta[j] for g in out.global_results], u,
                                     f"{name} at the best point of the global stage")
        v[f"{name}_at_bound"] = _v("sample", np.array([vd.bound[j] for vd in _verdicts(out)], np.int8), None,
                                   f"whether {name} rests on a bound", flag_values=np.arange(4, dtype=np.int8),
                                   flag_meanings=" ".join(BOUND_FLAGS[k] for k in range(4)),
                                   comment="pushed_against_bound: the misfit would fall beyond it (the fit failed: "
                                           "widen it); at_physical_limit: a limit of the model (m2 = 0), no failure")
        if out.intervals is None:
            continue
        v[f"{name}_lower"] = _v("sample", [iv[j].lower for iv in out.intervals], u,
                                f"lower end of the 95 % profile-likelihood interval of {name}")
        v[f"{name}_upper"] = _v("sample", [iv[j].upper for iv in out.intervals], u,
                                f"upper end of the 95 % profile-likelihood interval of {name}")
        v[f"{name}_label"] = _v("sample", np.array([_LABELS.index(lab[j]) for lab in out.labels], np.int8), None,
                                f"how well {name} is determined", **LABEL_FLAGS,
                                comment=f"poorly constrained: 95 % interval wider than +-{out.settings['poor']:g} x "
                                        f"|best|; not identifiable: the profile stays below the threshold up to a "
                                        f"bound; not computed: the fit failed its forward solves (fit_status)")
        n_pp = max(pf[j].values.size for pf in out.profiles)
        vals, delta = np.full((nq, n_pp), np.nan), np.full((nq, n_pp), np.nan)
        for q, pf in enumerate(out.profiles):
            n = pf[j].values.size
            vals[q, :n] = pf[j].values
            delta[q, :n] = (pf[j].rss - out.fits[q].rss) / out.s2[q]
        v[f"{name}_profile"] = _v(("sample", f"profile_point_{name}"), vals, u, f"profiled values of {name}")
        v[f"{name}_profile_misfit"] = _v(("sample", f"profile_point_{name}"), delta, "1",
                                         f"increase of the misfit over its minimum with {name} fixed and the other "
                                         f"free parameters optimised (units of the noise variance)",
                                         threshold_95=np.array(out.crit))
    p = sp.p
    cov = np.array(out.covariances).reshape(nq, p, p)
    with np.errstate(invalid="ignore", divide="ignore"):
        sd = np.sqrt(np.einsum("qii->qi", cov))
        corr = cov / sd[:, :, None] / sd[:, None, :]
    v["covariance"] = _v(("sample", "parameter", "parameter_"), cov, None,
                         "covariance of the free parameters, s^2 (J^T J)^-1",
                         comment="units: the product of the two parameters' units (D0 in m, the others 1)")
    v["correlation"] = _v(("sample", "parameter", "parameter_"), corr, "1", "correlation of the free parameters")
    return v


def _verdicts(out: FitOutcome):
    """The verdicts of ``out`` (every fit ok, nothing at a bound, where it has none: an outcome built by hand)."""
    if out.verdicts is not None:
        return out.verdicts
    from .verdict import Verdict

    return [Verdict(0, np.zeros(out.space.p, np.int8), np.zeros(pr.n_residuals, bool), []) for pr in out.problems]


def _per_sample(out: FitOutcome) -> dict[str, xr.Variable]:
    n = [pr.n_residuals for pr in out.problems]
    vd = _verdicts(out)
    solved = [not v.unsolved.any() for v in vd]
    return {
        "fit_status": _v("sample", np.array([v.status for v in vd], np.int8), None,
                         "whether the fit can be trusted (sweep.fit.verdict; 0: ok, any other: the fit failed)",
                         flag_values=np.array(sorted(FIT_STATUS), np.int8),
                         flag_meanings=" ".join(FIT_STATUS[k] for k in sorted(FIT_STATUS)),
                         comment="failed_solves: the model gives no number for some data at the best point; singular: "
                                 "infinite standard errors; at_bound: the misfit would fall beyond a bound; "
                                 "not_converged: the least squares ran out of rounds; poor_fit: with the noise "
                                 "given, the misfit is far above its degrees of freedom; events_missed: a record's "
                                 "slip events missed by the best fit (sweep.fit.verdict)"),
        "misfit": _v("sample", [f.rss / s if ok else np.nan for f, s, ok in zip(out.fits, out.s2, solved)], "1",
                     "sum of squared residuals over the noise variance at the best fit (chi^2; NaN: failed solves)"),
        "degrees_of_freedom": _v("sample", np.array(n) - out.space.p - trend_count(out.problems), "1",
                                 "data values minus free parameters (and minus one per detrended record: its trend "
                                 "slope, sweep.fit.records.Record.detrend)"),
        "noise": _v("sample", [np.sqrt(s) * pr.noise[0] if not pr.noise_given and ok else np.nan
                               for pr, s, ok in zip(out.problems, out.s2, solved)],
                    _data_unit(out), "noise estimated from the residuals, sqrt(RSS/degrees_of_freedom) (NaN: noise "
                    "given, or failed solves)"),
        "engine_error": _v("sample", out.engine_error, "1",
                          "bound on the engine's error in the model values of the best fit, in units of the noise "
                          "(largest over the sample's data)",
                          comment="the optimisations' forward solves carry no estimate; the best fit is solved once "
                                  "more with them: its estimate plus the difference from the values used "
                                  "(sweep.fit.core: negligible below ENGINE_ERROR_LIMIT = 0.01, a warning above)"),
        "function_evaluations": _v("sample", [f.nfev for f in out.fits], "1", "least-squares function evaluations"),
        "least_squares_status": _v("sample", np.array([f.status for f in out.fits], np.int8), None,
                                   "how the least squares stopped (sweep.fit.levenberg.STATUS; 0: not converged)",
                                   flag_values=np.array(sorted(STATUS), np.int8),
                                   flag_meanings=" ".join(STATUS_FLAGS[k] for k in sorted(STATUS))),
        "stable_before_stop": _v("sample", np.array([f.stable for f in out.fits], np.int8), None,
                                 "steady sliding stable before every stop at the best fit (chi > mu1, eq. 3)",
                                 flag_values=np.array([0, 1], np.int8), flag_meanings="no yes"),
    }


def _landscape(out: FitOutcome) -> tuple[dict[str, xr.Variable], dict[str, xr.Variable]]:
    """(the grid's coordinates, the misfit landscape over them); neither without a global stage (search "local")."""
    if out.global_results is None:
        return {}, {}
    sp = out.space
    axes = grid_axes(sp)
    coords = {f"grid_{n}": _v(f"grid_{n}", a, UNITS[n], f"global-stage grid of {n}") for n, a in zip(sp.names, axes)}
    land = np.array([g.landscape / s for g, s in zip(out.global_results, out.s2)])
    return coords, {"misfit_landscape": _v(("sample",) + tuple(coords), land, "1",
                                           "misfit (chi^2, noise variance of the best fit) over the global stage's "
                                           "grid (engine at global_rtol; NaN: stick-slip side of the Hopf line)")}


def _is_record_fit(out: FitOutcome) -> bool:
    """Whether the fit's data are laboratory records (friction mu(t), sweep.fit.records), not stop data (slips)."""
    return hasattr(out.problems[0].data[0], "mu")


def _data_unit(out: FitOutcome) -> str:
    """The unit of the data and their noise: 1 (friction) for records, m (slip) for stop data."""
    return "1" if _is_record_fit(out) else "m"


def _data(out: FitOutcome) -> dict[str, xr.Variable]:
    cols: dict[str, list] = {k: [] for k in ("t", "K_over_M", "V", "observed", "fitted", "residual", "noise")}
    names, counts, owner = [], [], []  # per data set: its name, its number of data, its sample
    for q, (pr, f, vd) in enumerate(zip(out.problems, out.fits, _verdicts(out))):
        noise = pr.noise * np.sqrt(out.s2[q])  # s2 = 1 where the noise is given
        fitted = np.where(vd.unsolved, np.nan, pr.observed + f.residuals / pr.weights)  # NaN: the model gave none
        cols["observed"].append(pr.observed)
        cols["fitted"].append(fitted)
        cols["residual"].append((fitted - pr.observed) / noise)
        cols["noise"].append(noise)
        factor = out.space.full(f.theta).get("K_over_M_factor", [1.0])[0]
        for d in pr.data:
            n = d.n
            names.append(d.name)
            counts.append(n)
            owner.append(q)
            if not hasattr(d, "K_over_M"):  # a record (sweep.fit.records): mu(t), no stop's K/M and V
                cols["t"].append(d.t)
                cols["K_over_M"].append(np.full(n, np.nan))
                cols["V"].append(np.full(n, np.nan))
            elif isinstance(d, Curve):
                cols["t"].append(d.t)
                cols["K_over_M"].append(np.full(n, d.K_over_M * factor))
                cols["V"].append(np.full(n, d.V))
            else:
                cols["t"].append(np.full(n, np.nan))
                cols["K_over_M"].append(d.K_over_M * factor)
                cols["V"].append(d.V)
    c = {k: np.concatenate(v) for k, v in cols.items()}
    c["sample"], c["set"] = np.repeat(owner, counts), np.repeat(np.array(names, dtype=str), counts)
    unit, record = _data_unit(out), _is_record_fit(out)
    return {
        "datum_sample": _v("datum", c["sample"].astype(np.int32), None, "index of the sample (problem) of the datum"),
        "datum_set": _v("datum", c["set"], None, "name of the data set of the datum"),
        "datum_t": _v("datum", c["t"], "s", "the record's time (its own clock)" if record else
                      "time after the stop (NaN: a relaxed slip)"),
        "datum_K_over_M": _v("datum", c["K_over_M"], "s-2", "K/M of the datum (times the fitted factor if free)"),
        "datum_V": _v("datum", c["V"], "m s-1", "driving velocity before the stop"),
        "observed": _v("datum", c["observed"], unit,
                       "measured friction mu(t)" if record else "measured slip x(t) or relaxed slip Dx_inf"),
        "fitted": _v("datum", c["fitted"], unit, "the model at the best fit (NaN: the model gave no number)"),
        "residual": _v("datum", c["residual"], "1", "(fitted - observed)/noise"),
        "datum_noise": _v("datum", c["noise"], unit, "noise of the datum (given, or estimated per sample)"),
    }


def trend_count(problems) -> np.ndarray:
    """Per problem, its records' trend slopes (one per detrended record): parameters fitted besides the free ones."""
    return np.array([sum(getattr(d, "detrend", None) is not None for d in pr.data) for pr in problems], dtype=int)


def trend_slopes(out: FitOutcome) -> list[list[float | None]]:
    """Per problem and data set, the slope c of a detrended record's linear trend at the best fit [1/s for
    detrend="time", 1/m for "displacement"; None: no trend]: the least-squares c = sum w^2 x (observed - m) /
    sum w^2 x^2 (sweep.fit.record_forward) with m the model without its trend, solved once more at the best fit."""
    slopes: list[list[float | None]] = [[None] * len(pr.data) for pr in out.problems]
    need = [q for q, c in enumerate(trend_count(out.problems)) if c]
    if not need:
        return slopes
    from dataclasses import replace

    from .problem import Problem
    from .record_forward import RecordStack

    plain = [Problem(out.problems[q].name, tuple(replace(d, detrend=None) for d in out.problems[q].data),
                     out.problems[q].space) for q in need]
    r = RecordStack(plain, float(out.settings["rtol"]), estimates=False).residuals(
        np.arange(len(need)), np.array([out.fits[q].theta for q in need])[:, None, :])[0][:, 0]
    for row, q in enumerate(need):  # r = (m - observed) w
        w, col = out.problems[q].weights, 0
        for i, d in enumerate(out.problems[q].data):
            part = slice(col, col + d.n)
            if d.detrend is not None:
                x = d.t - d.t[0] if d.detrend == "time" else d.displacement - d.displacement[0]
                slopes[q][i] = float(-np.sum(w[part] * x * r[row, part]) / np.sum((w[part] * x) ** 2))
            col += d.n
    return slopes


def _records(out: FitOutcome) -> dict[str, xr.Variable]:
    """Per record of a record fit (dimension ``record``): its sample and its detrend slope at the best fit."""
    if not _is_record_fit(out):
        return {}
    slopes = trend_slopes(out)
    names, owner, per_time, per_disp, kind = [], [], [], [], []
    for q, pr in enumerate(out.problems):
        for d, c in zip(pr.data, slopes[q]):
            names.append(d.name)
            owner.append(q)
            kind.append(d.detrend or "none")
            per_time.append(c if d.detrend == "time" else np.nan)
            per_disp.append(c if d.detrend == "displacement" else np.nan)
    counted = "fitted with the other parameters: counted in degrees_of_freedom and in the estimated noise"
    return {
        "record_name": _v("record", np.array(names, dtype=str), None, "name of the record (its datum_set)"),
        "record_sample": _v("record", np.array(owner, np.int32), None, "index of the sample (problem) of the record"),
        "record_detrend": _v("record", np.array(kind, dtype=str), None,
                             "the record's linear trend: none, time or displacement (sweep.fit.records.Record)"),
        "detrend_slope_time": _v("record", per_time, "s-1", "slope of the record's linear trend in time, c in "
                                 "mu = model + c (t - t0), at the best fit (NaN: no trend in time)", comment=counted),
        "detrend_slope_displacement": _v("record", per_disp, "m-1", "slope of the record's linear trend in load-point "
                                         "displacement, c in mu = model + c (x - x0), at the best fit (NaN: no trend "
                                         "in displacement)", comment=counted),
    }


def build_fit_dataset(out: FitOutcome, history: str = "sweep.fit") -> xr.Dataset:
    """The Dataset of a fit (module docstring)."""
    grid_coords, landscape = _landscape(out)
    coords = {"sample": _v("sample", np.array([pr.name for pr in out.problems], dtype=str), None,
                           "sample (data sets sharing one parameter set)"),
              "parameter": _v("parameter", np.array(out.space.names, dtype=str), None, "free parameter"),
              "parameter_": _v("parameter_", np.array(out.space.names, dtype=str), None, "free parameter"),
              **grid_coords}
    bounds = {n: [float(lo), float(hi)] for n, lo, hi in zip(out.space.names, out.space.lower, out.space.upper)}
    attrs = {
        "Conventions": "CF-1.11",
        "title": "Friction parameters fitted to laboratory friction records (rate and state, spring-slider)"
        if _is_record_fit(out) else "Friction parameters fitted to stop transients (Baumberger & Gauthier 1996 "
                                    "spring-block model)",
        "source": versions(), "references": REFERENCES,
        "history": f"{_dt.datetime.now(_dt.UTC).isoformat(timespec='seconds')}: {history}",
        "sweep_kind": "fit",
        "fit_settings": json.dumps({**out.settings, "bounds": bounds}),
        "fit_rounds": json.dumps(out.rounds), "fit_seconds": json.dumps({k: round(v, 3) for k, v in
                                                                          out.seconds.items()}),
        "comment": ("quasi-static load-history model from steady sliding, aging law (docs/physics.md 7b)" if
                    _is_record_fit(out) else "quasi-static stop model, aging law (docs/physics.md 3a)")
        + ("; least squares from the best point of a global grid" if out.global_results is not None else
           "; least squares from the given start, no global stage (search local: no misfit landscape)")
        + "; intervals from profile likelihoods",
    }
    data_vars = {**_parameters(out), **_per_sample(out), **landscape, **_data(out), **_records(out)}
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def save_fit(ds: xr.Dataset, path: str | os.PathLike, overwrite: bool = False) -> Path:
    """Write the fit's Dataset as netCDF4 (through sweep.write.netcdf.save: written beside, then renamed into place); an
    existing file is replaced only with ``overwrite``."""
    from ..write.netcdf import save

    return save(ds, path, overwrite=overwrite)
