"""The bistable band above an inverted (subcritical) Hopf line, measured by simulation (docs/hopf-type.md).

Where l1 > 0 (sweep/analysis/lyapunov.py) the small cycle born at the line is unstable and lies on the stable side
(chi > chi_c): there steady sliding is stable against small perturbations, but a large enough kick lands on a
stick-slip cycle, up to the fold of cycles at chi_f > chi_c. The band chi_c < chi < chi_f is where an experiment
may see "premature" stick-slip above the linear line.

Measured with the driven simulation (sweep/integrate/driven.py) in the relative distance d = chi/chi_c - 1 above the
line: a large start (LARGE_PERTURBATION, or BIG_START x the stick-slip amplitude just below the line, whichever is
larger) ends in stick-slip inside the band and in steady sliding above it; d is bracketed by steps of x3 from
D_FIRST, then bisected geometrically until d_hi / d_lo - 1 <= ``rtol``. At the final d_lo a small start
(SIGN_PERTURBATION x 10) must decay: both attractors coexist there (bistability checked, not assumed). The runs
are those of sweep/analysis/hopf_batch.py (stepper rtol STEPPER_RTOL): :func:`band_search` is the search of one
velocity, which sweep.locate_hopf advances at all velocities in lockstep.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from ..accuracy import LARGE_PERTURBATION, TYPE_CYCLES, TYPE_DISTANCE
from ..errors import InputError
from ..integrate.driven import Regime
from .hopf_batch import Run, Search, drive

__all__ = ["Band", "band_search", "bistable_band", "check_band_inputs"]

D_FIRST = 1e-4
"""First relative distance above the line tried (the band is ~1e-3 wide at gamma/A = 0.1, m2 = 0)."""
D_LAST = 0.5
"""Largest relative distance tried: beyond it the band is reported open-ended (its edge not found)."""
D_SMALLEST = 1e-7
"""Smallest relative distance tried when the large start decays already at D_FIRST."""
BIG_START = 1.5
"""The large start is at least this times the stick-slip amplitude found just below the line."""
SMALL_START = 1e-4
"""The small start that must decay inside the band."""


class Band(NamedTuple):
    """The bistable band above the line at one V (reduced)."""

    d_lo: float
    """Largest relative distance chi/chi_c - 1 where a large start was seen to end in stick-slip (0: none found)."""
    d_hi: float
    """Smallest relative distance where it ended in steady sliding (inf: none up to D_LAST)."""
    bistable: bool
    """At d_lo a small start decayed while the large one stayed in stick-slip."""
    large_start: float
    """The large start's spring stretch z(0) [1]."""
    simulations: int
    undecided: int
    """Runs that ended undecided (budget out): they stop the bisection, the bracket stays as it was."""


def band_search(a: float, b: float, g: float, rtol: float = 1e-2) -> Search:
    """The search (sweep/analysis/hopf_batch.py: rounds of runs, many velocities in lockstep) behind
    :func:`bistable_band`; returns its :class:`Band`."""
    k_c = a * (1.0 + g)
    run = lambda d, start: [Run(k_c * (1.0 + d), a, b, g, start, TYPE_CYCLES)]  # noqa: E731
    runs, undecided = 1, 0
    below = (yield run(-TYPE_DISTANCE, SMALL_START))[0]
    large = max(LARGE_PERTURBATION, BIG_START * below.amplitude if below.regime == Regime.STICK_SLIP else 0.0)

    def sticks(d: float) -> Search:
        nonlocal runs, undecided
        runs += 1
        regime = (yield run(d, large))[0].regime
        if regime in (Regime.STICK_SLIP, Regime.NEUTRAL):
            return True
        if regime == Regime.STEADY:
            return False
        undecided += 1
        return None

    d_lo, d_hi = 0.0, math.inf
    d = D_FIRST
    first = yield from sticks(d)
    if first is None:
        return Band(0.0, math.inf, False, large, runs, undecided)
    if first:
        d_lo = d
        while d_hi == math.inf and d < D_LAST:
            d = min(3.0 * d, D_LAST)
            s = yield from sticks(d)
            if s is None:
                return Band(d_lo, math.inf, False, large, runs, undecided)
            d_lo, d_hi = (d, d_hi) if s else (d_lo, d)
    else:
        d_hi = d
        while d_lo == 0.0 and d > D_SMALLEST:
            d = d / 10.0
            s = yield from sticks(d)
            if s is None:
                return Band(0.0, d_hi, False, large, runs, undecided)
            d_lo, d_hi = (d, d_hi) if s else (d_lo, d)
    if d_lo > 0.0 and math.isfinite(d_hi):
        while d_hi / d_lo - 1.0 > rtol:
            mid = math.sqrt(d_lo * d_hi)
            s = yield from sticks(mid)
            if s is None:
                break
            d_lo, d_hi = (mid, d_hi) if s else (d_lo, mid)
    bistable = False
    if d_lo > 0.0:
        runs += 1
        bistable = bool((yield run(d_lo, SMALL_START))[0].regime == Regime.STEADY)
    return Band(d_lo, d_hi, bistable, large, runs, undecided)


def check_band_inputs(a: float, b: float, g: float, rtol: float) -> None:
    """InputError unless a = mu1/A > 0, g = gamma/A >= 0, b finite and rtol in [1e-6, 1] (before any run)."""
    if not (math.isfinite(a) and a > 0.0):
        raise InputError(f"a = mu1/A must be finite and > 0 (a Hopf line exists), got {a!r}")
    if not (math.isfinite(g) and g >= 0.0) or not math.isfinite(b):
        raise InputError(f"g = gamma/A must be finite and >= 0 and b = m2/A finite, got g={g!r}, b={b!r}")
    if not (math.isfinite(rtol) and 1e-6 <= rtol <= 1.0):
        raise InputError(f"rtol must be in [1e-6, 1] (relative precision of the band's edge), got {rtol!r}")


def bistable_band(a: float, b: float, g: float, rtol: float = 1e-2, law: str = "aging") -> Band:
    """The band at the reduced parameters a = mu1/A > 0, b = m2/A, g = gamma/A (0: quasi-static) on the line
    k_c = a (1 + g), to a relative precision ``rtol`` of its upper edge d_hi (module docstring)."""
    check_band_inputs(a, b, g, rtol)
    return drive([band_search(a, b, g, rtol)], law)[0]
