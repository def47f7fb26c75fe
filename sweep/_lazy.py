"""Names of a package imported on first use (PEP 562): a package's ``__init__`` re-exports its modules' public names
without importing them (and numba with them) when the package is imported."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping


def lazy_exports(package: str, names: Mapping[str, str], fallback: str | None = None
                 ) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """(__getattr__, __dir__) of ``package``: ``names`` maps a public name to the module (relative to the package)
    that defines it; any other name is looked up in ``fallback`` (the module whose path the package took over), then
    as a submodule."""

    def __getattr__(name: str) -> object:
        module = names.get(name)
        if module is not None:
            return getattr(importlib.import_module(f".{module}", package), name)
        try:
            return importlib.import_module(f".{name}", package)
        except ModuleNotFoundError as exc:
            if exc.name != f"{package}.{name}":
                raise
        if fallback is not None:
            source = importlib.import_module(f".{fallback}", package)
            if hasattr(source, name):
                return getattr(source, name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(names)

    return __getattr__, __dir__
