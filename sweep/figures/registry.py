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
from ..io import save
from ..plot_style import file_params, preset_name
from ..plot_style import save as save_png
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


def reproduce(name: str, out_dir: str | os.PathLike) -> list[Written]:
    """Reproduce figure ``name`` (a key of :data:`FIGURES`, or "all") into ``out_dir``: NAME.nc, NAME.png and
    NAME.txt (the key numbers beside the paper's, to check by eye)."""
    if name != "all" and name not in FIGURES:
        raise InputError(f"unknown figure {name!r}; one of {[*FIGURES, 'all']}")
    out = Path(out_dir)
    return [_write(FIGURES[n], out) for n in (FIGURES if name == "all" else [name])]


def _write(figure: Figure, out: Path) -> Written:
    t0 = time.perf_counter()
    ds = figure.compute()
    seconds = time.perf_counter() - t0
    data = save(ds, out / f"{figure.name}.nc")
    png = save_png(figure.draw(ds), out / f"{figure.name}.png")
    numbers = figure.key_numbers(ds)
    preset = preset_name(file_params(ds))
    header = [figure.title, f"reproduces: {PAPER}",
              f"parameters: preset {preset} (paper Table I, partly illegible in the OCR, ~20 % uncertainty: see "
              f"sweep.provenance[{preset!r}])",
              f"files: {data.name} (data), {png.name} (picture); regenerate with: sweep reproduce {figure.name}", ""]
    text = out / f"{figure.name}.txt"
    text.write_text("\n".join(header + numbers) + "\n", encoding="utf-8")
    return Written(figure.name, data, png, text, numbers, seconds)
