"""The output schema of the history protocol: per point and segment the friction at the segment's end, the
steady-state jump, the peak after a hold and the relaxation during a hold, each with its error estimate; the status,
steps and model per point; the segments as coordinates."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ...assemble.dataset import global_attrs, grid_coords, variable
from ...scene.scene import Scene
from ...status import MODEL_FLAG, flag_attrs
from .engine import OBSERVABLES
from .healing import is_series

__all__ = ["history_attributes", "history_coords", "history_variables"]

NAMES = {
    "mu_end": "friction coefficient at the end of the segment",
    "delta_mu_ss": "steady-state friction jump mu_ss(V_j) - mu_ss(V_j-1) (NaN unless both segments end in steady "
                   "sliding)",
    "delta_mu_peak": "peak friction on reslide after a hold above the steady friction at the reslide velocity "
                     "(NaN: not a reslide after a hold)",
    "delta_mu_relax": "friction relaxation during the hold, mu at its start - mu at its end (NaN: not a hold)",
}


def history_variables(scene: Scene, out: dict[str, np.ndarray]) -> dict[str, xr.Variable]:
    """The data variables over the grid of ``scene`` (a run's chunk: its block) from flat outputs in the grid's C
    order (per segment: (points, segments))."""
    dims, seg_dims = scene.dims, (*scene.dims, "segment")
    n_seg = len(scene.options.segments)
    grid = lambda a: a.reshape(scene.shape)  # noqa: E731
    per_seg = lambda a: a.reshape((*scene.shape, n_seg))  # noqa: E731
    data = {"status": variable(dims, grid(out["status"]), "1", "numerical status of the point", **flag_attrs()),
            "steps": variable(dims, grid(out["steps"]), "1", "accepted and rejected steps of the point (both runs)"),
            "model": variable(dims, grid(out["model"]), "1", "model used for the point", **MODEL_FLAG)}
    for name in OBSERVABLES:
        if name in scene.observables:
            data[name] = variable(seg_dims, per_seg(out[name]), "1", NAMES[name],
                                  ancillary_variables=f"{name}_error")
            data[f"{name}_error"] = variable(seg_dims, per_seg(out[f"{name}_error"]), "1",
                                             f"estimated absolute numerical error of {name} (pair of tolerances)")
    if "delta_mu_peak" in scene.observables and is_series(scene.options.segments):  # healing.py
        data["beta"] = variable(dims, grid(out["beta"]), "1", "healing rate d delta_mu_peak / d log10 t_hold (least "
                                "squares over the point's holds)", ancillary_variables="beta_error")
        data["beta_error"] = variable(dims, grid(out["beta_error"]), "1", "estimated absolute numerical error of "
                                      "beta (from delta_mu_peak_error)")
    if "mu_t" in scene.observables:  # mu at the times t_obs (sweep/protocols/history/sampled.py)
        per_t = lambda a: a.reshape((*scene.shape, len(scene.options.t_obs)))  # noqa: E731
        data["mu_t"] = variable((*dims, "t_obs"), per_t(out["mu_t"]), "1", "friction coefficient at the time t_obs "
                                "(NaN past the point's history)", ancillary_variables="mu_t_error")
        data["mu_t_error"] = variable((*dims, "t_obs"), per_t(out["mu_t_error"]), "1",
                                      "estimated absolute numerical error of mu_t (pair of tolerances)")
    return data


def history_coords(scene: Scene) -> dict[str, xr.Variable]:
    """The grid's coordinates and the segments': index, V_ratio, duration or load-point displacement."""
    segs = scene.options.segments
    coords = grid_coords(scene)
    coords["V"].attrs["long_name"] = "reference velocity V (each segment's load point moves at V_ratio x V)"
    coords["segment"] = variable("segment", np.arange(len(segs)), "1", "segment of the load history")
    if "mu_t" in scene.observables:
        coords["t_obs"] = variable("t_obs", np.asarray(scene.options.t_obs, float), "s",
                                   "time from the start of the load history")

    def column(key: str) -> tuple[np.ndarray, dict[str, str]]:
        """The segments' numbers for ``key`` (NaN where an axis gives it per point, which a comment names)."""
        values = [s.get(key, np.nan) for s in segs]
        named = {i: v for i, v in enumerate(values) if isinstance(v, str)}
        attrs = {"comment": "NaN where an axis of the grid gives it per point: " + ", ".join(
            f"segment {i} -> {name}" for i, name in named.items())} if named else {}
        return np.array([np.nan if isinstance(v, str) else v for v in values], float), attrs

    ratio, ratio_attrs = column("V_ratio")
    coords["V_ratio"] = variable("segment", ratio, "1", "load-point velocity of the segment over V (0: hold)",
                                 **ratio_attrs)
    duration, duration_attrs = column("duration")
    coords["duration"] = variable("segment", duration, "s",
                                  "duration of the segment (NaN: given by its load-point displacement)",
                                  **duration_attrs)
    disp, disp_attrs = column("displacement")
    coords["load_point_displacement"] = variable("segment", disp, "m", "load-point displacement of the segment "
                                                 "(NaN: given by its duration)", **disp_attrs)
    return coords


def history_attributes(scene: Scene, seconds: float, description: dict[str, str], history: str = ""
                       ) -> dict[str, object]:
    """The global attributes of a history sweep's file (``description``: its plan's)."""
    attrs = global_attrs(scene, "Friction under a piecewise load history (velocity steps, holds) of the "
                         "Baumberger-Gauthier spring-block model (history scene)",
                         "quasi-static or inertial model per point (variable model); errors: difference of runs "
                         "at rtol/10 and rtol/100", history, seconds)
    attrs.update({f"plan_{k}": v for k, v in description.items()})
    return attrs
