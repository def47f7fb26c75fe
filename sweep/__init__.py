"""sweep: Numba-accelerated parameter-space sweeps of the Baumberger & Gauthier (1996) spring-block model.

The public names below are imported on first use (PEP 562), so that ``import sweep`` and the command line start
without loading numba: ``sweep --version`` answers at once and a Ctrl-C while the kernels load is a one-line
message, not a traceback from inside an import.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from . import _moved
from ._version import __version__
from .errors import InputError
from .scene.params import FrictionParams
from .scene.presets import presets, provenance  # eager: the name would otherwise be the submodule sweep.presets

_moved.install()  # the module paths of earlier layouts (sweep.io, sweep.api, ...) stay importable, with a warning

_PUBLIC = {
    "run_sweep": "api", "solve_point": "api", "local_cluster": "run.backends", "locate_hopf": "analysis.hopf",
    "open": ("write.read", "open_sweep_file"), "save": "write.netcdf", "Plan": "plan.plan", "make_plan": "plan.plan",
    "Scene": "scene.scene", "default_scene": "scene.scene", "load_scene": "scene.scene", "Status": "status",
}
# sweep.fit is a callable subpackage (sweep/fit/__init__.py): the submodule fallback of __getattr__ imports it
"""Public name -> module of the package (or (module, name in it))."""

__all__ = ["FrictionParams", "InputError", "Plan", "Scene", "Status", "__version__", "default_scene", "fit",
           "load_scene", "local_cluster", "locate_hopf", "make_plan", "open", "presets", "provenance", "run_sweep",
           "save", "solve_point"]


def __getattr__(name: str):
    where = _PUBLIC.get(name)
    if where is None:  # a submodule, as after "import sweep.<name>"
        try:
            return importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
        raise AttributeError(f"module 'sweep' has no attribute {name!r}")
    module, attr = (where, name) if isinstance(where, str) else where
    value = getattr(importlib.import_module(f".{module}", __name__), attr)
    globals()[name] = value  # next time a plain module attribute
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # for type checkers and IDEs: the same names, imported eagerly
    from .analysis.hopf import locate_hopf
    from .api import run_sweep, solve_point
    from .plan.plan import Plan, make_plan
    from .run.backends import local_cluster
    from .scene.scene import Scene, default_scene, load_scene
    from .status import Status
    from .write.netcdf import open_dataset as open
    from .write.netcdf import save
