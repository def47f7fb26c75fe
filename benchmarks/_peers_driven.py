"""The driven scene's peers (issue 35): the engine beside numbalsoda, diffrax and scipy on the same driven points.

    python benchmarks/peers.py --driven [--quick] [--models quasistatic,auto,deep_inertial] [--out ...] [--no-png]

(default output benchmarks/results/peers_driven.json and .png)

Scenes (grids from benchmarks/driven_lanes.issue_grid): the issue's grid, preset sample2, V 20 values log-spaced over
0.1..5 um/s, K/M 40 values log-spaced from 0.3 x the smallest to 3 x the largest quasi-static (K/M)_c over those V,
with model "quasistatic" and model "auto" (inertia where the quasi-static run breaks down; each point then runs the
model the engine used for it); and "deep_inertial", driven_lanes.py's deep stick-slip grid (model inertial, V 10 x
K/M 10 over 0.05..0.5 x the smallest (K/M)_c, every point stick-slip).

Every tool integrates the engine's own equations (sweep.integrate.models.driven: (z, u) quasi-static, (z, u, w) with
inertia, reduced k, a, b, g from the engine's plan) from the engine's start (z = perturbation, u = w = 0) over the
HORIZON the engine needed for that point (measured once, at the default rtol):

* (cycles + 1.5) x period where the engine closed at least two cycles (its decision cycle is then inside);
* otherwise from the linear theory's leading root sigma (physics.characteristic_roots): 1.5 ln(1/DECAYED)/|Re sigma|
  where steady sliding is stable (the decay the engine waits for), 3 x 2 pi/Im sigma (or 10/Re sigma) where not;
* where the engine called runaway (the quasi-static model breaks down): the time at which scipy LSODA at rtol
  1e-10 (an event) reaches the engine's threshold ln xi' = W_RUNAWAY. These points are timed but their regime and
  observables are not compared: the blow-up is ill-conditioned in time (LSODA and Radau at 1e-10 place it 2e-6 tau
  apart at tau 579) and passes between output samples, so a sampled trajectory cannot call it (a user would add an
  event). A tool calls runaway where a sample has ln xi' > W_RUNAWAY - RUNAWAY_SLACK.

The peers return the state at output times (SAMPLES_PER_CYCLE per cycle; numbalsoda NUMBALSODA_SAMPLES_PER_CYCLE);
numbalsoda's lsoda and diffrax's SaveAt interpolate to them without shortening their steps. The extrema of z
between samples are located by Newton on the quintic Hermite interpolant of (z, z', z'') at the two samples around
the sign change of z' (z' and z'' from the right-hand side at the sampled states). Where the samples do not resolve
an extremum (an inertial slip ends within ~g tau, far below a sample spacing: at 1000 samples a cycle scipy Radau at
1e-10 had amplitudes 4.7e-4 off and miscalled regimes), each tool locates it as a user of it would:

* numbalsoda (no events): while the quintic and the cubic Hermite interpolants (z, z' only) disagree by more than
  its own tolerance (rtol |z| + atol), LSODA is restarted from the sample before the sign change over
  REFINE_SUBSAMPLES samples of the bracket, up to REFINE_LEVELS times (inside the timed njit loop);
* scipy: an event at ln xi' = 0 (z' = 0) located on the dense output, and a sample EVENT_BRACKET x the spacing
  either side of it;
* diffrax: the samples only (not refined).

From the extrema, every tool's cycles are booked as the engine books them (a_k = half the peak-to-peak stretch,
growth = ln(a_k/a_k-1)/T_k, a maximum rising less than REBOUND x the last amplitude skipped as a rebound) and its
regime is called by the engine's own rule (sweep.integrate.driven._decide, DECAYED, W_RUNAWAY): the regime each
would call from that horizon.

Accuracy: against scipy Radau (analytic Jacobian) at REF_RTOL on a fixed-seed subsample, through the same sampling
and events at REF_SAMPLES_PER_CYCLE, checked against Radau at CHECK_RTOL on a few points (the floor below which
errors are not resolved): the error of the growth rate per cycle |g - g_ref| T_ref and of the amplitude
|a/a_ref - 1|, on the subsample's points whose reference closed at least two cycles, and the regimes that differ
from the reference's.
A setting matches an error level where its growth rates and amplitudes are both within it and every regime is the
reference's. The horizon is longer than the engine's own run (it stops at its decision), which costs the peers
extra time: horizon / the reference's decision time is in the JSON. Work: time per point per core over the whole
grid (engine, numbalsoda; diffrax and scipy: the subsample, at SLOW_TOLS), JIT compile excluded (one untimed call
first). Writes JSON and PNG (time per point per core vs the larger of the growth and amplitude errors, per scene).
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
import time
from pathlib import Path

import _common as common
import numba
import numpy as np
from numba import njit, prange

import sweep
from sweep import physics
from sweep.accuracy import DECAYED, REBOUND, W_RUNAWAY, driven_stepper_rtol
from sweep.integrate.driven import HISTORY, Regime, _decide, _linear_amplitude
from sweep.integrate.models.driven import DrivenParams, log_velocity_rate, make_driven_rhs
from sweep.integrate.models.state_laws import STATE_LAWS
from sweep.protocols.driven.chunk import driven_chunk

DEFAULT_OUT = Path(__file__).resolve().parent / "results" / "peers_driven.json"
N_V, N_KM = 20, 40  # the issue grid (driven_lanes.issue_grid)
ENGINE_RTOLS = (1e-6, 1e-8, 1e-9)  # scene rtol; the stepper runs at driven_stepper_rtol (1e-9, 1e-10, 1e-11)
PEER_TOLS = (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
PEER_TOLS_QUICK = (1e-7, 1e-9, 1e-11)
# the slow peers (seconds a point in Python or in lockstep under vmap) at fewer tolerances; on scenes with inertial
# points fewer still (quick auto grid: diffrax's Kvaerno5 under vmap took 1.6 s a point at 1e-7 and 21.6 s at 1e-9,
# both with regimes unlike the reference's; numbalsoda's LSODA fails on the inertial points after 30-60 ms each)
SLOW_TOLS = {"diffrax_1t": (1e-7, 1e-9, 1e-11), "scipy_LSODA": (1e-7, 1e-9, 1e-11), "scipy_Radau": (1e-7, 1e-9)}
SLOW_TOLS_INERTIAL = {**SLOW_TOLS, "diffrax_1t": (1e-7,), "numbalsoda_1t": (1e-7, 1e-9, 1e-11)}
ATOL_OVER_RTOL = 1e-3  # x the perturbation: the state's scale near steady sliding
SAMPLES_PER_CYCLE = 1000
SCIPY_PIECE = 2000.0  # tau: scipy integrates in pieces this long (scipy_solve)
EVENT_BRACKET = 1e-6  # x the sample spacing: scipy's samples either side of an extremum (module docstring)
REFINE_SUBSAMPLES, REFINE_LEVELS = 32, 6  # an unresolved extremum's re-integration (module docstring)
NUMBALSODA_SAMPLES_PER_CYCLE = 1000  # at 100 (1.5-2x faster on the quick grid) 2 of the 12 subsample points of the
# full quasi-static grid (stick-slip, 4 cycles) came out undecided at every rtol
REF_SAMPLES_PER_CYCLE = 3000
RUNAWAY_SEARCH = 1e6  # tau: where the engine's runaway time is looked for
RUNAWAY_SLACK = 0.1  # a tool calls runaway once ln xi' > W_RUNAWAY - RUNAWAY_SLACK (module docstring)
REF_RTOL, CHECK_RTOL = 1e-10, 1e-12
N_SUB, N_SUB_QUICK = 12, 6
N_CHECK = 2
SEED = 20261128
LSODA_MXSTEP = 10_000_000
DIFFRAX_MAX_STEPS = 2_000_000
REPEATS, REPEATS_QUICK = 2, 1
XLA_ONE_THREAD = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"


SCENES = ("quasistatic", "auto", "deep_inertial")


def driven_scene(name: str, quick: bool) -> sweep.Scene:
    """The issue's driven grid with model ``name`` (quasistatic, auto; every 4th K/M and V with ``quick``), or the
    deep inertial stick-slip grid (``deep_inertial``: model inertial; every 2nd): driven_lanes.issue_grid's."""
    from driven_lanes import issue_grid

    deep = name == "deep_inertial"
    p, KM, V = issue_grid(10, 10, deep=True) if deep else issue_grid(N_V, N_KM)
    if quick:
        KM, V = (KM[::2], V[::2]) if deep else (KM[::4], V[::4])
    return sweep.Scene(protocol="driven", params=p, K_over_M=KM, V=V, model="inertial" if deep else name)


