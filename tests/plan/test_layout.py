"""The chunk layout (sweep/plan/layout.py): blocks that are both consecutive ranges of the flat index and rectangles
of the grid aligned with the storage chunks, covering every point once, for any shape and chunk size."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sweep.plan.layout import block_shape, block_slices, chunk_bounds
from sweep.run.runner import chunk_points


@settings(max_examples=300, deadline=None)
@given(shape=st.lists(st.integers(1, 9), min_size=1, max_size=4).map(tuple), chunk=st.integers(1, 400))
def test_blocks_cover_the_grid_once_in_order_as_aligned_rectangles(shape, chunk):
    bounds = chunk_bounds(shape, chunk)
    flat = np.arange(math.prod(shape)).reshape(shape)
    block = block_shape(shape, chunk)
    assert bounds[0][0] == 0 and bounds[-1][1] == flat.size
    assert all(a[1] == b[0] for a, b in zip(bounds, bounds[1:]))
    for lo, hi in bounds:
        assert 0 < hi - lo <= chunk
        slices = block_slices(shape, lo, hi)
        np.testing.assert_array_equal(flat[slices].ravel(), np.arange(lo, hi))  # the range is the rectangle
        assert all(s.start % b == 0 and s.stop - s.start <= b for s, b in zip(slices, block))  # one storage chunk


def test_a_block_takes_whole_rows_where_they_fit_and_part_of_a_row_where_not():
    assert block_shape((200, 100), 4096) == (40, 100)
    assert block_shape((4, 10_000), 4096) == (1, 4096)
    assert block_shape((3, 4, 5), 7) == (1, 1, 5)
    assert block_shape((3, 4, 5), 45) == (2, 4, 5)
    assert block_shape((3, 4, 5), 10**6) == (3, 4, 5)


def test_a_range_that_is_not_a_block_is_refused():
    with pytest.raises(ValueError, match="not a block"):
        block_slices((4, 5), 3, 8)  # crosses a row boundary without covering whole rows


def test_a_chunk_holds_its_range_in_a_fixed_shuffled_order_made_on_demand():
    layout = chunk_points((300, 70), 1000)
    assert len(layout) == len(layout.bounds) == 300 // 14 + 1
    for i in (0, 5, len(layout) - 1):
        lo, hi = layout.bounds[i]
        points = layout[i]
        assert not points.flags.writeable and sorted(points.tolist()) == list(range(lo, hi))
        assert not np.array_equal(points, np.arange(lo, hi))  # shuffled: costly corners mixed over the threads
        np.testing.assert_array_equal(points, layout[i])  # the same order every time it is asked for
