"""Every calibrated accuracy constant of the engine, each with the measurement that set it.

Grouped by the part of the engine that reads it. A constant here is a choice that trades cost for accuracy and was
set by a measurement (named in its docstring, with the benchmark or test that repeats it); structural constants of
a method (tableau coefficients, controller SAFETY/MIN/MAX factors: sweep/solvers/controllers.py) live with it.
Changing a value here changes the numbers of the runs that use it, and the plan's hash (a resume of a run made
with the old value is refused).
"""

from __future__ import annotations

import math

# ---------------------------------------------------------------------------------------------------------------
# Driven scene: the stepper and the regime decisions (sweep/integrate/driven.py)
# ---------------------------------------------------------------------------------------------------------------

RUNAWAY_XI_DOT = 1e8
"""Slip velocity xi' = V_slip/V beyond which the quasi-static model is declared broken down (regime runaway): far
past any stick-slip peak of the presets (xi' ~ 1e3), well before exp(w) can overflow."""
W_RUNAWAY = math.log(RUNAWAY_XI_DOT)
DECAYED = 1e-3
"""Amplitude, relative to the perturbation, below which a decaying oscillation is steady sliding."""
GROWTH_RTOL = 1e-3
"""Agreement of three successive per-cycle growth rates for the linear decay to count as established."""
STATIONARY_TOL = 1e-7
"""Largest |a_k/a_(k-1) - 1| of a stationary cycle (three in a row)."""
NEUTRAL_SPREAD = 1e-2
"""Stationary cycles within this relative distance of the first cycle's amplitude are neutral, not a limit cycle."""
NEUTRAL_START = 2.0
"""...and only where the first cycle is no larger than NEUTRAL_START x the amplitude of the linear oscillation
through the initial state: an orbit that grew within its first cycle (far below the line) reached a limit cycle,
however flat its later cycles are."""
STIFF_SWITCH = 1.5
"""A driven step runs RODAS3 instead of Dormand-Prince where h times the inertial mode's rate exceeds this (DP5 is
stable up to ~3.3 on the negative axis; half of that leaves the explicit steps accuracy-limited)."""
MIN_CYCLES = 3
"""Cycles needed before a regime is decided from their amplitudes (three growth rates)."""


def driven_stepper_rtol(rtol: float) -> float:
    """Local tolerance of the driven stepper: the regime decisions compare amplitudes of successive cycles to
    STATIONARY_TOL (1e-7), so the integration must be far tighter than that whatever the scene's rtol."""
    return min(1e-2 * rtol, 1e-9)

# ---------------------------------------------------------------------------------------------------------------
# Adaptive per-point solutions whose error is estimated from a pair of tolerances (inertial stop, slip-law stop)
# ---------------------------------------------------------------------------------------------------------------

TIGHTER = 10.0
"""Such a solution is run at local tolerances rtol/TIGHTER and rtol/TIGHTER^2; the tighter value is kept and the
difference, ~the error of the looser run, is its error estimate. (The looser pair rtol, rtol/10 flagged 20 % of the
default scene error_above_tol with the inertial model: the adaptive steps' global error reaches ~5x their local
tolerance.)"""
GENERAL_ESTIMATE_GAIN = 2.0
"""Estimate of the general (slip-law) stop path = GENERAL_ESTIMATE_GAIN x max(|x1 - x2|, |x2 - x3|) of its runs at
rtol/TIGHTER^(1, 2, 3), x2 returned (sweep/integrate/stop_slip.py): as the step ladder's non-asymptotic estimate
(sweep/ladder.py CONSERVATIVE_GAIN). On tests/test_slip_law.py's cases at rtol 1e-6 and 1e-9 it bounds the true
error and stays within 100x of it."""
