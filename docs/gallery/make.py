"""Regenerate the README's gallery: ``python docs/gallery/make.py`` (from any folder).

Runs the real commands: ``sweep reproduce all`` (the paper's figures, with their key-number texts) and ``sweep run``
+ ``sweep plot`` on the stop, driven and Hopf scenes beside this script. The netCDF files go to sweep-out/gallery/
(not committed); the PNGs and texts come here, the PNGs stored with a 256-colour palette (Pillow, which matplotlib
itself requires) to keep the repository small. About a minute on 2 cores once numba's kernels are compiled.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT))  # this checkout's sweep, installed or not

from PIL import Image  # noqa: E402

from sweep.cli import main  # noqa: E402

DATA = ROOT / "sweep-out" / "gallery"


def sweep(*args) -> None:
    """Run ``sweep ARGS --overwrite``: the gallery's files are regenerated in place."""
    print("$ sweep", *args, flush=True)
    if main([str(a) for a in args] + ["--overwrite"]) != 0:
        sys.exit(f"sweep {' '.join(map(str, args))} failed")


def compact(png: Path) -> None:
    """Store ``png`` with a 256-colour palette (about 3x smaller; the pictures have few colours)."""
    Image.open(png).convert("RGB").quantize(256, method=Image.Quantize.FASTOCTREE).save(png, optimize=True)


def build() -> None:
    sweep("reproduce", "all", "-o", DATA)
    for path in sorted(DATA.glob("fig*.png")) + sorted(DATA.glob("fig*.txt")):
        shutil.copy(path, HERE / path.name)
    sweep("run", HERE / "stop.toml", "-o", DATA / "stop.nc", "-q")
    sweep("plot", DATA / "stop.nc", "-o", HERE / "plot_stop.png")  # and plot_stop_trajectories.png
    sweep("run", HERE / "driven.toml", "-o", DATA / "driven.nc", "-q")
    sweep("plot", DATA / "driven.nc", "-o", HERE / "plot_driven.png")
    sweep("hopf", HERE / "hopf.toml", "-o", DATA / "hopf.nc")
    sweep("plot", DATA / "hopf.nc", "-o", HERE / "plot_hopf.png")
    for png in sorted(HERE.glob("*.png")):
        compact(png)
        print(f"{png.relative_to(ROOT)}: {png.stat().st_size / 1024:.0f} KiB")


if __name__ == "__main__":
    build()