# ------------------------------------------------------------------------------------ cycle bookkeeping

_RHS = (make_driven_rhs(STATE_LAWS["aging"].rate, False), make_driven_rhs(STATE_LAWS["aging"].rate, True))


STEADY_I, RUNAWAY_I, UNDECIDED_I = int(Regime.STEADY), int(Regime.RUNAWAY), int(Regime.UNDECIDED)


@njit
def _no_restart(y0, ts, data, rtol, atol):
    """The plain observe's stand-in for a tool's restart (never called: ``refine`` is False)."""
    return np.empty((ts.size, y0.size)), False


def _make_observe(inertial: bool, restart=_no_restart, refine: bool = False):
    """observe(t, Y, n_valid, p, perturbation, rtol, atol, data) for the model (``inertial``); with ``refine``, an
    extremum the samples do not resolve is located on the tool's own re-integration ``restart(y0, ts, data, rtol,
    atol) -> (Y at ts, success)`` from the sample before it (module docstring)."""
    rhs = _RHS[inertial]

    @njit
    def extremum(t0, t1, y0, y1, p, d0, d1):
        """(t, z, error estimate) of the extremum of z between samples (t0, y0) and (t1, y1): Newton on the quintic
        Hermite interpolant of z with z' and z'' from the right-hand side; the error estimate is its distance to the
        cubic Hermite interpolant (z, z' only) there."""
        dt = t1 - t0
        lw0 = rhs(y0, p, d0)
        s0 = -math.exp(min(lw0, 700.0)) * log_velocity_rate(y0, d0, p) * dt * dt
        lw1 = rhs(y1, p, d1)
        s1 = -math.exp(min(lw1, 700.0)) * log_velocity_rate(y1, d1, p) * dt * dt
        z0, z1, g0, g1 = y0[0], y1[0], d0[0] * dt, d1[0] * dt
        dz = z1 - z0
        c = (z0, g0, 0.5 * s0, 10.0 * dz - 6.0 * g0 - 4.0 * g1 - 1.5 * s0 + 0.5 * s1,
             -15.0 * dz + 8.0 * g0 + 7.0 * g1 + 1.5 * s0 - s1, 6.0 * dz - 3.0 * g0 - 3.0 * g1 - 0.5 * s0 + 0.5 * s1)
        x = g0 / (g0 - g1) if g0 != g1 else 0.5
        for _ in range(20):
            d = c[1] + x * (2.0 * c[2] + x * (3.0 * c[3] + x * (4.0 * c[4] + x * 5.0 * c[5])))
            dd = 2.0 * c[2] + x * (6.0 * c[3] + x * (12.0 * c[4] + x * 20.0 * c[5]))
            if dd == 0.0:
                break
            step = d / dd
            x = min(max(x - step, 0.0), 1.0)
            if abs(step) < 1e-14:
                break
        z = c[0] + x * (c[1] + x * (c[2] + x * (c[3] + x * (c[4] + x * c[5]))))
        cubic = z0 + x * (g0 + x * (3.0 * dz - 2.0 * g0 - g1 + x * (g0 + g1 - 2.0 * dz)))
        return t0 + x * dt, z, abs(z - cubic)

    @njit
    def locate(t0, t1, y0, y1, p, d0, d1, rtol, atol, data):
        """(t, z) of the extremum between two samples; with ``refine``, while the interpolants disagree by more than
        the tool's tolerance (rtol |z| + atol), the bracket is re-integrated from its start at REFINE_SUBSAMPLES
        samples and the sub-bracket with the same sign change taken (at most REFINE_LEVELS times)."""
        t, z, err = extremum(t0, t1, y0, y1, p, d0, d1)
        if not refine:
            return t, z
        up = d0[0] > 0.0
        ya, yb = y0.copy(), y1.copy()
        da, db = d0.copy(), d1.copy()
        for _ in range(REFINE_LEVELS):
            if err <= rtol * abs(z) + atol:
                break
            ts = np.linspace(t0, t1, REFINE_SUBSAMPLES + 1)
            Ys, ok = restart(ya, ts, data, rtol, atol)
            if not ok:
                break
            rhs(Ys[0], p, da)
            found = False
            for m in range(1, ts.size):
                rhs(Ys[m], p, db)
                if (da[0] > 0.0 and db[0] <= 0.0) if up else (da[0] < 0.0 and db[0] >= 0.0):
                    t0, t1 = ts[m - 1], ts[m]
                    ya[:], yb[:] = Ys[m - 1], Ys[m]
                    found = True
                    break
                da[:] = db
            if not found:  # the sign change is not found again (the restart's own error): keep the last estimate
                break
            t, z, err = extremum(t0, t1, ya, yb, p, da, db)
        return t, z

    @njit
    def observe(t, Y, n_valid, p, perturbation, rtol, atol, data):
        """(regime, growth_rate, period, amplitude, cycles, tau of the decision) called from the samples Y[:n_valid]
        at times t, by the
        engine's bookkeeping (sweep.integrate.driven.simulate: cycles cut at maxima, rebounds skipped) with its
        extrema located between samples."""
        n = Y.shape[1]
        d0, d1 = np.empty(n), np.empty(n)
        amp, per, grow = np.full(HISTORY, np.nan), np.full(HISTORY, np.nan), np.full(HISTORY, np.nan)
        z_min, t_max_prev, amp_first = math.inf, math.nan, math.nan
        a_start = _linear_amplitude(p, perturbation)
        cycles = 0
        after_rebound = False
        rhs(Y[0], p, d0)
        dz = d0[0]
        for j in range(1, n_valid):
            lw1 = rhs(Y[j], p, d1)
            if not math.isfinite(lw1) or lw1 > W_RUNAWAY - RUNAWAY_SLACK:
                return RUNAWAY_I, grow[-1], per[-1], math.nan, cycles, t[j]
            norm = 0.0
            for m in range(n):
                norm = max(norm, abs(Y[j, m]))
            if norm < DECAYED * perturbation:
                return STEADY_I, grow[-1], per[-1], 0.0, cycles, t[j]
            dz1 = d1[0]
            if dz > 0.0 and dz1 <= 0.0:
                rhs(Y[j - 1], p, d0)
                t_peak, z_top = locate(t[j - 1], t[j], Y[j - 1], Y[j], p, d0, d1, rtol, atol, data)
                rebound = 0.5 * (z_top - z_min) < REBOUND * amp[-1]  # as the engine: not a cycle end
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
                        return regime.value, grow[-1], per[-1], amplitude, cycles, t_peak
                if not rebound:
                    t_max_prev = t_peak
                after_rebound = rebound
            elif dz < 0.0 and dz1 >= 0.0:
                rhs(Y[j - 1], p, d0)
                z_new = locate(t[j - 1], t[j], Y[j - 1], Y[j], p, d0, d1, rtol, atol, data)[1]
                z_min = min(z_min, z_new) if after_rebound else z_new
            dz = dz1
        return UNDECIDED_I, grow[-1], per[-1], math.nan, cycles, math.nan

    return observe


