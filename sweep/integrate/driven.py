"""Driven scene driver (docs/physics.md 3b): one point integrated from a perturbed steady sliding until its regime
is decided; the batch loop over flat points.

Model x stepper x controller x recorder: the right-hand side of :mod:`sweep.integrate.models.driven` (with the scene's
state
law), the explicit stage loop of :mod:`sweep.integrate.solvers.explicit` with the Dormand-Prince 5(4) tableau and the PI
controller, or, where the inertial mode is stiff (h times its rate A/(gamma xi') > STIFF_SWITCH: stick phases),
RODAS3 (:mod:`sweep.integrate.solvers.rosenbrock_step`) with the analytic Jacobian and the I controller; what is
recorded is
the cycle history below. Near steady sliding (xi' ~ 1, where the Hopf line is located) the explicit stepper stays
in use. The driven scene's inertial points (``point_kernel(..., slaved=True)``) run on the slow manifold of the
inertial model (w slaved to second order, :func:`sweep.integrate.models.driven.make_slaved_rhs`, the explicit
stepper) wherever the inertial term is small and the full system has relaxed onto it
(:data:`sweep.accuracy.SLAVED_INERTIA`, :data:`sweep.accuracy.SLAVED_ENTRY`): the stick phases and the ends of each
slip, where the full system's steps were RODAS3 ones or dp5 ones held at its stability limit (there at
:data:`sweep.accuracy.SLAVED_TOL` x the stepper's tolerance). A slip velocity beyond RUNAWAY_XI_DOT ends the point as
``runaway`` (the quasi-static model breaks down: m2 = 0 below the Hopf line overflows in finite time), before any
exponent can overflow.

The run starts from steady sliding with the spring stretched by ``perturbation`` (z(0) = perturbation, u(0) = 0).
Each cycle of the oscillation is cut at its maximum of z (z' = 1 - e^w turns negative, located by Newton on exact
partial steps, so the peak is as accurate as the stepper) and its minimum (a maximum whose rise is below
REBOUND x the last cycle's amplitude is a rebound inside a slip, skipped); with a_k = half the peak-to-peak
stretch of cycle k and T_k the time between its maxima, the observables are

    growth_rate = ln(a_k/a_(k-1)) / T_k    (reduced, per unit tau; Re sigma of the linear theory while small),
    period      = T_k                      (tau units; 2 pi / Im sigma, -> 2 pi / omega_c at the line),
    amplitude   = a_k once the cycles are stationary (0 for steady sliding).

How a regime is decided (never guessed; ``undecided`` when the budget ends first; constants in sweep/accuracy.py):

* ``runaway``: the slip velocity passed RUNAWAY_XI_DOT.
* ``steady``: the state (max |z|, |u|) fell below DECAYED x perturbation, or the growth rate is negative and has
  converged (three successive cycles agree to GROWTH_RTOL): a linear decay is then established and the
  perturbation dies. Without two full cycles (strong damping, or an overdamped return without any) the growth
  rate is the decay rate of the state from 0.1 to DECAYED x perturbation.
* ``stick_slip`` / ``neutral``: the cycles are stationary, |a_k/a_(k-1) - 1| <= STATIONARY_TOL over three cycles.
  A long transient is not mistaken for an attractor: a transient with |growth_rate| T above STATIONARY_TOL is not
  stationary, and one below it (a drift of < 1e-7 per cycle) is called neutral only where the amplitude is still
  that of the first cycle (within NEUTRAL_SPREAD) and the first cycle is no larger than NEUTRAL_START x the
  linear oscillation through the initial state; other stationary cycles are a limit cycle reached from the
  perturbation (stick_slip). Quasi-static m2 = 0 at the line is the neutral case.
"""

from __future__ import annotations

import functools
import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit

from ..accuracy import (
    DECAYED,
    GROWTH_RTOL,
    MIN_CYCLES,
    NEUTRAL_SPREAD,
    NEUTRAL_START,
    REBOUND,
    SLAVED_ENTRY,
    SLAVED_INERTIA,
    SLAVED_TOL,
    STATIONARY_TOL,
    STIFF_SWITCH,
    W_RUNAWAY,
)
from ..jitcache import pin, pin_module
from ..status import Status
from .models.driven import (
    DrivenParams,
    inertial_system,
    log_velocity_rate,
    make_driven_rhs,
    make_slaved_rhs,
    stiffness,
)
from .models.state_laws import STATE_LAWS
from .solvers import DP5, RODAS3
from .solvers.controllers import ERR_FLOOR, I_CONTROLLER, PI_CONTROLLER, accepted_factor_log2, rejected_factor
from .solvers.explicit import make_erk_step
from .solvers.fastmath import FAST
from .solvers.rosenbrock_step import make_rodas3_step, scratch
from .solvers.vmath import EXP_MAX, log2_approx

