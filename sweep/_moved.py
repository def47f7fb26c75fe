"""The module paths of earlier layouts, still importable: ``import sweep.io`` gives :mod:`sweep.write.netcdf` with a
FutureWarning that names the new path (the package's folders: docs/design.md, "Layout").

A finder at the front of ``sys.meta_path`` answers for the old names only; the module it returns is the one under
the new name (one module object, never a second copy of a module that compiles numba kernels).
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings
from types import MappingProxyType, ModuleType

__all__ = ["MOVED", "install", "new_name"]

MOVED = MappingProxyType({
    "sweep.backends": "sweep.run.backends",
    "sweep.compile_notice": "sweep.run.compile_notice",
    "sweep.concurrent_chunks": "sweep.run.concurrent_chunks",
    "sweep.journal": "sweep.run.journal",
    "sweep.lock": "sweep.run.lock",
    "sweep.progress": "sweep.run.progress",
    "sweep.runner": "sweep.run.runner",
    "sweep.size": "sweep.run.size",
    "sweep.dataset": "sweep.assemble.dataset",
    "sweep.driven_sweep": "sweep.protocols.driven.chunk",
    "sweep.engine": "sweep.protocols.stop.engine",
    "sweep.estimate": "sweep.protocols.stop.estimate",
    "sweep.model_choice": "sweep.protocols.stop.model_choice",
    "sweep.files": "sweep.write.read",
    "sweep.io": "sweep.write.netcdf",
    "sweep.outputs": "sweep.write.targets",
    "sweep.hopf": "sweep.analysis.hopf",
    "sweep.params": "sweep.scene.params",
    "sweep.presets": "sweep.scene.presets",
    "sweep.plausibility": "sweep.scene.plausibility",
    "sweep.plot_blocks": "sweep.plot.blocks",
    "sweep.plot_curves": "sweep.plot.curves",
    "sweep.plot_maps": "sweep.plot.maps",
    "sweep.plot_slices": "sweep.plot.slices",
    "sweep.plot_style": "sweep.plot.style",
    "sweep.models": "sweep.integrate.models",
    "sweep.solvers": "sweep.integrate.solvers",
})
"""Old module (or package) path -> its path now; a moved package's submodules move with it."""


def new_name(name: str) -> str | None:
    """The path now of the old module ``name`` (None if it did not move)."""
    for old, new in MOVED.items():
        if name == old or name.startswith(old + "."):
            return new + name[len(old):]
    return None


class _Alias(importlib.abc.Loader):
    def __init__(self, new: str) -> None:
        self.new = new

    def create_module(self, spec) -> ModuleType:
        warnings.warn(f"{spec.name} is now {self.new}: import it from there (the old path will be removed)",
                      FutureWarning, stacklevel=2)
        module = importlib.import_module(self.new)
        self.spec = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        """The module under its new name is already executed; importlib gave it the old name's spec: its own back
        (relative imports and pickling go by it)."""
        module.__spec__ = self.spec


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname: str, path=None, target=None):
        new = new_name(fullname)
        return None if new is None else importlib.util.spec_from_loader(fullname, _Alias(new))


def install() -> None:
    """Put the finder first in ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