OBSERVE = (_make_observe(False), _make_observe(True))


def observe_point(t, Y, n_valid, k, a, b, g, perturbation):
    """The regime and observables a tool's samples give (see :func:`_make_observe`; extrema from the samples)."""
    return OBSERVE[int(g > 0.0)](t, Y, n_valid, DrivenParams(k, a, b, g), perturbation, 0.0, 0.0, np.empty(4))


# --------------------------------------------------------------------------------------------- points

@dataclasses.dataclass
class Points:
    """The points of one scene with the engine's model and horizon per point (flat arrays)."""

    k: np.ndarray
    a: np.ndarray
    b: np.ndarray
    g: np.ndarray
    horizon: np.ndarray
    samples: np.ndarray  # output times per point (SAMPLES_PER_CYCLE per cycle of the horizon)
    perturbation: float
    engine: dict  # the engine's outputs at the default rtol


def linear_period(k, a, g) -> np.ndarray:
    """2 pi / Im sigma of the leading root of the linear theory (NaN: no oscillation)."""
    root = physics.characteristic_roots(k, a, 1.0, g)[..., 0]
    with np.errstate(divide="ignore"):
        return np.where(root.imag != 0.0, 2.0 * np.pi / np.abs(root.imag), np.nan)


def horizons(out: dict, k, a, g) -> tuple[np.ndarray, np.ndarray]:
    """(horizon, cycles in it) per point: the module docstring's rule."""
    root = physics.characteristic_roots(k, a, 1.0, g)[..., 0]
    period_lin = linear_period(k, a, g)
    cyc, per = out["cycles"], out["period"]
    closed = (cyc >= 2) & np.isfinite(per)
    with np.errstate(divide="ignore", invalid="ignore"):
        decay = 1.5 * math.log(1.0 / DECAYED) / np.abs(root.real)
        grow = np.where(np.isfinite(period_lin), 3.0 * period_lin, 10.0 / np.abs(root.real))
        fallback = np.where(root.real < 0.0, decay, grow)
        T = np.where(closed, (cyc + 1.5) * per, fallback)
        n_cycles = np.where(closed, cyc + 1.5, np.where(np.isfinite(period_lin), T / period_lin, 2.0))
    return T, np.maximum(n_cycles, 2.0)


def engine_points(scene) -> tuple[Points, object]:
    plan = sweep.make_plan(scene)
    out = driven_chunk(scene, plan)(np.arange(plan.n_points))
    g = plan.G * out["inertial"]
    T, n_cycles = horizons(out, plan.k, plan.a, g)
    samples = np.ceil(SAMPLES_PER_CYCLE * n_cycles).astype(np.int64) + 1
    pts = Points(plan.k, plan.a, plan.b, g, T, samples, scene.perturbation, out)
    period_lin = linear_period(plan.k, plan.a, g)
    for i in np.flatnonzero(out["regime"] == Regime.RUNAWAY):  # the time of the engine's runaway, from an event
        pts.horizon[i] = RUNAWAY_SEARCH
        t_run = scipy_solve(pts, i, 1e-10, "LSODA", None, slack=0.0)[0][-1]
        pts.horizon[i] = t_run
        cycles_run = t_run / period_lin[i] if np.isfinite(period_lin[i]) else 0.0
        pts.samples[i] = int(math.ceil(SAMPLES_PER_CYCLE * max(2.0, cycles_run))) + 1
    return pts, plan


# ---------------------------------------------------------------------------------------------- tools
# solve(points, idx, rtol) -> dict of per-point arrays regime, growth_rate, period, amplitude, cycles (idx: flat
# indices into the points), one call = every point of idx

def engine_tool(scene, plan, threads):
    def solve(pts, idx, rtol):
        old = numba.get_num_threads()
        numba.set_num_threads(threads)
        try:
            sc = dataclasses.replace(scene, rtol=rtol)
            return driven_chunk(sc, plan)(idx)
        finally:
            numba.set_num_threads(old)
    return solve


