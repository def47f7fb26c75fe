"""Friction at requested times of a history scene (observable ``mu_t`` at the scene's ``t_obs``): per point two runs
of the dense-output driver (sweep/integrate/history_dense.py) at local tolerances rtol/TIGHTER and rtol/TIGHTER^2,
the tighter run's mu with the difference to the looser as its error (as the per-segment observables,
sweep/protocols/history/engine.py)."""

from __future__ import annotations

import numpy as np

from ...accuracy import TIGHTER
from ...status import Status

__all__ = ["friction_samples", "read_samples", "two_runs"]


def two_runs(k, a, b, A, mu_ref, state_law: str, s_kick, ratios, durations, scale, times, rtol: float,
             max_steps: int) -> dict[str, np.ndarray]:
    """The dense-output driver run at rtol/TIGHTER and rtol/TIGHTER^2 for every set (k, a, b, A, mu_ref = mu_d(V),
    s_kick, scale = V/D0 [1/s] per set; ratios and physical durations [s] (sets, segments); sorted ``times`` [s]):
    ``mu_t`` = mu_ref + A s of the tighter run and ``mu_t_error`` (sets, times); ``status`` (ok, max_steps,
    step_underflow, or error_above_tol where an error exceeds rtol (|mu| + A)) and ``steps`` per set."""
    from ...integrate.history_dense import history_dense_batch
    from ...integrate.models.history import LAW_CODES

    n, times = k.size, np.ascontiguousarray(times, dtype=float)
    runs = []
    for e in (1, 2):
        s_out = np.empty((n, times.size))
        status, steps = np.zeros(n, np.int8), np.zeros(n, np.int64)
        history_dense_batch(k, a, b, LAW_CODES[state_law], s_kick, ratios, durations, scale, times,
                            rtol / TIGHTER**e, int(max_steps), s_out, status, steps)
        runs.append((s_out, status, steps))
    (s_loose, st_loose, n_loose), (s_tight, st_tight, n_tight) = runs
    return read_samples(s_loose, s_tight, st_loose, st_tight, A, mu_ref, rtol, n_loose + n_tight)


def read_samples(s_loose, s_tight, st_loose, st_tight, A, mu_ref, rtol: float, steps) -> dict[str, np.ndarray]:
    """mu_t, mu_t_error (sets, times), status and steps from the s samples of a looser and a tighter run (any driver)
    and their statuses: mu = mu_ref + A s of the tighter run, the error the difference to the looser (inf where
    only the looser failed), error_above_tol where an error exceeds rtol (|mu| + A)."""
    mu = mu_ref[:, None] + A[:, None] * s_tight
    error = np.abs(A[:, None] * (s_tight - s_loose))
    error[np.isnan(error) & np.isfinite(mu)] = np.inf  # the looser run failed there: no estimate
    status = np.where(st_tight != Status.OK, st_tight, st_loose).astype(np.int8)
    with np.errstate(invalid="ignore"):
        above = np.any(error > rtol * (np.abs(mu) + A[:, None]), axis=1)
    status[(status == Status.OK) & above] = Status.ERROR_ABOVE_TOL
    return {"mu_t": mu, "mu_t_error": error, "status": status, "steps": steps}


def friction_samples(plan, points: np.ndarray, scale: np.ndarray, t_obs: np.ndarray) -> dict[str, np.ndarray]:
    """:func:`two_runs` for the ``points`` of a history scene's plan (sweep.protocols.history.engine.HistoryPlan;
    ``scale`` = V/D0 [1/s] per point) at the times ``t_obs`` [s] from the history's start (sorted): NaN past a
    point's history end."""
    n, n_seg = points.size, plan.durations.shape[1]
    ratios = plan.ratios[points] if plan.ratios.ndim == 2 else plan.ratios
    ratios = np.ascontiguousarray(np.broadcast_to(ratios, (n, n_seg)), dtype=float)
    durations = np.ascontiguousarray(plan.durations[points] / scale[:, None])  # physical [s]
    k = plan.k[points]
    return two_runs(k, plan.a[points], plan.b[points], plan.A[points], plan.mu_ref[points], plan.state_law,
                    k * plan.perturbation, ratios, durations, np.ascontiguousarray(scale, dtype=float), t_obs,
                    plan.rtol, plan.max_steps)