__all__ = ["DrivenOutputs", "DrivenParams", "DrivenResult", "DrivenSettings", "Regime", "point_kernel",
           "simulate_driven", "simulate_point"]

OK, MAX_STEPS, STEP_UNDERFLOW = int(Status.OK), int(Status.MAX_STEPS), int(Status.STEP_UNDERFLOW)
BREAKDOWN = int(Status.QUASISTATIC_BREAKDOWN)
H_START = 0.01
"""First step in tau, times 1/(1 + k) (and at most 0.1 gamma/A with inertia): a fraction of the fastest time."""
H_FLOOR = 1e-15
"""Smallest step in tau relative to 1 + tau before the point is flagged step_underflow."""
HISTORY = 4
"""Cycles kept for the decisions."""
DP5_ORDER, RODAS3_ORDER = DP5.error_order, RODAS3.order_hat
_STAGES = DP5.stages


class Regime(IntEnum):
    """Outcome of a driven point (append-only, like :class:`sweep.status.Status`)."""

    STEADY = 0
    STICK_SLIP = 1
    NEUTRAL = 2
    RUNAWAY = 3
    UNDECIDED = 4


class DrivenSettings(NamedTuple):
    """How one driven point is run (the same for every point of a scene)."""

    perturbation: float
    """Initial spring stretch z(0) [1]."""
    rtol: float
    """Local tolerance of the stepper (absolute floor rtol x the largest |z| met)."""
    max_cycles: int
    max_steps: int


class DrivenResult(NamedTuple):
    """One driven point's outcome; NaN where an observable does not apply (e.g. no full cycle)."""

    regime: int
    status: int
    """ok, max_steps or step_underflow (regime undecided), quasistatic_breakdown (regime runaway)."""
    growth_rate: float
    period: float
    amplitude: float
    cycles: int
    steps: int
    peak_w: float
    """Largest ln xi' met."""


class DrivenOutputs(NamedTuple):
    """Flat per-point output arrays of :func:`driven_batch` (one field per :class:`DrivenResult` field)."""

    regime: np.ndarray
    status: np.ndarray
    growth_rate: np.ndarray
    period: np.ndarray
    amplitude: np.ndarray
    cycles: np.ndarray
    steps: np.ndarray
    peak_w: np.ndarray

    @classmethod
    def empty(cls, n: int) -> DrivenOutputs:
        nan = lambda: np.full(n, np.nan)  # noqa: E731
        return cls(np.zeros(n, np.int8), np.zeros(n, np.int8), nan(), nan(), nan(), np.zeros(n, np.int64),
                   np.zeros(n, np.int64), nan())


_stiff_step = make_rodas3_step(inertial_system)


def _make_advance(rhs, with_inertia: bool, variant: tuple[str, str]):
    """advance(stiff, y, h, p, K, ys, y_new, err, work) -> (done, ln xi' at y_new or NaN): one step of size h from
    y (rates in K[0]): Dormand-Prince (FSAL: its last stage is the rates at y_new, kept in K[-1]), or RODAS3 where
    ``stiff`` (inertial variant only) with its scratch ``work`` (a :class:`RodasWork` from ``scratch``). Every kernel
    a factory builds is pinned to its ``variant`` (state law, model): one whose closure holds an unpinned dispatcher
    misses numba's disk cache in every new process."""
    erk_step = make_erk_step(rhs, _size(with_inertia), DP5)

    @njit(inline="always", fastmath=FAST, error_model="numpy")
    def advance(stiff, y, h, p, K, ys, y_new, err, work):
        """(done, FSAL): done False if the Rosenbrock matrix was singular; FSAL True when the rates at y_new are
        in K[-1] (the explicit FSAL stepper) and ln xi' there is the returned aux, NaN otherwise."""
        if with_inertia and stiff:
            return _stiff_step(0.0, y, h, p, y_new, err, work), math.nan
        return True, erk_step(K, ys, y, h, p, y_new, err)

    return pin(advance, *variant)