def _observe_all(pts, idx, ts_of, ys_of, ok):
    res = {f: np.empty(idx.size) for f in ("regime", "growth_rate", "period", "amplitude", "cycles")}
    for j, i in enumerate(idx):
        t, Y = ts_of(j), ys_of(j)
        n_valid = Y.shape[0] if ok[j] else int(np.argmax(~np.isfinite(Y).all(axis=1))) or Y.shape[0]
        r = observe_point(t, Y, max(n_valid, 1), pts.k[i], pts.a[i], pts.b[i], pts.g[i], pts.perturbation)
        for f, v in zip(res, r):
            res[f][j] = v
    res["regime"] = res["regime"].astype(np.int8)
    return res


def numbalsoda_tool():
    """numbalsoda's LSODA from an njit loop (1 thread), or a reason why not."""
    try:
        import numbalsoda
        from numba import carray, cfunc
    except Exception as exc:
        return None, f"not installed ({type(exc).__name__}: {exc})"

    @cfunc(numbalsoda.lsoda_sig)
    def rhs_qs(t, y, dy, d):
        p = carray(d, (4,))
        z, u = y[0], y[1]
        lw = p[0] * z - u * (p[1] + p[2] * u) - u
        e = math.exp(min(lw, 700.0))
        dy[0], dy[1] = 1.0 - e, math.exp(min(-u, 700.0)) - e

    @cfunc(numbalsoda.lsoda_sig)
    def rhs_in(t, y, dy, d):
        p = carray(d, (4,))
        z, u, w = y[0], y[1], y[2]
        balance = p[0] * z - u * (p[1] + p[2] * u) - u
        e = math.exp(min(w, 700.0))
        dy[0], dy[1], dy[2] = 1.0 - e, math.exp(min(-u, 700.0)) - e, (balance - w) * math.exp(min(-w, 700.0)) / p[3]

    ptrs = (rhs_qs.address, rhs_in.address)
    lsoda = numbalsoda.lsoda

    def make_batch(inertial):
        n, ptr = 3 if inertial else 2, ptrs[inertial]

        @njit
        def restart(y0, ts, data, rtol, atol):
            return lsoda(ptr, y0, ts, data=data, rtol=rtol, atol=atol, mxstep=LSODA_MXSTEP)

        observe = _make_observe(inertial, restart, refine=True)

        @njit(parallel=True)
        def batch(k, a, b, g, T, samples, perturbation, rtol, atol, out):
            for j in prange(k.size):  # each point integrated, then its samples observed (no storage across points)
                y0 = np.zeros(n)
                y0[0] = perturbation
                t = np.linspace(0.0, T[j], samples[j])
                data = np.array([k[j], a[j], b[j], g[j]])
                usol, success = lsoda(ptr, y0, t, data=data, rtol=rtol, atol=atol, mxstep=LSODA_MXSTEP)
                n_valid = samples[j]
                if not success:  # the rows after a failure are not written: stop at the first non-finite one
                    for m in range(samples[j]):
                        if not (math.isfinite(usol[m, 0]) and math.isfinite(usol[m, 1])):
                            n_valid = m
                            break
                r = observe(t, usol, max(n_valid, 1), DrivenParams(k[j], a[j], b[j], g[j]), perturbation, rtol, atol,
                            data)
                out[j, 0], out[j, 1], out[j, 2], out[j, 3], out[j, 4] = r[0], r[1], r[2], r[3], r[4]
                if not success and r[0] != RUNAWAY_I:
                    out[j, 0] = UNDECIDED_I
        return batch

    batches = (make_batch(False), make_batch(True))

    def solve(pts, idx, rtol):
        out = np.full((idx.size, 5), np.nan)
        for inertial in (False, True):
            where = np.flatnonzero((pts.g[idx] > 0.0) == inertial)
            if not where.size:
                continue
            sel = idx[where]
            part = np.full((sel.size, 5), np.nan)
            samples = (pts.samples[sel] - 1) * NUMBALSODA_SAMPLES_PER_CYCLE // SAMPLES_PER_CYCLE + 2
            batches[inertial](pts.k[sel], pts.a[sel], pts.b[sel], pts.g[sel], pts.horizon[sel], samples,
                              pts.perturbation, rtol, ATOL_OVER_RTOL * rtol * pts.perturbation, part)
            out[where] = part
        res = dict(zip(("regime", "growth_rate", "period", "amplitude", "cycles"), out.T))
        res["regime"] = res["regime"].astype(np.int8)
        return res

    with_one = lambda pts, idx, rtol: _threads(1, solve, pts, idx, rtol)  # noqa: E731
    return [("numbalsoda_1t", "numbalsoda LSODA (no Jacobian), njit loop, 1 thread", with_one, ("grid", "sub"))], None


def _threads(n, fn, *args):
    old = numba.get_num_threads()
    numba.set_num_threads(n)
    try:
        return fn(*args)
    finally:
        numba.set_num_threads(old)


def diffrax_tool():
    """diffrax under jax.vmap, CPU float64, one XLA thread: Tsit5 for the quasi-static points, Kvaerno5 (implicit,
    L-stable) for the inertial ones (stiff stick phases); or a reason why not."""
    if "jax" not in sys.modules:
        os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + XLA_ONE_THREAD).strip()
    try:
        import jax
        import jax.numpy as jnp
        jax.config.update("jax_enable_x64", True)
        jax.config.update("jax_platforms", "cpu")
        import diffrax
    except Exception as exc:
        return None, f"not installed ({type(exc).__name__}: {exc})"

    def rhs_qs(t, y, args):
        k, a, b, _ = args
        z, u = y[0], y[1]
        e = jnp.exp(jnp.minimum(k * z - u * (a + b * u) - u, 700.0))
        return jnp.stack([1.0 - e, jnp.exp(jnp.minimum(-u, 700.0)) - e])

    def rhs_in(t, y, args):
        k, a, b, g = args
        z, u, w = y[0], y[1], y[2]
        balance = k * z - u * (a + b * u) - u
        e = jnp.exp(jnp.minimum(w, 700.0))
        return jnp.stack([1.0 - e, jnp.exp(jnp.minimum(-u, 700.0)) - e,
                          (balance - w) * jnp.exp(jnp.minimum(-w, 700.0)) / g])

    solvers = {}

    def solver(inertial, n_out):
        key = (inertial, n_out)
        if key not in solvers:
            term = diffrax.ODETerm(rhs_in if inertial else rhs_qs)
            method = diffrax.Kvaerno5() if inertial else diffrax.Tsit5()

            def one(k, a, b, g, T, y0, rtol, atol):
                ts = jnp.linspace(0.0, T, n_out)
                sol = diffrax.diffeqsolve(term, method, 0.0, T, None, y0, args=(k, a, b, g),
                                          saveat=diffrax.SaveAt(ts=ts),
                                          stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
                                          max_steps=DIFFRAX_MAX_STEPS, throw=False)
                return ts, sol.ys, sol.result == diffrax.RESULTS.successful

            solvers[key] = jax.jit(jax.vmap(one, in_axes=(0, 0, 0, 0, 0, None, None, None)))
        return solvers[key]

    def solve(pts, idx, rtol):
        res = {}
        pos = {i: j for j, i in enumerate(idx)}
        for inertial in (False, True):
            sel = idx[(pts.g[idx] > 0.0) == inertial]
            if not sel.size:
                continue
            n = 3 if inertial else 2
            y0 = np.zeros(n)
            y0[0] = pts.perturbation
            bucket = 2 ** np.ceil(np.log2(pts.samples[sel])).astype(np.int64)
            for n_out in np.unique(bucket):  # one vmap per power-of-2 sample count (its output times)
                part = sel[bucket == n_out]
                ts, ys, ok = (np.asarray(x) for x in jax.block_until_ready(solver(inertial, int(n_out))(
                    *(jnp.asarray(v[part]) for v in (pts.k, pts.a, pts.b, pts.g, pts.horizon)), jnp.asarray(y0),
                    rtol, ATOL_OVER_RTOL * rtol * pts.perturbation)))
                r = _observe_all(pts, part, lambda j: ts[j], lambda j: ys[j], ok)  # noqa: B023
                for f, v in r.items():
                    res.setdefault(f, np.empty(idx.size, v.dtype))[[pos[i] for i in part]] = v
        return res

    return [("diffrax_1t", "diffrax Tsit5 (quasi-static) / Kvaerno5 (inertial) + PID, jax.vmap, CPU f64, 1 thread",
             solve, ("sub",))], None


