"""Friction at requested times (observable ``mu_t`` of a history scene at its ``t_obs``; the forward model
sweep.protocols.history.forward): runs of the dense-output driver (sweep/integrate/history_dense.py) at local
tolerances rtol/TIGHTER and rtol/TIGHTER^2, the tighter run's mu with the difference to the looser as its error (as
the per-segment observables, sweep/protocols/history/engine.py, which then come from the same runs)."""

from __future__ import annotations

import numba
import numpy as np

from ...accuracy import TIGHTER
from ...status import Status

__all__ = ["read_samples", "run_sampled", "two_runs"]


def two_runs(k, a, b, A, mu_ref, state_law: str, s_kick, ratios, durations, scale, times, rtol: float,
             max_steps: int, estimates: bool = True, time_row=None, n_times=None) -> dict[str, np.ndarray]:
    """The dense-output driver run at rtol/TIGHTER and rtol/TIGHTER^2 for every set (k, a, b, A, mu_ref = mu_d(V),
    s_kick, scale = V/D0 [1/s] per set; ratios and physical durations [s] (sets, segments); sorted ``times`` [s]):
    ``mu_t`` = mu_ref + A s of the tighter run and ``mu_t_error`` (sets, times); ``status`` (ok, max_steps,
    step_underflow, or error_above_tol where an error exceeds rtol (|mu| + A)) and ``steps`` per set. Without
    ``estimates`` the tighter run alone (the same ``mu_t``; ``mu_t_error`` NaN, no error_above_tol). With
    ``time_row`` and ``n_times``, ``times`` is a table whose row time_row[i] holds set i's times, n_times[i] of them
    (several records' sets in one call; the rows of the results NaN beyond)."""
    from ...integrate.history_dense import history_dense_batch, history_dense_rows
    from ...integrate.models.history import LAW_CODES

    n, m, times = k.size, ratios.shape[1], np.ascontiguousarray(times, dtype=float)
    own = () if time_row is None else tuple(np.ascontiguousarray(x, np.int64) for x in (time_row, n_times))
    runs = []
    for e in (1, 2) if estimates else (2,):
        s_out = np.empty((n, times.shape[-1])) if time_row is None else np.full((n, times.shape[-1]), np.nan)
        status, steps = np.zeros(n, np.int8), np.zeros(n, np.int64)
        records = [np.empty((n, m)) for _ in range(3)]  # not read here
        (history_dense_rows if own else history_dense_batch)(
            k, a, b, LAW_CODES[state_law], s_kick, ratios, durations, scale, times, *own, rtol / TIGHTER**e,
            int(max_steps), *records, np.zeros((n, m), np.int8), s_out, status, steps)
        runs.append((s_out, status, steps))
    (s_loose, st_loose, n_loose), (s_tight, st_tight, n_tight) = runs[0], runs[-1]
    return read_samples(s_loose, s_tight, st_loose, st_tight, A, mu_ref, rtol,
                        n_tight + (n_loose if estimates else 0), estimates)


@numba.njit(cache=True, nogil=True)
def _read_off(s_loose, s_tight, A, mu_ref, rtol, mu, error, above):  # pragma: no cover (compiled)
    """mu = mu_ref + A s_tight, error = |A (s_tight - s_loose)| (inf where only the looser is NaN), above[i]:
    some error of set i exceeds rtol (|mu| + A) (NaNs compare false): one pass (numpy took ~10 over the global
    stage's sets x samples, ~4 ms of a record fit's grid)."""
    for i in range(mu.shape[0]):
        flag = False
        for j in range(mu.shape[1]):
            m = mu_ref[i] + A[i] * s_tight[i, j]
            e = abs(A[i] * (s_tight[i, j] - s_loose[i, j]))
            if np.isnan(e) and np.isfinite(m):
                e = np.inf  # the looser run failed there: no estimate
            mu[i, j] = m
            error[i, j] = e
            if e > rtol * (abs(m) + A[i]):
                flag = True
        above[i] = flag


def read_samples(s_loose, s_tight, st_loose, st_tight, A, mu_ref, rtol: float, steps, estimates: bool = True
                 ) -> dict[str, np.ndarray]:
    """mu_t, mu_t_error (sets, times), status and steps from the s samples of a looser and a tighter run (any driver)
    and their statuses: mu = mu_ref + A s of the tighter run, the error the difference to the looser (inf where
    only the looser failed), error_above_tol where an error exceeds rtol (|mu| + A). Without ``estimates`` (the
    looser run not made: pass the tighter twice) the error is NaN and the status the tighter run's."""
    s_loose, s_tight = np.asarray(s_loose, dtype=float), np.asarray(s_tight, dtype=float)
    mu, error, above = np.empty(s_tight.shape), np.empty(s_tight.shape), np.empty(s_tight.shape[0], np.bool_)
    # copies, not views: a broadcast (read-only) view into a compiled function is a numba FutureWarning
    _read_off(s_loose, s_tight, np.array(A, dtype=float), np.array(mu_ref, dtype=float), float(rtol), mu, error,
              above)
    if not estimates:
        error[:] = np.nan
        return {"mu_t": mu, "mu_t_error": error, "status": np.asarray(st_tight, np.int8), "steps": steps}
    status = np.where(st_tight != Status.OK, st_tight, st_loose).astype(np.int8)
    status[(status == Status.OK) & above] = Status.ERROR_ABOVE_TOL
    return {"mu_t": mu, "mu_t_error": error, "status": status, "steps": steps}


def run_sampled(plan, points: np.ndarray, tol: float) -> dict[str, np.ndarray]:
    """One quasi-static run at the local tolerance ``tol`` for the ``points`` of a history plan
    (sweep.protocols.history.engine.HistoryPlan) that asks for mu_t: the per-segment records s_start, s_end,
    s_peak, steady (points, segments) of the dense-output driver (the same steps as the records' driver) and s_t,
    s at t_obs (points, times); status, steps."""
    from ...integrate.history_dense import history_dense_batch
    from ...integrate.models.history import LAW_CODES

    n, m = points.size, plan.durations.shape[1]
    rec = {name: np.full((n, m), np.nan) for name in ("s_start", "s_end", "s_peak")}
    rec["steady"] = np.zeros((n, m), np.int8)
    rec["s_t"] = np.full((n, plan.t_obs.size), np.nan)
    status, steps = np.zeros(n, np.int8), np.zeros(n, np.int64)
    scale = np.ascontiguousarray(plan.scale[points])
    ratios = plan.ratios[points] if plan.ratios.ndim == 2 else plan.ratios
    ratios = np.ascontiguousarray(np.broadcast_to(ratios, (n, m)), dtype=float)
    k = plan.k[points]
    history_dense_batch(k, plan.a[points], plan.b[points], LAW_CODES[plan.state_law], k * plan.perturbation, ratios,
                        np.ascontiguousarray(plan.durations[points] / scale[:, None]), scale,
                        np.ascontiguousarray(plan.t_obs, dtype=float), tol, plan.max_steps, rec["s_start"],
                        rec["s_end"], rec["s_peak"], rec["steady"], rec["s_t"], status, steps)
    return {**rec, "status": status, "steps": steps}
