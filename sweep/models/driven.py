"""Driven scene (PHYSICS.md 3b): stability of steady sliding and stick-slip, per point, quasi-static or inertial.

The drive keeps moving at V. In reduced time tau, with the spring stretch z = tau - xi and u = ln psi,

    A ln(xi' psi) = chi z - dmu(psi)   =>   w = ln xi' = (chi z - mu1 u - m2 u^2)/A - u,
    z' = 1 - e^w,    u' = e^-u - e^w,

an autonomous system in (z, u) whose fixed point z = u = 0 is steady sliding. The log-velocity w is a function of
the state, so the slip velocity is never a state variable: stick phases (w << 0) and slip phases (w >> 0, where
xi' rises by orders of magnitude) are the same smooth equations, and the adaptive Dormand-Prince 5(4) stepper
(PI controller) takes steps of ~A/(chi e^w) in a slip and long steps in a stick. A slip velocity beyond
RUNAWAY_XI_DOT ends the point as ``runaway`` (the quasi-static model breaks down: m2 = 0 below the Hopf line
overflows in finite time), before any exponent can overflow.

With inertia (gamma = V^2/(g D0) > 0) the Newton equation gamma xi'' = chi z - dmu(psi) - A ln(xi' psi) makes
w = ln xi' a third state, w' = ((chi z - dmu)/A - u - w) e^-w A/gamma, relaxing at the rate A/(gamma xi'): stiff
for small gamma/A and in the stick phases of stick-slip (xi' << 1). A step whose size times that rate exceeds
STIFF_SWITCH is taken with the L-stable RODAS3 and the analytic 3x3 Jacobian (:func:`inertial_system`) instead of
Dormand-Prince; near steady sliding (xi' ~ 1, where the Hopf line is located) the explicit stepper stays in use.

The run starts from steady sliding with the spring stretched by ``perturbation`` (z(0) = perturbation, u(0) = 0).
Each cycle of the oscillation is cut at its maximum of z (z' = 1 - e^w turns negative, located by Newton on exact
partial steps, so the peak is as accurate as the stepper) and its minimum; with a_k = half the peak-to-peak
stretch of cycle k and T_k the time between its maxima, the observables are

    growth_rate = ln(a_k/a_(k-1)) / T_k    (reduced, per unit tau; Re sigma of the linear theory while small),
    period      = T_k                      (tau units; 2 pi / Im sigma, -> 2 pi / omega_c at the line),
    amplitude   = a_k once the cycles are stationary (0 for steady sliding).

How a regime is decided (never guessed; ``undecided`` when the budget ends first):

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

import math
from enum import IntEnum

import numpy as np
from numba import njit, prange

from ..jitcache import pin, pin_module
from ..solvers import DP5
from ..solvers.rosenbrock_step import ERROR_EXPONENT, make_rodas3_step, scratch
from ..status import Status
from .stop import EXP_MAX, FAST

__all__ = ["Regime", "simulate_driven", "simulate_batch", "RUNAWAY_XI_DOT"]

OK, MAX_STEPS, STEP_UNDERFLOW = int(Status.OK), int(Status.MAX_STEPS), int(Status.STEP_UNDERFLOW)
BREAKDOWN = int(Status.QUASISTATIC_BREAKDOWN)


class Regime(IntEnum):
    """Outcome of a driven point (append-only, like :class:`sweep.status.Status`)."""

    STEADY = 0
    STICK_SLIP = 1
    NEUTRAL = 2
    RUNAWAY = 3
    UNDECIDED = 4


RUNAWAY_XI_DOT = 1e8
"""Slip velocity xi' = V_slip/V beyond which the quasi-static model is declared broken down (regime runaway)."""
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
"""A step runs RODAS3 instead of Dormand-Prince where h times the inertial mode's rate exceeds this (DP5 is
stable up to ~3.3 on the negative axis; half of that leaves the explicit steps accuracy-limited)."""
MIN_CYCLES = 3
HISTORY = 4  # cycles kept for the decisions

_, _A, _B, _E = (np.ascontiguousarray(x) for x in DP5.arrays())
_STAGES = _B.size


@njit(cache=True, fastmath=FAST, error_model="numpy")
def _rates(z, u, w, k, a, b, g):
    """(z', u', w', ln xi') of the driven equations; k = chi/A, a = mu1/A, b = m2/A, g = gamma/A. Quasi-static
    (g = 0): ln xi' is the balance k z - a u - b u^2 - u itself and the state w is unused (w' = 0). Inertial:
    w = ln xi' is a state, (gamma/A) xi'' = k z - a u - b u^2 - A ln(xi' psi)/A gives w' = (balance - w) e^-w / g
    (PHYSICS.md 3b with the spring chi (tau - xi))."""
    balance = k * z - u * (a + b * u) - u
    if g == 0.0:
        lw, dw = balance, 0.0
    else:
        lw, dw = w, (balance - w) * math.exp(min(-w, EXP_MAX)) / g
    e = math.exp(min(lw, EXP_MAX))
    return 1.0 - e, math.exp(min(-u, EXP_MAX)) - e, dw, lw