def scipy_solve(pts, i, rtol, method, samples_per_cycle=SAMPLES_PER_CYCLE, slack=RUNAWAY_SLACK):
    """One point with scipy's solve_ivp (``method``; Radau and LSODA get the analytic Jacobian), sampled at
    ``samples_per_cycle`` per cycle of the horizon (None: at its steps) and EVENT_BRACKET x the sample spacing
    either side of each z' = 0 (an event: ln xi' = 0, located on the dense output), stopped where
    ln xi' > W_RUNAWAY - slack: (t, Y, success, nfev, Y and t with the runaway event's state appended)."""
    from scipy.integrate import solve_ivp
    k, a, b, g = pts.k[i], pts.a[i], pts.b[i], pts.g[i]
    inertial = g > 0.0

    def f(t, y):
        if inertial:
            z, u, w = y
            balance = k * z - u * (a + b * u) - u
            e = math.exp(min(w, 700.0))
            return [1.0 - e, math.exp(min(-u, 700.0)) - e, (balance - w) * math.exp(min(-w, 700.0)) / g]
        z, u = y
        e = math.exp(min(k * z - u * (a + b * u) - u, 700.0))
        return [1.0 - e, math.exp(min(-u, 700.0)) - e]

    def jac(t, y):
        if inertial:
            z, u, w = y
            balance = k * z - u * (a + b * u) - u
            e, eu, c = math.exp(min(w, 700.0)), math.exp(min(-u, 700.0)), math.exp(min(-w, 700.0)) / g
            return [[0.0, 0.0, -e], [0.0, -eu, -e], [k * c, -(a + 2.0 * b * u + 1.0) * c, -(1.0 + balance - w) * c]]
        z, u = y
        e, eu = math.exp(min(k * z - u * (a + b * u) - u, 700.0)), math.exp(min(-u, 700.0))
        dw = (k, -(a + 2.0 * b * u + 1.0))
        return [[-e * dw[0], -e * dw[1]], [-e * dw[0], -eu - e * dw[1]]]

    def log_velocity(t, y):
        return y[2] if inertial else k * y[0] - y[1] * (a + b * y[1]) - y[1]

    def runaway(t, y):
        return log_velocity(t, y) - (W_RUNAWAY - 0.5 * slack)
    runaway.terminal = True

    y0 = [pts.perturbation, 0.0] + ([0.0] if inertial else [])
    kw = {"jac": jac} if method in ("Radau", "LSODA", "BDF") else {}
    grid = None
    if samples_per_cycle is not None:
        n_cycles = (pts.samples[i] - 1) / SAMPLES_PER_CYCLE
        grid = np.linspace(0.0, pts.horizon[i], max(2, int(math.ceil(samples_per_cycle * n_cycles)) + 1))
    ts, Ys, nfev, start, y = [], [], 0, 0.0, y0
    while True:  # in pieces of SCIPY_PIECE tau from tau = 0 (autonomous): a slip's end needs steps below the
        # spacing of doubles at tau ~ 5e4 (scipy Radau stopped there on the deep grid)
        span = min(SCIPY_PIECE, pts.horizon[i] - start)
        sol = solve_ivp(f, (0.0, span), y, method=method, rtol=rtol, atol=ATOL_OVER_RTOL * rtol * pts.perturbation,
                        events=(runaway, log_velocity), dense_output=grid is not None, **kw)
        nfev += sol.nfev
        if grid is None:
            t = np.asarray(sol.t, float)
        else:  # the samples, and a pair either side of each z' = 0 (a bracket that resolves the extremum)
            t = grid[(grid >= start) & (grid <= start + sol.t[-1])] - start
            half = EVENT_BRACKET * (grid[1] - grid[0])
            t = np.unique(np.concatenate([t, sol.t_events[1] - half, sol.t_events[1] + half]).clip(0.0, sol.t[-1]))
        ts.append(t + start)
        Ys.append(np.asarray(sol.y, float).T if grid is None else np.asarray(sol.sol(t), float).T)
        if sol.status != 0 or start + span >= pts.horizon[i] or not np.isfinite(sol.y[:, -1]).all():
            break
        start, y = start + span, sol.y[:, -1]
    t, Y = np.concatenate(ts), np.vstack(Ys)
    if sol.status == 1:  # ran away: the samples up to the event, and the event's state
        return t, Y, True, nfev, np.vstack([Y, sol.y_events[0]]), np.append(t, start + sol.t_events[0])
    return t, Y, sol.status == 0 and np.isfinite(Y[-1]).all(), nfev, Y, t


def scipy_tool(method):
    def solve(pts, idx, rtol):
        res = {f: np.empty(idx.size) for f in ("regime", "growth_rate", "period", "amplitude", "cycles")}
        for j, i in enumerate(idx):
            try:
                _, _, _, _, Y, t = scipy_solve(pts, i, rtol, method)
                r = observe_point(t, Y, Y.shape[0], pts.k[i], pts.a[i], pts.b[i], pts.g[i], pts.perturbation)
            except ValueError:  # solve_ivp gave up on the point (LSODA on a slip's end): undecided, not a crash
                r = (UNDECIDED_I, math.nan, math.nan, math.nan, 0)
            for f, v in zip(res, r):
                res[f][j] = v
        res["regime"] = res["regime"].astype(np.int8)
        return res
    return (f"scipy_{method}", f"scipy solve_ivp {method}" + (" (analytic Jacobian)" if method != "DOP853" else "")
            + ", Python loop, 1 thread", solve, ("sub",))


