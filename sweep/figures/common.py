"""What every reproduced figure shares: running its scene, its title, and the rows of its key-number text."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..api import run_sweep
from ..scene.scene import Scene

__all__ = ["PAPER", "model_summary", "row", "run"]

PAPER = "T. Baumberger & L. Gauthier, J. Phys. I France 6 (1996) 1021"


def run(scene: Scene, name: str, figure: str) -> xr.Dataset:
    """The Dataset of ``scene`` (sweep.run_sweep, no progress bar), its history and ``figure`` attribute naming
    the paper's figure it reproduces."""
    ds = run_sweep(scene, progress=False, history=f"sweep reproduce {name}")
    ds.attrs["figure"] = f"{figure} of {PAPER}"
    return ds


def row(what: str, engine: str, paper: str = "", expected: str = "") -> str:
    """One line of a key-number text: what, the engine's value, what the paper shows (where it says) and what is
    expected from docs/physics.md (where the paper does not say)."""
    return (f"{what:<52} {engine:<20}" + (f" | paper: {paper}" if paper else "")
            + (f" | expected: {expected}" if expected else ""))


def model_summary(ds: xr.Dataset) -> str:
    """Which model the points used and the largest estimated error of the quasi-static model where it was."""
    inertial = int(np.count_nonzero(ds["model"].values))
    text = f"quasi-static at {ds['model'].size - inertial} point(s), inertial at {inertial}"
    if "model_error" in ds:
        used = ds["model_error"].values[ds["model"].values == 0]
        if np.isfinite(used).any():
            text += f"; largest estimated inertia error where quasi-static: {np.nanmax(used):.1g}"
    return text
