"""The inertial points of a history scene: one run of the inertial driver (sweep/integrate/history_inertial.py, aging
law) per point and tolerance, with the same per-segment records as the quasi-static driver and s at t_obs; and the
per-point model choice (docs/physics.md 7b)."""

from __future__ import annotations

import numpy as np

__all__ = ["inertial_points", "inertial_samples", "run_inertial"]


def inertial_points(model: str, G: np.ndarray, ratios: np.ndarray, model_tol: float) -> np.ndarray:
    """Which points run with inertia: all for model "inertial", none for "quasistatic", and for "auto" those where
    some segment's gamma/A = G r_j^2 (gamma at the segment's velocity r_j V) exceeds ``model_tol``. ``G``: gamma/A
    at the grid's V per point; ``ratios`` (points, segments)."""
    if model == "inertial":
        return np.ones(G.size, bool)
    if model == "quasistatic":
        return np.zeros(G.size, bool)
    return G * np.max(np.atleast_2d(ratios), axis=1) ** 2 > model_tol


def run_inertial(plan, points: np.ndarray, tol: float) -> dict[str, np.ndarray]:
    """One inertial run at the local tolerance ``tol`` for the ``points`` of a history plan
    (sweep.protocols.history.engine.HistoryPlan): s_start, s_end, s_peak, steady (points, segments); s_t (points,
    t_obs); status, steps."""
    from ...integrate.history_inertial import history_inertial_batch

    n, m = points.size, plan.durations.shape[1]
    rec = {name: np.full((n, m), np.nan) for name in ("s_start", "s_end", "s_peak")}
    rec["steady"] = np.zeros((n, m), np.int8)
    rec["s_t"] = np.full((n, plan.t_obs.size), np.nan)
    status, steps = np.zeros(n, np.int8), np.zeros(n, np.int64)
    k = plan.k[points]
    ratios = np.ascontiguousarray(np.broadcast_to(plan.ratios[points] if plan.ratios.ndim == 2 else plan.ratios,
                                                  (n, m)), dtype=float)
    history_inertial_batch(k, plan.a[points], plan.b[points], plan.G[points], k * plan.perturbation, ratios,
                           np.ascontiguousarray(plan.durations[points]), np.ascontiguousarray(plan.scale[points]),
                           np.ascontiguousarray(plan.t_obs, dtype=float), tol, plan.max_steps, rec["s_start"],
                           rec["s_end"], rec["s_peak"], rec["steady"], rec["s_t"], status, steps)
    return {**rec, "status": status, "steps": steps}


def inertial_samples(k, a, b, G, s_kick, ratios, durations, scale, times, tol: float, max_steps: int
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """s at the sorted physical ``times`` [s] of one inertial run per set (k, a, b, G = gamma/A at the reference
    velocity V, s_kick, scale = V/D0 per set; ratios and reduced durations (sets, segments)) at the local tolerance
    ``tol``: (s (sets, times), status, steps)."""
    from ...integrate.history_inertial import history_inertial_batch

    n, m = k.size, ratios.shape[1]
    rec = [np.full((n, m), np.nan) for _ in range(3)]
    s_out = np.full((n, times.size), np.nan)
    status, steps = np.zeros(n, np.int8), np.zeros(n, np.int64)
    history_inertial_batch(k, a, b, G, s_kick, ratios, durations, scale, np.ascontiguousarray(times, dtype=float),
                           tol, int(max_steps), *rec, np.zeros((n, m), np.int8), s_out, status, steps)
    return s_out, status, steps

