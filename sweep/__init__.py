"""sweep: Numba-accelerated parameter-space sweeps of the Baumberger & Gauthier (1996) spring-block model."""

from ._version import __version__
from .api import run_sweep, solve_point
from .backends import local_cluster
from .errors import InputError
from .hopf import locate_hopf
from .io import open_dataset as open
from .io import save
from .params import FrictionParams
from .plan import Plan, make_plan
from .presets import presets, provenance
from .scene import Scene, default_scene, load_scene
from .status import Status

__all__ = ["FrictionParams", "InputError", "Plan", "Scene", "Status", "default_scene", "load_scene", "local_cluster",
           "locate_hopf", "make_plan", "open", "presets", "provenance", "run_sweep", "save", "solve_point"]