@njit(cache=True, fastmath=FAST, error_model="numpy")
def _step(z, u, w, h, k, a, b, g, kz, ku, kw):
    """One Dormand-Prince step of size h from (z, u, w); stage derivatives in kz, ku, kw (stage 0 given).
    Returns (z1, u1, w1, errors in z, u, w, largest ln xi' met)."""
    w_max = -math.inf
    for i in range(1, _STAGES):
        zi, ui, wi = z, u, w
        for j in range(i):
            zi += h * _A[i, j] * kz[j]
            ui += h * _A[i, j] * ku[j]
            wi += h * _A[i, j] * kw[j]
        kz[i], ku[i], kw[i], lw = _rates(zi, ui, wi, k, a, b, g)
        w_max = max(w_max, lw)
    z1, u1, w1, ez, eu, ew = z, u, w, 0.0, 0.0, 0.0
    for i in range(_STAGES):
        z1 += h * _B[i] * kz[i]
        u1 += h * _B[i] * ku[i]
        w1 += h * _B[i] * kw[i]
        ez += h * _E[i] * kz[i]
        eu += h * _E[i] * ku[i]
        ew += h * _E[i] * kw[i]
    return z1, u1, w1, ez, eu, ew, w_max


@njit(inline="always", fastmath=FAST, error_model="numpy")
def inertial_system(s, y, p, f, J, ft, jacobian):
    """The inertial driven equations (:func:`_rates`, g > 0) with their Jacobian in (z, u, w), for the stiff
    phases (:func:`sweep.solvers.rosenbrock_step.make_rodas3_step`; autonomous: df/dtau = 0)."""
    k, a, b, g = p
    z, u, w = y[0], y[1], y[2]
    balance = k * z - u * (a + b * u) - u
    e, e_u, c = math.exp(min(w, EXP_MAX)), math.exp(min(-u, EXP_MAX)), math.exp(min(-w, EXP_MAX)) / g
    f[0], f[1], f[2] = 1.0 - e, e_u - e, (balance - w) * c
    if jacobian:
        J[0, 0], J[0, 1], J[0, 2] = 0.0, 0.0, -e
        J[1, 0], J[1, 1], J[1, 2] = 0.0, -e_u, -e
        J[2, 0], J[2, 1], J[2, 2] = k * c, -(a + 2.0 * b * u + 1.0) * c, -(1.0 + balance - w) * c
        ft[0], ft[1], ft[2] = 0.0, 0.0, 0.0


_stiff_step = make_rodas3_step(inertial_system)


@njit(inline="always", fastmath=FAST, error_model="numpy")
def _stiffness(z, u, w, k, a, b, g):
    """|dw'/dw| of the inertial equations: the rate of the stiff mode A/(gamma xi') (0 without inertia)."""
    if g == 0.0:
        return 0.0
    balance = k * z - u * (a + b * u) - u
    return abs(1.0 + balance - w) * math.exp(min(-w, EXP_MAX)) / g


@njit(inline="always", fastmath=FAST, error_model="numpy")
def _advance(stiff, z, u, w, h, k, a, b, g, kz, ku, kw, work):
    """One step of size h from (z, u, w) whose rates are in kz[0], ku[0], kw[0]: Dormand-Prince, or RODAS3 where
    ``stiff``; returns (z1, u1, w1, ez, eu, ew) (NaN if the Rosenbrock matrix was singular)."""
    if not stiff:
        return _step(z, u, w, h, k, a, b, g, kz, ku, kw)[:6]
    y, y_new, err, K, M, piv, f, ft, ys = work
    y[0], y[1], y[2] = z, u, w
    if not _stiff_step(0.0, y, h, (k, a, b, g), y_new, err, K, M, piv, f, ft, ys):
        return math.nan, math.nan, math.nan, math.nan, math.nan, math.nan
    return y_new[0], y_new[1], y_new[2], err[0], err[1], err[2]


