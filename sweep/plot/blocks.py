"""Maps with more points than the picture has pixels: drawn in blocks of consecutive points, and the picture says so.

A map panel of sweep's pictures is ~450-570 pixels a side (sweep.plot.style.SIZES at 100 dpi). A 1000 x 1000 grid
drawn cell by cell cost ~0.8 s of a 1e6-point ``sweep run`` (matplotlib's quad mesh, drawn twice: once for the
constrained layout, once into the file) and showed no more than the pixels can: Agg paints each pixel with whichever
cell was drawn last under its centre, one sample of the few cells there. The rule here: an axis of n points is cut into
blocks of ``s = ceil(n / MAX_CELLS)`` consecutive points (the last block may be shorter), each block drawn as one cell
spanning exactly the cells of its points, coloured by the geometric mean of its points' values (the maps use a log
colour scale: that is the colour of the block's mean there). A block is blank only where none of its points has a
finite positive value; a point without one is crossed by the map anyway (sweep.plot.style.mark_failed), at its own
place. Where nothing is reduced the map is drawn cell by cell as before.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MAX_CELLS", "block_size", "block_edges", "block_means", "reduction_note"]

MAX_CELLS = 400
"""Most cells drawn along an axis of a map: about a panel's size in pixels, so a block is about one pixel."""


def block_size(n: int, most: int = MAX_CELLS) -> int:
    """Points per block along an axis of ``n`` points (1: every point its own cell)."""
    return max(1, math.ceil(n / most))


def block_edges(centres: np.ndarray, s: int) -> np.ndarray:
    """Edges [units of ``centres``] of the blocks of ``s`` consecutive points along an axis: the edges of the cells
    that matplotlib's ``pcolormesh(shading="nearest")`` gives the points (half way between neighbours, half a step
    beyond the ends), taken every ``s`` points and at the end, so that a block covers exactly its points' cells."""
    c = np.asarray(centres, dtype=float)
    if c.size == 1:
        return np.array([c[0], c[0]])  # matplotlib's (degenerate) edges of a single cell
    half = np.diff(c) / 2.0
    edges = np.concatenate([[c[0] - half[0]], c[:-1] + half, [c[-1] + half[-1]]])
    return edges[np.unique(np.append(np.arange(0, c.size, s), c.size))]


def block_means(z: np.ndarray, s_rows: int, s_cols: int) -> np.ndarray:
    """Geometric mean of the finite positive values of ``z`` over blocks of ``s_rows`` x ``s_cols`` consecutive
    entries (the last block of each axis may be shorter); NaN where a block has no such value."""
    z = np.asarray(z, dtype=float)
    good = np.isfinite(z) & (z > 0)
    logs = np.log(np.where(good, z, 1.0))
    rows, cols = np.arange(0, z.shape[0], s_rows), np.arange(0, z.shape[1], s_cols)

    def block_sum(a):
        return np.add.reduceat(np.add.reduceat(a, rows, axis=0), cols, axis=1)

    count = block_sum(good.astype(np.int64))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, np.exp(block_sum(logs) / count), np.nan)


def reduction_note(shape: tuple[int, int], blocks: tuple[int, int]) -> str | None:
    """What the picture says about a map of ``shape`` (K/M points, V points) drawn in ``blocks`` (points per block
    along K/M, along V); None where nothing was reduced."""
    if blocks == (1, 1):
        return None
    cells = tuple(math.ceil(n / s) for n, s in zip(shape, blocks))
    return (f"{shape[0]} x {shape[1]} points (K/M x V) shown as {cells[0]} x {cells[1]} cells: geometric means of "
            f"blocks of {blocks[0]} x {blocks[1]} points")
