"""The paper's figures by name, and ``reproduce``: compute each from the presets, write its data (netCDF), its
picture (PNG) and a short text of its key numbers beside what the paper shows."""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import matplotlib.figure
import xarray as xr

from ..errors import InputError
from ..plot.style import file_params, preset_name
from ..plot.style import save as save_png
from ..write.netcdf import save
from ..write.targets import check_targets
from . import fig2, fig3, fig4
from .common import PAPER

__all__ = ["FIGURES", "Figure", "Written", "reproduce"]


@dataclass(frozen=True)
class Figure:
    """One figure of the paper: what it shows, how to compute its data, draw it (a matplotlib Figure) and list its
    key numbers."""

    name: str
    title: str
    compute: Callable[[], xr.Dataset]
    draw: Callable[[xr.Dataset], matplotlib.figure.Figure]
    key_numbers: Callable[[xr.Dataset], list[str]]


@dataclass(frozen=True)
class Written:
    """What ``reproduce`` wrote for one figure, its key numbers and its compute time [s] (netCDF and PNG
    excluded)."""

    name: str
    data: Path
    png: Path
    text: Path
    key_numbers: list[str]
    seconds: float


FIGURES: dict[str, Figure] = {f.name: f for f in (
    Figure("fig2", fig2.TITLE, fig2.compute, fig2.figure, fig2.key_numbers),
    Figure("fig3a", fig3.TITLE_A, fig3.compute_a, fig3.figure_a, fig3.key_numbers_a),
    Figure("fig3b", fig3.TITLE_B, fig3.compute_b, fig3.figure_b, fig3.key_numbers_b),
    Figure("fig4a", fig4.TITLE_A, fig4.compute_a, fig4.figure_a, fig4.key_numbers_a),
    Figure("fig4b", fig4.TITLE_B, fig4.compute_b, fig4.figure_b, fig4.key_numbers_b),
)}


def reproduce(name: str, out_dir: str | os.PathLike, overwrite: bool = False) -> list[Written]:
    """Reproduce figure ``name`` (a key of :data:`FIGURES`, or "all") into the folder ``out_dir``: NAME.nc,
    NAME.png and NAME.txt (the key numbers beside the paper's, to check by eye). Every file is checked before any
    figure is computed (sweep/write/targets.py): an existing one is replaced only with ``overwrite=True``."""
    if name != "all" and name not in FIGURES:
        raise InputError(f"unknown figure {name!r}; one of {[*FIGURES, 'all']}")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"the output of reproduce is a folder, and {out} is a file: give a folder (e.g. "
                         f"{out.with_suffix('')}_figures)")
    names = list(FIGURES) if name == "all" else [name]
    check_targets({f"{n} {kind}": _paths(out, n)[kind] for n in names for kind in ("data", "picture", "text")},
                  overwrite=overwrite)
    return [_write(FIGURES[n], out) for n in names]


def _paths(out: Path, name: str) -> dict[str, Path]:
    """The files of figure ``name`` in the folder ``out``."""
    return {"data": out / f"{name}.nc", "picture": out / f"{name}.png", "text": out / f"{name}.txt"}


def _write(figure: Figure, out: Path) -> Written:
    t0 = time.perf_counter()
    ds = figure.compute()
    seconds = time.perf_counter() - t0
    paths = _paths(out, figure.name)
    data = save(ds, paths["data"], overwrite=True)  # checked by reproduce before any figure was computed
    png = save_png(figure.draw(ds), paths["picture"])
    numbers = figure.key_numbers(ds)
    preset = preset_name(file_params(ds))
    header = [figure.title, f"reproduces: {PAPER}",
              f"parameters: preset {preset} (paper Table I, partly illegible in the OCR, ~20 % uncertainty: see "
              f"sweep.provenance[{preset!r}])",
              f"files: {data.name} (data), {png.name} (picture); regenerate with: sweep reproduce {figure.name}", ""]
    paths["text"].write_text("\n".join(header + numbers) + "\n", encoding="utf-8")
    return Written(figure.name, data, png, paths["text"], numbers, seconds)