def reference(pts, sub):
    """scipy Radau at REF_RTOL (REF_SAMPLES_PER_CYCLE) on ``sub``; CHECK_RTOL on N_CHECK of them."""
    t0 = time.perf_counter()
    ref = {f: np.empty(sub.size) for f in ("regime", "growth_rate", "period", "amplitude", "cycles", "decided")}
    for j, i in enumerate(sub):
        _, _, _, _, Y, t = scipy_solve(pts, i, REF_RTOL, "Radau", REF_SAMPLES_PER_CYCLE)
        for f, v in zip(ref, observe_point(t, Y, Y.shape[0], pts.k[i], pts.a[i], pts.b[i], pts.g[i],
                                           pts.perturbation)):
            ref[f][j] = v
    ref_s = time.perf_counter() - t0
    cycled = np.flatnonzero(ref["cycles"] >= 2)
    chk = cycled[np.argsort(ref["cycles"][cycled])[:N_CHECK]]
    diffs = []
    for j in chk:
        i = sub[j]
        _, _, _, _, Y, t = scipy_solve(pts, i, CHECK_RTOL, "Radau", REF_SAMPLES_PER_CYCLE)
        r = observe_point(t, Y, Y.shape[0], pts.k[i], pts.a[i], pts.b[i], pts.g[i], pts.perturbation)
        diffs.append((abs(r[1] - ref["growth_rate"][j]) * ref["period"][j],
                      abs(r[3] / ref["amplitude"][j] - 1.0) if ref["amplitude"][j] > 0 else 0.0))
    floor = (max([d[0] for d in diffs] + [1e-15]), max([d[1] for d in diffs] + [1e-15]))
    return ref, {"what": f"scipy Radau (analytic Jacobian) at rtol {REF_RTOL:g}, atol {ATOL_OVER_RTOL:g} rtol "
                         f"perturbation, {REF_SAMPLES_PER_CYCLE} samples per cycle; checked at rtol {CHECK_RTOL:g} on "
                         f"{len(chk)} points", "seconds": ref_s,
                 "regimes": {Regime(int(r)).name.lower(): int((ref["regime"] == r).sum()) for r in np.unique(
                     ref["regime"])},
                 "check_points": sub[chk].tolist(), "floor_growth_per_cycle": floor[0], "floor_amplitude": floor[1],
                 "horizon_over_decision": _spread(pts.horizon[sub] / ref["decided"])}


def _spread(x):
    """min, median, max of the finite values of x (None: none)."""
    x = x[np.isfinite(x)]
    return {"min": float(x.min()), "median": float(np.median(x)), "max": float(x.max())} if x.size else None


# --------------------------------------------------------------------------------------------- timing

def errors(res, ref, compared):
    """Errors of a tool's per-point results on the subsample against the reference; regimes on ``compared``."""
    both = (ref["cycles"] >= 2) & np.isfinite(ref["growth_rate"]) & compared
    g_err = np.abs(res["growth_rate"][both] - ref["growth_rate"][both]) * ref["period"][both]
    amp = both & (ref["amplitude"] > 0)
    a_err = np.abs(res["amplitude"][amp] / ref["amplitude"][amp] - 1.0)
    fin = lambda x, fn: float(fn(x)) if x.size and np.isfinite(x).all() else (None if not x.size else math.inf)  # noqa: E731
    return {"max_growth_err_per_cycle": fin(g_err, np.max), "median_growth_err_per_cycle": fin(g_err, np.median),
            "max_amplitude_rel_err": fin(a_err, np.max), "median_amplitude_rel_err": fin(a_err, np.median),
            "points_compared": int(both.sum()), "amplitudes_compared": int(amp.sum()),
            "regimes_differing_from_reference": int((res["regime"] != ref["regime"])[compared].sum())}


def time_one(solve, pts, idx, rtol, repeats, warm_all=True):
    """Best of ``repeats`` timed calls after an untimed one (JIT compile, jax trace for the shapes of idx; scipy,
    without JIT: on one point)."""
    solve(pts, idx if warm_all else idx[:1], rtol)
    load0 = common.loadavg()
    cpu, wall, res = common.timings(lambda: solve(pts, idx, rtol), repeats)
    return min(wall), min(cpu), res, [load0, common.loadavg()]