@njit(cache=True, fastmath=FAST, error_model="numpy")
def _extremum(stiff, z0, u0, w0, h, dz0, dz1, k, a, b, g, kz, ku, kw, work):
    """Time offset theta*h and value of the extremum of z inside a step of size h from (z0, u0, w0) where z'
    changes sign (dz0 at the start, dz1 at the end): linear interpolation of z' as a first guess, then Newton on
    exact partial steps of size theta*h with the step's own method (z'' = -xi' (ln xi')')."""
    theta = dz0 / (dz0 - dz1)
    for _ in range(4):
        kz[0], ku[0], kw[0], _lw = _rates(z0, u0, w0, k, a, b, g)
        zt, ut, wt, _ez, _eu, _ew = _advance(stiff, z0, u0, w0, theta * h, k, a, b, g, kz, ku, kw, work)
        dz, du, dw, lw = _rates(zt, ut, wt, k, a, b, g)
        dlw = k * dz - (a + 2.0 * b * ut) * du - du if g == 0.0 else dw
        ddz = -math.exp(min(lw, EXP_MAX)) * dlw
        if ddz == 0.0 or not math.isfinite(ddz):
            break
        delta = -dz / (ddz * h)
        theta = min(max(theta + delta, 0.0), 1.0)
        if abs(delta) < 1e-12:
            break
    kz[0], ku[0], kw[0], _lw = _rates(z0, u0, w0, k, a, b, g)
    zt = _advance(stiff, z0, u0, w0, theta * h, k, a, b, g, kz, ku, kw, work)[0]
    return theta * h, zt


@njit(cache=True)
def _linear_amplitude(k, a, g, perturbation):
    """Amplitude of the small oscillation through the initial state (z, u) = (perturbation, 0), where
    z' = -k perturbation, in the linear theory: z = R e^(sigma_r tau) cos(omega tau + phi) with sigma = sigma_r
    +- i omega the roots of s^2 + (k - a) s + k = 0 (PHYSICS.md 3b, reduced by A); NaN without oscillation.
    With inertia (g > 0) the start has xi' = 1, z' = 0: it is an extremum, R ~ perturbation."""
    if g > 0.0:
        return perturbation
    disc = k - 0.25 * (k - a) ** 2
    if disc <= 0.0:
        return math.nan
    omega, sigma_r = math.sqrt(disc), 0.5 * (a - k)
    return perturbation * math.sqrt(1.0 + ((k + sigma_r) / omega) ** 2)


def _make_simulate(with_inertia: bool):
    """simulate_point compiled for the quasi-static model only (``with_inertia`` False: the stiff stepper is not
    compiled into the loop, which was 18 % slower with it) or for both."""

    @njit(fastmath=FAST, error_model="numpy")
    def simulate(k, a, b, g, perturbation, rtol, max_cycles, max_steps):
        """:func:`simulate_point` (its docstring)."""
        kz = np.empty(_STAGES)
        ku = np.empty(_STAGES)
        kw = np.empty(_STAGES)
        z, u, w, tau = perturbation, 0.0, 0.0, 0.0
        size = perturbation  # largest |z| met: the error scale of both states (they oscillate about 0)
        h = 0.01 / (1.0 + k) if g == 0.0 else min(0.01 / (1.0 + k), 0.1 * g)
        amp = np.full(HISTORY, np.nan)
        per = np.full(HISTORY, np.nan)
        grow = np.full(HISTORY, np.nan)
        z_min, t_max_prev = math.inf, math.nan
        norm_tenth, t_tenth = math.nan, math.nan
        amp_first = math.nan
        a_start = _linear_amplitude(k, a, g, perturbation)
        cycles, steps = 0, 0
        w_peak = -math.inf
        err_prev = 1e-4
        work = (np.empty(3), np.empty(3), np.empty(3), *scratch(3))
        dz, du, dw, _lw = _rates(z, u, w, k, a, b, g)
        while steps < max_steps:
            kz[0], ku[0], kw[0] = dz, du, dw
            # explicit where it is stable, RODAS3 where the inertial mode's rate would hold the explicit step down
            stiff = with_inertia and g > 0.0 and h * _stiffness(z, u, w, k, a, b, g) > STIFF_SWITCH
            z1, u1, w1, ez, eu, ew = _advance(stiff, z, u, w, h, k, a, b, g, kz, ku, kw, work)
            steps += 1
            scale = rtol * max(size, abs(z1), abs(u1), abs(w1))
            err = max(abs(ez), abs(eu), abs(ew)) / scale
            if not err <= 1.0:  # rejected (NaN included: a stage beyond the exponent clamp)
                h *= max(0.2, 0.9 * err ** (ERROR_EXPONENT if stiff else -0.2)) if math.isfinite(err) else 0.25
                if h < 1e-15 * (1.0 + tau):
                    return Regime.UNDECIDED, STEP_UNDERFLOW, grow[-1], per[-1], math.nan, cycles, steps, w_peak
                continue
            dz1, du1, dw1, lw1 = _rates(z1, u1, w1, k, a, b, g)
            w_peak = max(w_peak, lw1)
            if lw1 > W_RUNAWAY:  # an accepted state: the slip velocity itself is past the threshold
                return Regime.RUNAWAY, BREAKDOWN, grow[-1], per[-1], math.nan, cycles, steps, w_peak
            norm = max(abs(z1), abs(u1), abs(w1))
            if norm < DECAYED * perturbation:  # decayed (also without cycles: an overdamped return)
                if not math.isfinite(grow[-1]):  # fewer than two cycles: the decay of the state since it was 0.1x
                    grow[-1] = math.log(norm / norm_tenth) / (tau + h - t_tenth)
                return Regime.STEADY, OK, grow[-1], per[-1], 0.0, cycles, steps, w_peak
            if norm < 0.1 * perturbation and not math.isfinite(t_tenth):
                norm_tenth, t_tenth = norm, tau + h
            if dz > 0.0 and dz1 <= 0.0:  # a maximum of z: a cycle ends
                dt, z_top = _extremum(stiff, z, u, w, h, dz, dz1, k, a, b, g, kz, ku, kw, work)
                t_peak = tau + dt
                if z_min < math.inf and math.isfinite(t_max_prev):
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
                        return regime, OK, grow[-1], per[-1], amplitude, cycles, steps, w_peak
                    if cycles >= max_cycles:
                        return Regime.UNDECIDED, OK, grow[-1], per[-1], math.nan, cycles, steps, w_peak
                t_max_prev = t_peak
            elif dz < 0.0 and dz1 >= 0.0:  # a minimum of z
                _dt, z_min = _extremum(stiff, z, u, w, h, dz, dz1, k, a, b, g, kz, ku, kw, work)
            z, u, w, tau = z1, u1, w1, tau + h
            dz, du, dw = dz1, du1, dw1
            size = max(size, abs(z))
            err = max(err, 1e-10)
            if stiff:
                h *= min(5.0, max(0.2, 0.9 * err ** ERROR_EXPONENT))
            else:  # PI step-size control (Gustafsson), exponents 0.7/5 and 0.4/5
                h *= min(5.0, max(0.2, 0.9 * err ** -0.14 * err_prev ** 0.08))
            err_prev = err
        return Regime.UNDECIDED, MAX_STEPS, grow[-1], per[-1], math.nan, cycles, steps, w_peak

    return pin(simulate, "inertial" if with_inertia else "quasistatic")