NEWTON_FINISH = 1e-3
"""Newton correction (a fraction of the step) below which an extremum's z is finished by its Taylor series
(:func:`_make_extremum`)."""


@njit(inline="always", fastmath=FAST, error_model="numpy")
def _first_guess(dz0, dz1, ddz0_h, ddz1_h):
    """The fraction theta of a step where z' = 0, from z' (dz0, dz1: opposite signs) and z'' times the step
    (ddz0_h, ddz1_h) at its ends: the root in [0, 1] of the cubic Hermite interpolant of z' (Newton from the root of
    the quadratic through dz0, ddz0_h and dz1, itself Newton from the linear interpolation's root). Where a stage is
    unusable (a vanishing slope, a root outside the step) the previous guess stands."""
    theta = dz0 / (dz0 - dz1)
    c = dz1 - dz0 - ddz0_h  # the quadratic dz0 + ddz0_h s + c s^2
    for _ in range(3):
        slope = ddz0_h + 2.0 * c * theta
        if slope == 0.0:
            break
        step = (dz0 + theta * (ddz0_h + c * theta)) / slope
        if not 0.0 <= theta - step <= 1.0:
            break
        theta -= step
    for _ in range(6):  # the cubic's coefficients in the Hermite basis (value and slope at s = 0, 1)
        s = theta
        q = (2.0 * s - 3.0) * s * s * (dz0 - dz1) + dz0 + s * (s - 1.0) * ((s - 1.0) * ddz0_h + s * ddz1_h)
        dq = 6.0 * s * (s - 1.0) * (dz0 - dz1) + (s - 1.0) * (3.0 * s - 1.0) * ddz0_h + s * (3.0 * s - 2.0) * ddz1_h
        if dq == 0.0:
            break
        step = q / dq
        if not 0.0 <= s - step <= 1.0:
            break
        theta = s - step
        if abs(step) < 1e-15:
            break
    return theta


def _make_extremum(rhs, advance, variant: tuple[str, ...], slaved: bool = False):
    """extremum(stiff, y0, y1, h, dz0, dz1, p, K, ys, yt, err, work, dy) -> (theta h, z there): the extremum of z
    inside a step of size h from y0 to y1 where z' changes sign (dz0 at the start, dz1 at the end): a first guess from
    z' and z'' at both ends (:func:`_first_guess`), then Newton on exact partial steps of size theta h with the step's
    own method (z'' = -xi' (ln xi')'; on the slaved inertial form, ``slaved``, (ln xi')' is the quasi-static
    balance's rate: a Newton slope, exact to O(g e^w)). Once a Newton correction delta is below NEWTON_FINISH, z at
    theta + delta is the partial step's z continued by its Taylor series to second order, off by
    O((delta h)^3 z^(3)), far below the step's own error, instead of one more partial step: mostly one partial step
    per extremum."""

    @njit(fastmath=FAST, error_model="numpy")
    def extremum(stiff, y0, y1, h, dz0, dz1, p, K, ys, yt, err, work, dy):
        rate_of = DrivenParams(p.k, p.a, p.b, 0.0) if slaved else p
        lw1 = rhs(y1, p, dy)
        ddz1_h = -math.exp(min(lw1, EXP_MAX)) * log_velocity_rate(y1, dy, rate_of) * h
        lw0 = rhs(y0, p, K[0])  # a partial step leaves K[0] as it found it
        theta = _first_guess(dz0, dz1, -math.exp(min(lw0, EXP_MAX)) * log_velocity_rate(y0, K[0], rate_of) * h,
                             ddz1_h)
        for _ in range(4):
            advance(stiff, y0, theta * h, p, K, ys, yt, err, work)
            lw = rhs(yt, p, dy)
            ddz = -math.exp(min(lw, EXP_MAX)) * log_velocity_rate(yt, dy, rate_of)
            if ddz == 0.0 or not math.isfinite(ddz):
                break
            delta = -dy[0] / (ddz * h)
            if abs(delta) < NEWTON_FINISH and 0.0 <= theta + delta <= 1.0:
                s = delta * h
                return (theta + delta) * h, yt[0] + s * (dy[0] + 0.5 * ddz * s)
            theta = min(max(theta + delta, 0.0), 1.0)
        advance(stiff, y0, theta * h, p, K, ys, yt, err, work)
        return theta * h, yt[0]

    return pin(extremum, *variant)


