"""The chunk layout of a grid: rectangular blocks that are also consecutive ranges of the flat (C order) point index.

A sweep's points are numbered flat in C order over its grid (Scene.dims: K_over_M, V and the extra axes). A block
takes, from the last dim outwards, whole extents while they fit in the chunk size, then part of the next dim, and one
index of each dim before it (in 2-D: whole rows of every V, or part of one row where a row alone is larger than a
chunk). Such a block is at once

* a consecutive range of flat indices (what the journal records and checks), and
* a rectangle of the grid (a sub-grid of the scene: its points' parameters are computed from the scene, never stored,
  sweep.scene.scene.Scene.sub_grid), which is also the storage chunk of the file's variables, so that two chunks of a
  run never share a storage chunk (sweep/write/regions.py).

All blocks have the same shape except those at the far edge of the partial dim. The layout depends on the grid's
shape and the chunk size only, never on the machine: a journal resumes anywhere.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["block_shape", "block_slices", "chunk_bounds"]


def block_shape(shape: tuple[int, ...], chunk_size: int) -> tuple[int, ...]:
    """The shape of the blocks of a grid of ``shape`` with at most ``chunk_size`` points each (module docstring)."""
    block = [1] * len(shape)
    inner = 1
    for d in range(len(shape) - 1, -1, -1):
        block[d] = max(1, min(shape[d], chunk_size // inner))
        if block[d] < shape[d]:
            break
        inner *= shape[d]
    return tuple(block)


def chunk_bounds(shape: tuple[int, ...], chunk_size: int) -> list[tuple[int, int]]:
    """(first flat point, last + 1) of each block of the grid, in order."""
    n = math.prod(shape)
    if n == 0:
        return []
    block = block_shape(shape, chunk_size)
    d = _partial_dim(shape, block)
    inner = math.prod(shape[d + 1:])  # points of one index of dim d (the whole extents after it)
    outer = math.prod(shape[:d])  # indices of the dims before d: one block row each
    starts = np.arange(0, shape[d], block[d])
    stops = np.minimum(starts + block[d], shape[d])
    bounds = []
    for row in range(outer):
        base = row * shape[d] * inner
        bounds.extend((base + int(a) * inner, base + int(b) * inner) for a, b in zip(starts, stops))
    return bounds


def block_slices(shape: tuple[int, ...], start: int, stop: int) -> tuple[slice, ...]:
    """The flat points start..stop-1 of a grid of ``shape`` as one slice per dim, where they form a block (a range of
    :func:`chunk_bounds`: whole extents of the last dims, part of one dim, one index of the dims before it)."""
    n, inner, d = stop - start, 1, len(shape) - 1
    while d > 0 and n % (inner * shape[d]) == 0 and start % (inner * shape[d]) == 0:
        inner *= shape[d]
        d -= 1
    first = np.unravel_index(start, shape)
    length = n // inner
    if n % inner or first[d] + length > shape[d] or any(first[d + 1:]):
        raise ValueError(f"points {start}..{stop - 1} are not a block of a grid of shape {shape}")
    return (tuple(slice(int(i), int(i) + 1) for i in first[:d]) + (slice(int(first[d]), int(first[d]) + length),)
            + tuple(slice(0, k) for k in shape[d + 1:]))


def _partial_dim(shape: tuple[int, ...], block: tuple[int, ...]) -> int:
    """The dim a block takes part of (the first from the left with a block extent below the grid's, else dim 0)."""
    for d in range(len(shape) - 1, -1, -1):
        if block[d] < shape[d]:
            return d
    return 0