_simulate_quasistatic = _make_simulate(False)
_simulate_inertial = _make_simulate(True)


@njit(cache=True)
def simulate_point(k, a, b, g, perturbation, rtol, max_cycles, max_steps):
    """One driven point (reduced k = chi/A, a = mu1/A, b = m2/A; g = gamma/A, 0 for the quasi-static model;
    state z = tau - xi, u = ln psi and, with inertia, w = ln xi'). Returns (regime, status, growth_rate, period,
    amplitude, cycles, steps, peak log-velocity w); NaN where an observable does not apply (e.g. no full cycle).
    status: ok, max_steps or step_underflow (regime undecided), quasistatic_breakdown (regime runaway)."""
    if g == 0.0:
        return _simulate_quasistatic(k, a, b, g, perturbation, rtol, max_cycles, max_steps)
    return _simulate_inertial(k, a, b, g, perturbation, rtol, max_cycles, max_steps)


@njit(parallel=True, cache=True)
def simulate_batch(k, a, b, g, perturbation, rtol, max_cycles, max_steps, regime, status, growth_rate, period,
                   amplitude, cycles, steps, peak_w):
    """Every point of flat arrays k, a, b (one thread per point at a time; a point's arithmetic does not depend
    on the others)."""
    for i in prange(k.size):
        (regime[i], status[i], growth_rate[i], period[i], amplitude[i], cycles[i], steps[i],
         peak_w[i]) = simulate_point(k[i], a[i], b[i], g[i], perturbation, rtol, max_cycles, max_steps)


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


def simulate_driven(chi: float, mu1: float, m2: float, A: float, perturbation: float = 1e-3, rtol: float = 1e-9,
                    max_cycles: int = 2000, max_steps: int = 5_000_000,
                    gamma: float = 0.0) -> dict[str, float | str | int]:
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
    regime, status, g, T, amp, cycles, steps, w = simulate_point(chi / A, mu1 / A, m2 / A, gamma / A, perturbation,
                                                                   rtol, max_cycles, max_steps)
    return {"regime": Regime(regime).name.lower(), "status": Status(status).name.lower(), "growth_rate": g,
            "period": T, "amplitude": amp,
            "cycles": int(cycles), "steps": int(steps), "peak_log_velocity": w}


pin_module(__name__)