def bench_scene(name, scene, tools, peer_tols, engine_rtols, repeats, n_sub, quick):
    t0 = time.perf_counter()
    pts, plan = engine_points(scene)
    n = plan.n_points
    sub = np.sort(np.random.default_rng(SEED).choice(n, size=min(n_sub, n), replace=False))
    regimes = {Regime(int(r)).name.lower(): int((pts.engine["regime"] == r).sum())
               for r in np.unique(pts.engine["regime"])}
    print(f"[{name}] {scene.shape[0]} x {scene.shape[1]} = {n} points ({regimes}; inertial "
          f"{int(pts.engine['inertial'].sum())}), subsample {sub.size}; reference Radau {REF_RTOL:g}", flush=True)
    ref, ref_info = reference(pts, sub)
    compared = pts.engine["regime"] != Regime.RUNAWAY  # see the module docstring
    print(f"    reference: {ref_info['seconds']:.1f} s, floor growth {ref_info['floor_growth_per_cycle']:.1e}/cycle, "
          f"amplitude {ref_info['floor_amplitude']:.1e}", flush=True)
    out = {}
    all_idx = np.arange(n)
    n_all = numba.config.NUMBA_NUM_THREADS
    engine = [(f"engine_{nt}t", f"engine driven_chunk (kernel path), {nt} thread{'s' * (nt > 1)}",
               engine_tool(scene, plan, nt), ("grid", "sub") if nt == 1 else ("grid",), engine_rtols)
              for nt in sorted({1, n_all})]
    slow = SLOW_TOLS_INERTIAL if pts.engine["inertial"].any() else SLOW_TOLS
    for tname, label, solve, scopes, tols in engine + [t + (slow.get(t[0], peer_tols),) for t in tools]:
        entry = out.setdefault(tname, {"label": label, "threads": 1 if not tname.startswith("engine") or
                                       tname.endswith("_1t") else n_all, "scopes": {}})
        for scope in scopes:
            idx = all_idx if scope == "grid" else sub
            rows = []
            for rt in tols:
                tt = time.perf_counter()
                try:
                    scipy = tname.startswith("scipy")
                    parts = {}  # a peer on a scene of both models: each model's points timed on their own
                    for cls, of_cls in _classes(pts, idx, not tname.startswith("engine")).items():
                        parts[cls] = (of_cls, *time_one(solve, pts, idx[of_cls], rt, 1 if scipy else repeats,
                                                        not scipy))
                except Exception as exc:
                    entry["failed"] = f"{type(exc).__name__}: {exc}"[:400]
                    print(f"    {tname:16s} {scope:4s} rtol {rt:7.0e}: failed ({entry['failed']})", flush=True)
                    break
                wall, cpu = sum(p[1] for p in parts.values()), sum(p[2] for p in parts.values())
                load = [p[4] for p in parts.values()][0]
                res = {}
                for of_cls, _, _, r, _ in parts.values():
                    for fld, v in r.items():
                        res.setdefault(fld, np.empty(idx.size, np.asarray(v).dtype))[of_cls] = v
                res_sub = {f: np.asarray(v)[sub] for f, v in res.items()} if scope == "grid" else res
                row = {"rtol": rt, "stepper_rtol": driven_stepper_rtol(rt) if tname.startswith("engine") else rt,
                       "points": int(idx.size), "best_wall_s": wall, "best_cpu_s": cpu,
                       "us_per_point_per_core": wall * entry["threads"] / idx.size * 1e6,
                       "points_per_s_per_core": idx.size / (wall * entry["threads"]), "loadavg": load,
                       **errors(res_sub, ref, compared[sub])}
                if len(parts) > 1:
                    on_sub = np.isin(idx, sub) if scope == "grid" else np.ones(idx.size, bool)
                    row["models"] = {cls: {"points": int(of_cls.sum()), "best_wall_s": p_wall,
                                           **errors({f: v[of_cls & on_sub] for f, v in res.items()},
                                                    {f: v[_class_mask(pts, sub, cls)] for f, v in ref.items()},
                                                    compared[sub][_class_mask(pts, sub, cls)])}
                                     for cls, (of_cls, p_wall, *_) in parts.items()}
                if scope == "grid":
                    row["regimes_differing_from_engine"] = int((np.asarray(res["regime"]) !=
                                                                pts.engine["regime"])[compared].sum())
                rows.append(row)
                ge = row["max_growth_err_per_cycle"]
                print(f"    {tname:16s} {scope:4s} rtol {rt:7.0e}: {row['us_per_point_per_core']:11.1f} us/point/core"
                      f"  growth err {'-' if ge is None else f'{ge:.1e}':>8s}  amp err "
                      f"{row['max_amplitude_rel_err'] or 0:.1e}  regimes != ref "
                      f"{row['regimes_differing_from_reference']}"
                      f"  ({time.perf_counter() - tt:.1f} s)", flush=True)
            entry["scopes"][scope] = rows
    inertial = pts.g > 0.0
    shares = {"quasistatic": float(1.0 - inertial.mean()), "inertial": float(inertial.mean())} if 0 < inertial.sum(
    ) < n else None
    return {"shape": list(scene.shape), "points": n, "model": scene.model, "engine_regimes": regimes,
            "inertial_points": int(pts.engine["inertial"].sum()),
            "K_over_M_range": [float(scene.K_over_M.min()), float(scene.K_over_M.max())],
            "V_range": [float(scene.V.min()), float(scene.V.max())],
            "horizon_tau": {"min": float(pts.horizon.min()), "median": float(np.median(pts.horizon)),
                            "max": float(pts.horizon.max())},
            "subsample": {"points": int(sub.size), "seed": SEED, "flat_indices": sub.tolist()},
            "reference": ref_info, "tools": out, "matched": matched(out, shares), "seconds": time.perf_counter() - t0}


def _class_mask(pts, idx, cls):
    return (pts.g[idx] > 0.0) == (cls == "inertial")


def _classes(pts, idx, split):
    """{model: mask of idx}: both models apart where ``split`` and idx holds both, else all of idx as one."""
    masks = {cls: _class_mask(pts, idx, cls) for cls in ("quasistatic", "inertial")}
    if not split or not all(m.any() for m in masks.values()):
        return {"all": np.ones(idx.size, bool)}
    return masks


def _meets(row, lvl):
    """Growth rates per cycle and amplitudes within ``lvl`` of the reference's, every regime the reference's."""
    return (row["max_growth_err_per_cycle"] is not None and row["max_growth_err_per_cycle"] <= lvl
            and (row["max_amplitude_rel_err"] or 0.0) <= lvl and row["regimes_differing_from_reference"] == 0)


def matched(out, shares=None):
    """Per error level (:func:`_meets`): each tool's cheapest setting (subsample accuracy, grid time where it ran
    there), the engine's speed-up per core over the best peer, and, on a scene of both models (``shares``: each
    model's share of the grid's points), over the best peer per model (each model's points by its own cheapest
    peer setting that meets the level on them, times weighted by the shares)."""
    levels = {}
    for lvl in (1e-4, 1e-5, 1e-6, 1e-7, 1e-8):
        ent = {}
        for tname, t in out.items():
            scope = "grid" if "grid" in t["scopes"] else "sub"
            ok = [r for r in t["scopes"].get(scope, []) if _meets(r, lvl)]
            if ok:
                best = min(ok, key=lambda r: r["us_per_point_per_core"])
                ent[tname] = {"rtol": best["rtol"], "us_per_point_per_core": best["us_per_point_per_core"],
                              "scope": scope}
        peers = [t for t in ent if not t.startswith("engine")]
        bp = min(peers, key=lambda t: ent[t]["us_per_point_per_core"]) if peers else None
        ent["best_peer"] = bp
        if bp and "engine_1t" in ent:
            ent["engine_1t_speedup_vs_best_peer"] = ent[bp]["us_per_point_per_core"] / ent["engine_1t"][
                "us_per_point_per_core"]
        per_model, total = {}, 0.0
        for cls, share in (shares or {}).items():
            cands = [(m["best_wall_s"] / m["points"] * 1e6, tname, r["rtol"])
                     for tname, t in out.items() if not tname.startswith("engine")
                     for r in t["scopes"].get("grid" if "grid" in t["scopes"] else "sub", [])
                     if (m := r.get("models", {}).get(cls)) and _meets(m, lvl)]
            if not cands:
                per_model = {}
                break
            us, tname, rt = min(cands)
            per_model[cls] = {"tool": tname, "rtol": rt, "us_per_point": us, "share": share}
            total += share * us
        if per_model:
            ent["best_peer_per_model"] = {"models": per_model, "us_per_point_per_core": total}
            if "engine_1t" in ent:
                ent["engine_1t_speedup_vs_best_peer_per_model"] = total / ent["engine_1t"]["us_per_point_per_core"]
        levels[f"{lvl:g}"] = ent
    return levels