@njit(cache=True)
def _linear_amplitude(p, perturbation):
    """Amplitude of the small oscillation through the initial state (z, u) = (perturbation, 0), where
    z' = -k perturbation, in the linear theory: z = R e^(sigma_r tau) cos(omega tau + phi) with sigma = sigma_r
    +- i omega the roots of s^2 + (k - a) s + k = 0 (docs/physics.md 3b, reduced by A); NaN without oscillation.
    With inertia (g > 0) the start has xi' = 1, z' = 0: it is an extremum, R ~ perturbation."""
    if p.g > 0.0:
        return perturbation
    disc = p.k - 0.25 * (p.k - p.a) ** 2
    if disc <= 0.0:
        return math.nan
    omega, sigma_r = math.sqrt(disc), 0.5 * (p.a - p.k)
    return perturbation * math.sqrt(1.0 + ((p.k + sigma_r) / omega) ** 2)


@njit(cache=True)
def _decide(amp, grow, perturbation, amp_first, a_start, cycles):
    """The regime after a cycle (module docstring), or UNDECIDED to go on."""
    a_k = amp[-1]
    if a_k < DECAYED * perturbation:
        return Regime.STEADY
    if cycles < MIN_CYCLES + 1:
        return Regime.UNDECIDED
    g0, g1, g2 = grow[-3], grow[-2], grow[-1]
    if g2 < 0.0 and abs(g1 - g2) <= GROWTH_RTOL * abs(g2) and abs(g0 - g1) <= GROWTH_RTOL * abs(g1):
        # an established linear decay, unless the cycles are (nearly) stationary: then the stationary test decides
        if abs(amp[-1] / amp[-2] - 1.0) > STATIONARY_TOL:
            return Regime.STEADY
    stationary = True
    for i in range(HISTORY - 3, HISTORY):
        if not abs(amp[i] / amp[i - 1] - 1.0) <= STATIONARY_TOL:
            stationary = False
    if stationary:
        if abs(a_k / amp_first - 1.0) <= NEUTRAL_SPREAD and amp_first <= NEUTRAL_START * a_start:
            return Regime.NEUTRAL
        return Regime.STICK_SLIP
    return Regime.UNDECIDED


INERTIAL_NOT_CACHED = True
"""The inertial variant is compiled in every process, never loaded from numba's disk cache: loaded from the cache
it gave slightly different numbers (3 of 40 growth rates, a few steps) from the same kernel compiled in the process
that wrote the cache (numba 0.68; found by the dask bitwise test, whose workers load what the main
process compiles). A resumed or distributed run must give exactly the numbers of one uninterrupted run, so this
variant pays its compile time (~6 s) in each process until the cause is understood."""


def cached(with_inertia: bool) -> bool:
    """Whether a driven kernel of this variant uses numba's disk cache (:data:`INERTIAL_NOT_CACHED`)."""
    return not (with_inertia and INERTIAL_NOT_CACHED)


def _size(with_inertia: bool) -> int:
    """Components of the state: (z, u) quasi-static, (z, u, w) with inertia."""
    return 3 if with_inertia else 2


@njit(inline="always")
def _largest(size, v):
    """max(size, |v_0|, |v_1|, ...), NaN if any of them is NaN (a step that produced one is then rejected)."""
    for m in range(v.size):
        a = abs(v[m])
        if a > size or a != a:
            size = a
    return size


@functools.cache
def scalar_parts(law: str, with_inertia: bool):
    """(rhs, advance, extremum) of one variant, made once per process: the driver below and the inertial lanes
    (sweep/integrate/lanes_driven_inertial.py, which locate their extrema with this ``extremum`` and take their
    stiff RODAS3 steps with this ``advance``) share them."""
    rhs = make_driven_rhs(STATE_LAWS[law].rate, with_inertia)
    variant = (law, "inertial" if with_inertia else "quasistatic")
    advance = _make_advance(rhs, with_inertia, variant)
    return rhs, advance, _make_extremum(rhs, advance, variant)


