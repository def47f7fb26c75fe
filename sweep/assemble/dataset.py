"""What every protocol's Dataset shares: CF variables with units, the grid's coordinates (the axes, chi, mu1, the Hopf
line, gamma), the global attributes (Conventions, source, history, references, the scene). Each protocol's output
schema (sweep/protocols/*/schema.py) builds its own variables from these (docs/design.md, "Output contract").

Reduced quantities (xi, tau, chi) and dimensional ones (slip in m, times in s) never share a name.
"""

from __future__ import annotations

import datetime as _dt
import functools
import sys
from importlib import metadata

import numpy as np
import xarray as xr

from .. import physics
from ..plan.plan import line_uses_inertia
from ..scene.scene import AXIS_UNITS, Scene
from ..status import Status

__all__ = ["DIMS", "REFERENCES", "global_attrs", "grid_coords", "line_model_comment", "on_grid", "variable", "versions",
           "with_errors"]

REFERENCES = (
    "T. Baumberger and L. Gauthier, Creeplike relaxation at the interface between rough solids under shear, "
    "J. Phys. I France 6 (1996) 1021-1030, doi:10.1051/jp1:1996113"
)
DIMS = ("K_over_M", "V")


@functools.cache
def versions() -> str:
    """The versions of sweep and its numerical stack, for the file's ``source`` (looked up once per process: the
    package metadata lookups cost ~2.5 ms, an eighth of a 20,000-point sweep's serial time on two threads)."""

    def v(pkg: str) -> str:
        try:
            return metadata.version(pkg)
        except metadata.PackageNotFoundError:
            return "unknown"

    from .._version import __version__

    return (f"sweep {__version__}, numba {v('numba')}, numpy {v('numpy')}, xarray {v('xarray')}, "
            f"python {sys.version.split()[0]}")


def variable(dims, data, units: str, long_name: str, **attrs) -> xr.Variable:
    """A CF variable: ``units`` ("1" when dimensionless) and ``long_name`` always, other attributes as given."""
    return xr.Variable(dims, data, {"units": units, "long_name": long_name, **attrs})


AXIS_NAMES = {"K_over_M": "spring stiffness over slider mass K/M", "V": "driving velocity before the stop",
              "A": "direct-effect coefficient A (eq. 1)", "m1": "slope m1 of mu_d at V0 (eq. 6)",
              "m2": "curvature m2 of mu_d (eq. 6)", "D0": "memory length D0"}
"""long_name of each grid axis (Scene.dims)."""


def on_grid(scene: Scene, names: tuple[str, ...], fn) -> tuple[tuple[str, ...], np.ndarray]:
    """(dims, values) of fn(**parameters) over the grid dims among ``names`` (a quantity of the parameters
    ``names``; parameters that are not axes enter as numbers): in 2-D, chi over K_over_M and mu1 over V."""
    dims = scene.on_dims(names)
    value = fn(**{n: scene.broadcast(n, dims) for n in names})
    return dims, np.broadcast_to(value, tuple(scene.axis(d).size for d in dims)).copy()


def grid_coords(scene: Scene) -> dict[str, xr.Variable]:
    p = scene.params
    line_model = lambda V, m1, m2, A, D0: line_uses_inertia(  # noqa: E731
        physics.inertia_number(V, D0, p.g) / A, scene.model, scene.model_tol)
    mu1 = lambda V, m1, m2: physics.mu1(V, m1, m2, p.V0)  # noqa: E731
    coords = {d: variable(d, scene.axis(d), AXIS_UNITS[d], AXIS_NAMES[d]) if d in AXIS_NAMES
              else xr.Variable(d, scene.axis(d), scene.axis_attrs(d)) for d in scene.dims}  # k, a, b, Dc, options
    coords.update({
        "chi": variable(*on_grid(scene, ("K_over_M", "D0"), lambda K_over_M, D0: physics.reduced_stiffness(K_over_M, D0,
                                                                                                     p.g)),
                    "1", "reduced stiffness chi = K D0/(M g)"),
        "mu1": variable(*on_grid(scene, ("V", "m1", "m2"), mu1), "1",
                        "velocity-weakening slope mu1(V) = m1 - 2 m2 ln(V/V0)"),
        "chi_c": variable(*on_grid(scene, ("V", "m1", "m2", "A", "D0"), lambda V, m1, m2, A, D0: physics.chi_c_inertial(
                          mu1(V, m1, m2), A, physics.inertia_number(V, D0, p.g) * line_model(V, m1, m2, A, D0))),
                      "1", "reduced stiffness on the Hopf line of the model used at this V, mu1 (1 + gamma/A) with "
                      "inertia (NaN: no Hopf line, mu1 <= 0)", comment=line_model_comment(scene)),
        "chi_c_quasistatic": variable(*on_grid(scene, ("V", "m1", "m2"), lambda V, m1, m2: physics.chi_c_quasistatic(
                                      mu1(V, m1, m2))), "1",
                                  "reduced stiffness on the Hopf line of the quasi-static model mu1 (paper eq. 3; NaN: "
                                  "no Hopf line)"),
        "gamma": variable(*on_grid(scene, ("V", "D0"), lambda V, D0: physics.inertia_number(V, D0, p.g)), "1",
                      "inertia number gamma = V^2/(g D0)"),
    })
    if "trajectory" in scene.observables:
        coords["tau"] = variable("tau", scene.tau_samples, "1", "reduced time after the stop tau = V t/D0")
    if "slip_at" in scene.observables:
        coords["t_obs"] = variable("t_obs", np.asarray(scene.t_obs), "s", "time after the stop")
    return coords


def line_model_comment(scene: Scene) -> str:
    if scene.model == "auto":
        return (f"inertial model where gamma/A > model_tol = {scene.model_tol:g} (inertia shifts the line by gamma/A "
                f"relative), quasi-static elsewhere")
    return f"{scene.model} model"


def with_errors(data: dict[str, xr.Variable], errors: dict[str, np.ndarray]) -> dict[str, xr.Variable]:
    """The ``<name>_error`` variables of ``errors`` (each linked from its variable in ``data``)."""
    out = {}
    for name, err in errors.items():
        var = data[name]
        var.attrs["ancillary_variables"] = f"{name}_error"
        out[f"{name}_error"] = variable(var.dims, err, var.attrs["units"],
                                    f"estimated absolute numerical error of {name} (Richardson pair + tail bound)")
    return out


def global_attrs(scene: Scene, title: str, comment: str, history: str, seconds: float) -> dict[str, object]:
    """Global attributes shared by every protocol's Dataset."""
    return {
        "Conventions": "CF-1.11",
        "title": title,
        "institution": "sweep users",
        "source": versions(),
        "history": f"{_dt.datetime.now(_dt.UTC).isoformat(timespec='seconds')}: {history or 'sweep'}",
        "references": REFERENCES,
        "comment": f"status codes: {', '.join(f'{s.value}={s.name.lower()}' for s in Status)}; {comment}",
        "scene": scene.to_toml(),
        "elapsed_seconds": float(seconds),
    }