def plot(result, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    scenes = list(result["scenes"])
    fig, axes = plt.subplots(1, len(scenes), figsize=(6.2 * len(scenes), 5.6), squeeze=False)
    for ax, sname in zip(axes[0], scenes):
        sc = result["scenes"][sname]
        for tname, t in sc["tools"].items():
            scope = "grid" if "grid" in t["scopes"] else "sub"
            rows = [r for r in t["scopes"].get(scope, []) if r["max_growth_err_per_cycle"]]
            if rows:
                ax.loglog([max(r["max_growth_err_per_cycle"], r["max_amplitude_rel_err"] or 0.0) for r in rows],
                          [r["us_per_point_per_core"] for r in rows],
                          "-" if tname.startswith("engine") else "--", marker="o", ms=3,
                          label=f"{t['label']} [{scope}: {rows[0]['points']} pts]")
        ax.axvspan(1e-17, sc["reference"]["floor_growth_per_cycle"], color="0.9", zorder=0)
        ax.set_xlabel("max of growth-rate error per cycle |g - g_ref| T and amplitude error |a/a_ref - 1|\n"
                      "(subsample, vs scipy Radau 1e-10)", fontsize=8)
        ax.set_ylabel("us per point per core")
        ax.set_title(f"driven, model {sc['model']}: {sc['shape'][0]} x {sc['shape'][1]}", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=1)
    fig.suptitle(f"driven scene vs peers, {result['machine']['cpu']} ({result['date']}); JIT excluded", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path)


def print_table(result):
    for sname, sc in result["scenes"].items():
        print(f"\n[driven {sname}] {sc['points']} points, regimes {sc['engine_regimes']}; reference floor growth "
              f"{sc['reference']['floor_growth_per_cycle']:.0e}")
        for lvl, ent in sc["matched"].items():
            bp = ent["best_peer"]
            e = ent.get("engine_1t")
            print(f"  errors <= {lvl:>6s}: engine 1t {e['us_per_point_per_core'] if e else float('nan'):10.1f} "
                  f"us, best peer {bp or '-':14s} "
                  f"{ent[bp]['us_per_point_per_core'] if bp else float('nan'):10.1f} us, engine x"
                  f"{ent.get('engine_1t_speedup_vs_best_peer', float('nan')):.2f}")
            if "best_peer_per_model" in ent:
                pm = ent["best_peer_per_model"]
                print("      best peer per model: " + ", ".join(
                    f"{cls} {m['tool']} {m['rtol']:g} {m['us_per_point']:.1f} us" for cls, m in pm["models"].items())
                    + f" -> {pm['us_per_point_per_core']:.1f} us, engine x"
                      f"{ent.get('engine_1t_speedup_vs_best_peer_per_model', float('nan')):.2f}")


def main(argv=None):
    """Run the driven peers (benchmarks/peers.py --driven passes its other arguments here)."""
    import argparse
    import datetime as _dt
    import importlib.metadata
    import warnings

    ap = argparse.ArgumentParser(description="the driven scene's peers (benchmarks/_peers_driven.py)")
    ap.add_argument("--quick", action="store_true", help="every 4th K/M and V, 8-point subsample, 3 peer tolerances")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    ap.add_argument("--no-png", action="store_true")
    ap.add_argument("--models", default=",".join(SCENES), help="scenes: " + ", ".join(SCENES))
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", RuntimeWarning)
    t_start = time.perf_counter()
    load0, digest0 = common.loadavg(), common.sweep_digest()
    tools, status = [], {}
    for name, make in (("numbalsoda", numbalsoda_tool), ("diffrax", diffrax_tool),
                       ("scipy", lambda: ([scipy_tool("LSODA"), scipy_tool("Radau")], None))):
        got, why = make()
        status[name] = "ok" if got else why
        tools += got or []
        print(f"peer {name}: {status[name]}", flush=True)
    peer_tols = PEER_TOLS_QUICK if args.quick else PEER_TOLS
    repeats = REPEATS_QUICK if args.quick else REPEATS
    n_sub = N_SUB_QUICK if args.quick else N_SUB
    scenes = {m: bench_scene(m, driven_scene(m, args.quick), tools, peer_tols, ENGINE_RTOLS, repeats, n_sub,
                             args.quick) for m in args.models.split(",")}

    def version(dist):
        try:
            return importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            return None

    import scipy
    result = {
        "benchmark": "benchmarks/peers.py --driven" + (" --quick" if args.quick else "") + f" --models {args.models}",
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "machine": common.machine_info(),
        "versions": {**common.versions(), "scipy": scipy.__version__, "jax": version("jax"),
                     "diffrax": version("diffrax"), "numbalsoda": version("numbalsoda")},
        "sweep_source_digest_start_end": [digest0, common.sweep_digest()],
        "loadavg_start_end": [load0, common.loadavg()],
        "peers_status": status,
        "tools_missing": {name: why for name, why in status.items() if why != "ok"},
        "settings": {"peer_tols": list(peer_tols), "engine_rtols": list(ENGINE_RTOLS),
                     "engine_stepper_rtols": [driven_stepper_rtol(r) for r in ENGINE_RTOLS],
                     "atol_peers": f"{ATOL_OVER_RTOL:g} x rtol x perturbation", "repeats": repeats,
                     "samples_per_cycle": SAMPLES_PER_CYCLE, "seed": SEED,
                     "grid": "sample2, V 20 log-spaced 0.1..5 um/s, K/M 40 log-spaced 0.3 x min .. 3 x max "
                             "quasi-static (K/M)_c" + (" (every 4th K/M and V)" if args.quick else ""),
                     "deep_grid": "sample2, V 10 log-spaced 0.1..5 um/s, K/M 10 log-spaced 0.05 .. 0.5 x the smallest "
                                  "(K/M)_c, model inertial (driven_lanes.issue_grid)"
                                  + (" (every 2nd K/M and V)" if args.quick else ""),
                     "horizon": "(cycles + 1.5) x period of the engine at rtol 1e-6 where it closed >= 2 cycles, "
                                "else from the linear theory (module docstring)",
                     "per_core": "wall x threads / points; JIT excluded (an untimed call first)",
                     "scopes": "grid: every point (engine, numbalsoda); sub: the fixed-seed subsample (all tools; "
                               "accuracy is always measured there)"},
        "scenes": scenes,
    }
    common.write_result(result, args.out, t_start, None if args.no_png else plot, print_table)


if __name__ == "__main__":
    main()