def _slaved_parts(law: str):
    """(rhs, advance, extremum) of the inertial model on its slow manifold (:func:`make_slaved_rhs`), made once per
    process (the inertial lanes locate their extrema on the manifold with this ``extremum``)."""
    rhs = make_slaved_rhs(STATE_LAWS[law].rate)
    variant = (law, "slaved")
    advance = _make_advance(rhs, True, variant)  # (z, u, w), always called with stiff False
    return rhs, advance, _make_extremum(rhs, advance, variant, slaved=True)


@njit(inline="always", fastmath=FAST, error_model="numpy")
def _inertia_size(y, p):
    """The inertial term against the slow manifold's bounds (:data:`SLAVED_INERTIA`): max(-P/low, P/high,
    g e^w/slow) with P = gamma xi''/A = balance - w at the inertial state y = (z, u, w); the slaved form holds where
    this is <= 1."""
    balance = p.k * y[0] - y[1] * (p.a + p.b * y[1]) - y[1]
    low, high, slow = SLAVED_INERTIA
    return max((y[2] - balance) / low, (balance - y[2]) / high, p.g * math.exp(min(y[2], EXP_MAX)) / slow)


def _make_simulate(law: str, with_inertia: bool, slaved: bool = False):
    """simulate(p, settings) -> DrivenResult for one state law, compiled for the quasi-static model only
    (``with_inertia`` False: the stiff stepper is not compiled into the loop, which was 18 % slower with it, and
    compiling takes half the time) or for both; with ``slaved`` (inertial only) the inertial model runs on its slow
    manifold where inertia is below :data:`SLAVED_INERTIA` (:func:`make_slaved_rhs`: the stick phases and the
    decay after a slip, where the full system took ~2/3 of the steps of a stick-slip cycle, all RODAS3)."""
    rhs, advance, extremum = scalar_parts(law, with_inertia)
    rhs_s, advance_s, extremum_s = _slaved_parts(law) if slaved else (rhs, advance, extremum)
    n = _size(with_inertia)
    variant = (law, ("inertial-slaved" if slaved else "inertial") if with_inertia else "quasistatic")

    @njit(cache=cached(with_inertia), fastmath=FAST, error_model="numpy")
    def simulate(p, settings):
        perturbation, rtol = settings.perturbation, settings.rtol
        K, ys = np.empty((_STAGES, n)), np.empty(n)
        y, y_new, err_v, dy = np.zeros(n), np.empty(n), np.empty(n), np.empty(n)
        yt, dyt = np.empty(n), np.empty(n)  # the extremum search's own
        y[0] = perturbation
        tau = 0.0
        size = perturbation  # largest |z| met: the error scale of both states (they oscillate about 0)
        h = H_START / (1.0 + p.k) if p.g == 0.0 else min(H_START / (1.0 + p.k), 0.1 * p.g)
        amp = np.full(HISTORY, np.nan)
        per = np.full(HISTORY, np.nan)
        grow = np.full(HISTORY, np.nan)
        z_min, t_max_prev = math.inf, math.nan
        after_rebound = False  # the last maximum was a rebound (REBOUND)
        norm_tenth, t_tenth = math.nan, math.nan
        amp_first = math.nan
        a_start = _linear_amplitude(p, perturbation)
        cycles, steps = 0, 0
        w_peak = -math.inf
        lerr_prev, rejected = log2_approx(1e-4), False  # log2 of the last accepted error norm
        work = scratch(n)
        on_manifold = False  # the slaved form in use (``slaved`` only)
        rhs(y, p, dy)
        dz = dy[0]
        while steps < settings.max_steps:
            for m in range(n):  # (element loops: a slice assignment compiles numba's shape-mismatch error path, ~2 s)
                K[0, m] = dy[m]
            # explicit where it is stable, RODAS3 where the inertial mode's rate would hold the explicit step down
            stiff = with_inertia and p.g > 0.0 and not on_manifold and h * stiffness(y, p) > STIFF_SWITCH
            q = RODAS3_ORDER if stiff else DP5_ORDER
            if on_manifold:
                done, lw_fsal = advance_s(False, y, h, p, K, ys, y_new, err_v, work)
            else:
                done, lw_fsal = advance(stiff, y, h, p, K, ys, y_new, err_v, work)
            steps += 1
            scale = (SLAVED_TOL * rtol if on_manifold else rtol) * _largest(size, y_new)
            err = _largest(0.0, err_v) / scale if done else math.nan
            if not err <= 1.0:  # rejected (NaN included: a stage beyond the exponent clamp, a singular matrix)
                h *= rejected_factor(I_CONTROLLER, err, q)
                rejected = True
                if h < H_FLOOR * (1.0 + tau):
                    return DrivenResult(Regime.UNDECIDED, STEP_UNDERFLOW, grow[-1], per[-1], math.nan, cycles, steps,
                                        w_peak)
                continue
            if stiff:
                lw1 = rhs(y_new, p, dy)
            else:  # FSAL: dp5's last stage is the rates at y_new
                lw1 = lw_fsal
                for m in range(n):
                    dy[m] = K[_STAGES - 1, m]
            if on_manifold:  # w follows the slow flow (make_slaved_rhs)
                y_new[2] = lw1
            dz1 = dy[0]
            w_peak = max(w_peak, lw1)
            if lw1 > W_RUNAWAY:  # an accepted state: the slip velocity itself is past the threshold
                return DrivenResult(Regime.RUNAWAY, BREAKDOWN, grow[-1], per[-1], math.nan, cycles, steps, w_peak)
            norm = _largest(0.0, y_new)
            if norm < DECAYED * perturbation:  # decayed (also without cycles: an overdamped return)
                if not math.isfinite(grow[-1]):  # fewer than two cycles: the decay of the state since it was 0.1x
                    grow[-1] = math.log(norm / norm_tenth) / (tau + h - t_tenth)
                return DrivenResult(Regime.STEADY, OK, grow[-1], per[-1], 0.0, cycles, steps, w_peak)
            if norm < 0.1 * perturbation and not math.isfinite(t_tenth):
                norm_tenth, t_tenth = norm, tau + h
            if dz > 0.0 and dz1 <= 0.0:  # a maximum of z: a cycle ends
                if on_manifold:
                    dt, z_top = extremum_s(False, y, y_new, h, dz, dz1, p, K, ys, yt, err_v, work, dyt)
                else:
                    dt, z_top = extremum(stiff, y, y_new, h, dz, dz1, p, K, ys, yt, err_v, work, dyt)
                t_peak = tau + dt
                rebound = 0.5 * (z_top - z_min) < REBOUND * amp[-1]  # not a cycle end (False before two cycles)
                if not rebound and z_min < math.inf and math.isfinite(t_max_prev):
                    cycles += 1
                    for i in range(HISTORY - 1):
                        amp[i], per[i], grow[i] = amp[i + 1], per[i + 1], grow[i + 1]
                    amp[-1], per[-1] = 0.5 * (z_top - z_min), t_peak - t_max_prev
                    grow[-1] = math.log(amp[-1] / amp[-2]) / per[-1] if amp[-2] > 0.0 else math.nan
                    if cycles == 1:
                        amp_first = amp[-1]
                    regime = _decide(amp, grow, perturbation, amp_first, a_start, cycles)
                    if regime != Regime.UNDECIDED:
                        amplitude = 0.0 if regime == Regime.STEADY else amp[-1]
                        return DrivenResult(regime, OK, grow[-1], per[-1], amplitude, cycles, steps, w_peak)
                    if cycles >= settings.max_cycles:
                        return DrivenResult(Regime.UNDECIDED, OK, grow[-1], per[-1], math.nan, cycles, steps, w_peak)
                if not rebound:
                    t_max_prev = t_peak
                after_rebound = rebound
            elif dz < 0.0 and dz1 >= 0.0:  # a minimum of z (the lower one where the maximum between was a rebound)
                if on_manifold:
                    z_new = extremum_s(False, y, y_new, h, dz, dz1, p, K, ys, yt, err_v, work, dyt)[1]
                else:
                    z_new = extremum(stiff, y, y_new, h, dz, dz1, p, K, ys, yt, err_v, work, dyt)[1]
                z_min = min(z_min, z_new) if after_rebound else z_new
            for m in range(n):
                y[m] = y_new[m]
            tau += h
            if slaved:  # onto the slow manifold where inertia is small and the full system is on it (w within
                # SLAVED_ENTRY of the manifold's: the fast mode has relaxed, and the expansion holds there), back to
                # the full system past twice the bounds
                inertia = _inertia_size(y, p)
                if on_manifold:
                    switch = inertia > 2.0
                else:
                    switch = inertia <= 1.0 and abs(rhs_s(y, p, dyt) - y[2]) <= SLAVED_ENTRY * rtol * size
                if switch:
                    on_manifold = not on_manifold
                    if on_manifold:  # w onto the manifold (moves by <= SLAVED_ENTRY x the stepper's tolerance)
                        y[2] = rhs_s(y, p, dy)
                    else:  # w is the manifold's: the full system starts without an initial layer
                        rhs(y, p, dy)
                    dz1 = dy[0]
            dz = dz1
            size = max(size, abs(y[0]))
            lerr = log2_approx(max(err, ERR_FLOOR))  # the lanes' logarithm: a step factor needs no more than 0.5 %
            h *= accepted_factor_log2(I_CONTROLLER if stiff else PI_CONTROLLER, lerr, lerr_prev, q, rejected)
            lerr_prev = lerr
            rejected = False
        return DrivenResult(Regime.UNDECIDED, MAX_STEPS, grow[-1], per[-1], math.nan, cycles, steps, w_peak)

    return pin(simulate, *variant)


