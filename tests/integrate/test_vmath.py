"""The vectorisable exp of sweep/integrate/solvers/vmath.py against numpy's exp in extended precision."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from sweep.integrate.solvers.vmath import exp_f32, exp_f64, exp_f64_coarse


def _mapper(exp):
    """A compiled loop applying ``exp`` elementwise (as the lane kernels call it)."""

    @njit
    def apply(x):
        out = np.empty_like(x)
        for i in range(x.size):
            out[i] = exp(x[i])
        return out

    return apply


_map64, _map32, _map64_coarse = _mapper(exp_f64), _mapper(exp_f32), _mapper(exp_f64_coarse)


def _arguments(lo, hi):
    rng = np.random.default_rng(7)
    # the whole range, the reduced interval |r| <= ln2/2 densely, and the integers n ln 2 where n changes
    return np.concatenate([rng.uniform(lo, hi, 100_000), np.linspace(-0.35, 0.35, 20_001),
                           np.log(2.0) * np.arange(int(lo / np.log(2.0)) + 1, int(hi / np.log(2.0)))])


def test_exp_f64_within_one_ulp():
    x = _arguments(-708.0, 708.0)
    exact = np.exp(x.astype(np.longdouble))
    rel = np.abs((_map64(x).astype(np.longdouble) - exact) / exact).astype(float)
    assert rel.max() <= 1.0 * np.finfo(np.float64).eps


def test_exp_f32_within_one_ulp():
    x = _arguments(-87.0, 88.0).astype(np.float32)
    exact = np.exp(x.astype(np.float64))
    rel = np.abs(_map32(x).astype(np.float64) / exact - 1.0)
    assert rel.max() <= 1.0 * np.finfo(np.float32).eps


def test_exp_f64_coarse_within_its_stated_bound():
    """The degree-7 float64 exp of the first-order inertial correction's source: within 1e-8 relative (its
    docstring), and no better than it need be (or exp_f64 would do at no extra cost)."""
    x = _arguments(-708.0, 708.0)
    rel = np.abs((_map64_coarse(x).astype(np.longdouble) / np.exp(x.astype(np.longdouble))) - 1).astype(float)
    assert 1e-10 < rel.max() <= 1e-8


@pytest.mark.parametrize("mapper, big", [(_map64, 1e4), (_map32, np.float32(1e4)), (_map64_coarse, 1e4)])
def test_exp_clamps_instead_of_overflowing(mapper, big):
    """Arguments beyond the normal range are clamped (callers test their exponent themselves, EXP_MAX)."""
    x = np.array([-big, big], dtype=np.float32 if mapper is _map32 else np.float64)
    y = mapper(x)
    assert np.all(np.isfinite(y)) and 0.0 < y[0] < 1e-37 and y[1] > 1e38