@functools.cache
def point_kernel(law: str = "aging", inertia: bool = False, slaved: bool = False):
    """simulate(p: DrivenParams, settings: DrivenSettings) -> DrivenResult for a state law: the quasi-static variant
    (p.g = 0) or, with ``inertia``, the variant that also runs the inertial model (p.g > 0; aging law only), with
    ``slaved`` on its slow manifold where inertia is small (:data:`SLAVED_INERTIA`). Each is compiled on first use,
    so that a scene compiles only the variant its points need."""
    if inertia and law != "aging":
        raise ValueError(f"the driven scene runs with inertia under the aging law only, not {law!r}")
    return _make_simulate(law, inertia, slaved and inertia)


def simulate_point(p: DrivenParams, settings: DrivenSettings, law: str = "aging") -> DrivenResult:
    """One driven point (reduced parameters in ``p``; state z = tau - xi, u = ln psi and, with inertia,
    w = ln xi'): see the module docstring."""
    return point_kernel(law, p.g > 0.0)(p, settings)


def simulate_driven(chi: float, mu1: float, m2: float, A: float, perturbation: float = 1e-3, rtol: float = 1e-9,
                    max_cycles: int = 2000, max_steps: int = 5_000_000, gamma: float = 0.0,
                    state_law: str = "aging") -> dict[str, float | str | int]:
    """Simulate one driven point (reduced parameters chi, mu1(V), m2, A [1]); ``gamma`` = V^2/(g D0) [1] > 0 adds
    inertia (the full Newton equation), 0 is the quasi-static model.

    Returns a dict with ``regime`` (name), ``growth_rate`` [1/tau], ``period`` [tau], ``amplitude`` [1, half the
    peak-to-peak spring stretch tau - xi], ``cycles``, ``steps`` and ``peak_log_velocity`` (largest ln xi').
    ``perturbation`` is the initial stretch z(0) [1]; ``rtol`` the stepper's local tolerance (absolute floor
    rtol x perturbation)."""
    for name, value in (("A", A), ("perturbation", perturbation), ("rtol", rtol)):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    if not (math.isfinite(chi) and chi > 0.0):
        raise ValueError(f"chi must be finite and > 0, got {chi!r}")
    if not (math.isfinite(gamma) and gamma >= 0.0):
        raise ValueError(f"gamma must be finite and >= 0, got {gamma!r}")
    if state_law not in STATE_LAWS or (gamma > 0.0 and not STATE_LAWS[state_law].inertial):
        raise ValueError(f"state_law must be one of {sorted(STATE_LAWS)} (inertia with "
                         f"{[n for n, law in STATE_LAWS.items() if law.inertial]} only), got {state_law!r}")
    r = simulate_point(DrivenParams(chi / A, mu1 / A, m2 / A, gamma / A),
                       DrivenSettings(perturbation, rtol, max_cycles, max_steps), state_law)
    return {"regime": Regime(r.regime).name.lower(), "status": Status(r.status).name.lower(),
            "growth_rate": r.growth_rate, "period": r.period, "amplitude": r.amplitude, "cycles": int(r.cycles),
            "steps": int(r.steps), "peak_log_velocity": r.peak_w}


pin_module(__name__)
