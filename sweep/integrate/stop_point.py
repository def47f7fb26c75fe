"""One stop point with any explicit Runge-Kutta tableau, fixed or adaptive steps, and its error estimate.

The equations and the time map are those of :mod:`sweep.integrate.models.stop`; the method is data: the arrays
(c, a, b, e) of a :class:`sweep.integrate.solvers.tableau.ButcherTableau` (e = b - b_hat, the embedded error weights)
with its FSAL flag and error order q. One step fills the stage derivatives K[i] = f(y + h sum_j a_ij K[j]).

Step sequences (a *mesh* of step sizes in sigma):

* ``ADAPTIVE``: the PI controller of :mod:`sweep.integrate.solvers.controllers` (Gustafsson) keeps the embedded local
error
  estimate below ``ctrl_tol`` (:func:`error_norm`: xi relative with the atol floor, u = ln psi, and tau when
  time-resolved observables are asked for), and records the accepted steps;
* ``REPLAY``: steps mesh[i]/split, each mesh step taken as ``split`` equal substeps (the last size repeated if the
  run needs more steps than the mesh has). A fixed step h is the one-element mesh (h,).

Error estimate: each point is solved twice, on a coarse mesh and on the same mesh with every step halved. The
coarse solution is returned, with COARSE_GAIN times its difference from the fine one as its estimate: this needs
only that the fine run be at least twice as accurate, not that the pair be asymptotic (the Richardson estimate of
the fine solution, difference / (2^p - 1), which this path used before and the relaxed-slip lanes still use, does).
The asymptotic ratio fails here in three ways: the controller's steps reach the stability boundary along the creep
manifold and at the end of the decaying tail, where halving a step changes its error by anything from 2 to 2^12;
where the error contributions of the stiff start and of the tail cancel in xi_inf (stiff points with m2 = 0, slow
tails), the fine error is a small remainder of higher-order terms; and a sample inside a step has no asymptotic
ratio unless both runs reach it the same way (:func:`state_where`). Dividing by 2^p - 1 (31 for dp5, 255 for dop853)
gave estimates from 0.04x to 1.8e3x the true error. Where contributions of opposite sign cancel in the coarse run
instead, its error need not exceed the fine run's; a bound on the fine run's error from the sum of the
|contributions| is added (:func:`cancelled`, and :func:`crossing_error` for t50/t90). Each run's closed-form tail
error bound is added (negligible: the per-point path integrates until it is below TAIL_SAFETY (atol + TAIL_RTOL
|xi|)), and for samples taken from the closed-form continuation its bound
(:func:`sweep.integrate.models.stop.continuation_error`). On tests/integrate/test_error_estimates.py's table the
estimate is
1.2x..50x the true error for every method at rtol 1e-3..1e-9 (t50/t90 up to 130x where the two shares of their
error cancel). The price is accuracy: the returned solution is the less accurate of the two, so the step rules must
make the coarse run meet rtol (``CTRL_TOL_FACTOR`` of :mod:`sweep.plan.plan` for the adaptive methods; rk4 per point,
used for time-resolved observables, has its rule's TIME_RESOLVED_FACTOR).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..accuracy import COARSE_GAIN, TAIL_RTOL, TAIL_TIGHTENING
from ..jitcache import pin_module
from ..status import Status
from .models.stop import (
    FAST,
    MAX_STEPS,
    NO_FINITE_LIMIT,
    NONFINITE,
    OK,
    TAIL_SAFETY,
    StopParams,
    continuation_error,
    continue_in_closed_form,
    derivatives,
    tail_error,
    tail_slip,
)
from .solvers.controllers import PI_CONTROLLER, accepted_factor, rejected_factor

STEP_UNDERFLOW = int(Status.STEP_UNDERFLOW)
ADAPTIVE, REPLAY = 0, 1
H_FLOOR = 1e-12
"""Smallest adaptive step in sigma, relative to max(1, sigma): below it the point gets status step_underflow."""
LINEAR_MISS = 1e-8
"""In :func:`state_where`, a miss of the target below LINEAR_MISS x |target| is closed along the tangent instead of by
another partial step: the tangent's error is ~ (miss/target)^2 ~ 1e-16 relative (the curvature of xi, s, tau in
sigma is O(1) in their own units), far below any rtol, and a sample then costs 2 partial steps, not 3 (the Newton
from the Hermite estimate misses by ~1e-6 once, ~1e-12 after one step: the third step only confirmed it)."""
U_ROUNDING = 8.0 * 2.0**-52
"""Resolution of u = s - xi relative to s (a few roundings of s): the floor of u's weight in :func:`error_norm`."""


class Method(NamedTuple):
    """An explicit tableau for the per-point kernel: (c, A, b, e) of :meth:`ButcherTableau.arrays`, its FSAL flag,
    the order q of its error estimate (0: a fixed-step method) and its order p."""

    c: np.ndarray
    A: np.ndarray
    b: np.ndarray
    e: np.ndarray
    fsal: bool
    q: int
    order: int

    @classmethod
    def of(cls, tableau) -> Method:
        c, A, b, e = tableau.arrays()
        return cls(c, A, b, e, tableau.fsal, tableau.error_order, tableau.order)


class Mesh(NamedTuple):
    """The step sequence of a run: ``mode`` ADAPTIVE (trial step h0, building the mesh) or REPLAY (``steps[:n]``,
    each taken as ``split`` substeps)."""

    mode: int
    h0: float
    steps: np.ndarray
    n: int
    split: int


class Tolerances(NamedTuple):
    rtol: float
    """Of the continuation in closed form (E < TAIL_SAFETY rtol)."""
    atol: float
    """Absolute floor of xi (error norm and tail test)."""
    ctrl: float
    """Local tolerance of the adaptive controller."""


class Samples(NamedTuple):
    """What a run records: xi and u = ln psi at the increasing reduced times ``tau`` (into xi_at, u_at), tau and
    dxi/dtau where xi crosses the increasing ``xi`` (into tau_at, rate_at), and the relaxed slip if ``limit``. (A
    field, not an argument of :func:`march`: a literal True or False passed to a numba function compiles it once
    more, and march is the largest function of the per-point path.)"""

    tau: np.ndarray
    xi_at: np.ndarray
    u_at: np.ndarray
    xi: np.ndarray
    tau_at: np.ndarray
    rate_at: np.ndarray
    limit: bool


class Continuation(NamedTuple):
    """Where the closed-form continuation of the samples starts: first continued sample, E, g = (mu1 + 2 m2 u)/A
    and u there."""

    first: int
    E: float
    g: float
    u: float


class StepState(NamedTuple):
    """The state (xi, s, tau) at the start of a mesh step and its derivative there."""

    xi: float
    s: float
    tau: float
    dxi: float
    ds: float
    dtau: float


class Run(NamedTuple):
    """A :func:`march` result (its docstring)."""

    status: int
    xi_inf: float
    steps: int
    tail_err: float
    mesh: np.ndarray
    n_mesh: int
    cont: Continuation
    track: np.ndarray
    n_track: int
    at_mesh: np.ndarray


@njit(cache=True, fastmath=FAST, error_model="numpy")
def erk_step(method, K, xi, s, tau, h, p):
    """One explicit RK step of size h from (xi, s, tau), K[0] the derivative there; fills K[1:]. Returns (xi1, s1,
    tau1, err_xi, err_s, err_tau): the new state and the embedded error estimate h sum_j e_j K[j] (zero for a method
    without one). For an FSAL method K[-1] is the derivative at the new state.

    The stage loop of sweep/integrate/solvers/explicit.py written out in scalars for this three-component state:
    through the
    shared loop (state in arrays, the right-hand side writing into them) a dp5 run took 16.2 us instead of 12.3 us
    and time-resolved, dp5 and dop853 sweeps ran 1.2-1.25x slower (benchmarks/compare_commits.py), so this path keeps
    its own until the shared loop holds small states in registers."""
    A, b, e = method.A, method.b, method.e
    stages = b.size
    for i in range(1, stages):
        dx, ds, dt = 0.0, 0.0, 0.0
        for j in range(i):
            dx += A[i, j] * K[j, 0]
            ds += A[i, j] * K[j, 1]
            dt += A[i, j] * K[j, 2]
        K[i, 0], K[i, 1], K[i, 2], _ = derivatives(xi + h * dx, s + h * ds, p)
    dx, ds, dt, ex, es, et = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    for j in range(stages):
        dx += b[j] * K[j, 0]
        ds += b[j] * K[j, 1]
        dt += b[j] * K[j, 2]
        ex += e[j] * K[j, 0]
        es += e[j] * K[j, 1]
        et += e[j] * K[j, 2]
    return xi + h * dx, s + h * ds, tau + h * dt, h * ex, h * es, h * et


@njit(cache=True, fastmath=FAST)
def hermite(y0, y1, m0, m1, t):
    """Cubic Hermite interpolant on [0, 1] with end slopes m0, m1 (already scaled by the step)."""
    t2 = t * t
    t3 = t2 * t
    return (2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * m1


@njit(cache=True, fastmath=FAST)
def hermite_crossing(y0, y1, m0, m1, target):
    """theta in [0, 1] where the increasing Hermite interpolant equals target (safeguarded Newton)."""
    lo, hi = 0.0, 1.0
    t = (target - y0) / (y1 - y0) if y1 > y0 else 0.5
    for _ in range(60):
        t2 = t * t
        f = hermite(y0, y1, m0, m1, t) - target
        if f > 0.0:
            hi = t
        else:
            lo = t
        df = (6 * t2 - 6 * t) * y0 + (3 * t2 - 4 * t + 1) * m0 + (-6 * t2 + 6 * t) * y1 + (3 * t2 - 2 * t) * m1
        tn = t - f / df if df > 0.0 else 0.5 * (lo + hi)
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= 1e-15:
            return tn
        t = tn
    return t


@njit(cache=True, fastmath=FAST)
def state_where(method, K, component, target, theta, start, h, split, p):
    """State (xi, s, tau) and slip rate dxi/dtau inside a mesh step h where ``component`` (0: xi, 2: tau) equals
    ``target``: Newton on theta in [0, 1] with exact partial steps of size theta*h from the mesh step's start (the
    method's own local order), started from the estimate ``theta``. The partial step is taken as ``split`` equal
    substeps, like the run's own steps: the fine run's path to a sample is then the coarse run's path with every
    step halved, as for the values at mesh points, and the pair keeps its h^p ratio there too. (Located from the
    fine run's own last substep instead, a sample just past the middle of a coarse step came out of a partial
    step barely longer than the fine run's full one: as accurate, and estimates 0.14x the true error.)
    ``start``: the mesh step's start (:class:`StepState`)."""
    xi, s, tau, d0x, d0s, d0t = start
    x1, s1, t1, dx1, dt1 = xi, s, tau, d0x, d0t
    for _ in range(8):
        x1, s1, t1 = xi, s, tau
        K[0, 0], K[0, 1], K[0, 2] = d0x, d0s, d0t
        for _ in range(split):
            x1, s1, t1, _, _, _ = erk_step(method, K, x1, s1, t1, theta * h / split, p)
            dx1, ds1, dt1, _ = derivatives(x1, s1, p)
            K[0, 0], K[0, 1], K[0, 2] = dx1, ds1, dt1
        value = x1 if component == 0 else t1
        slope = h * (dx1 if component == 0 else dt1)
        miss = value - target
        if abs(miss) <= 4e-16 * abs(target) or not slope > 0.0:
            break
        if abs(miss) <= LINEAR_MISS * abs(target):  # the last Newton step taken along the tangent, not integrated
            d_sigma = -miss / (slope / h)
            x1, s1, t1 = x1 + dx1 * d_sigma, s1 + ds1 * d_sigma, t1 + dt1 * d_sigma
            if component == 0:
                x1 = target
            else:
                t1 = target
            break
        theta = min(1.0, max(0.0, theta - miss / slope))
    return x1, s1, t1, dx1 / dt1


@njit(cache=True, fastmath=FAST)
def error_norm(ex, es, et, xi, xi1, s1, tau1, ctrl_tol, atol, with_tau):
    """Weighted RMS norm of an embedded local error estimate (ex, es, et) of (xi, s, tau) over a step ending at
    (xi1, s1, tau1) [1].

    The components are xi, relative with the atol floor, and u = s - xi = ln psi (error es - ex), relative to
    min(|s|, max(1, |u|)) with the rounding floor U_ROUNDING |s|: u is what the rates depend on (E = exp(-(k xi +
    a u + b u^2)), an error du changes E by g du) and its error is the relative error of psi. Weighting s relative
    to |s| (as before; still so early on, s < 1) let u drift by ctrl_tol |s| per step where s >> u: in the costly
    corner (chi/A = 1e-5, mu1/A = -1, m2/A = 0.05, s ~ xi ~ 5e5, u ~ 10) dop853 crossed the fold of the creep
    manifold and the whole fall-off in one step of 10 in sigma, 1.35e-6 off at rtol 1e-6 with status ok and an
    estimate 28x too small, and 0.76 off at rtol 1e-4 (tests/protocols/test_extremes.py); with u weighted by max(1, |u|)
    dp5 and dop853 are within 1e-3 rtol there at rtol 1e-4..1e-8 (at up to 2x the steps in the corners at
    rtol 1e-9, where the creep manifold's stability limits the steps).
    When time-resolved observables are asked for, tau is a third component, relative: the error of psi at a given
    tau is the relative error of tau late on (psi ~ tau), and the steps that integrate tau = int e^u ds across
    the tail were otherwise limited by xi and u alone (late psi samples 0.35x underestimated with dp5).
    """
    sx = atol + ctrl_tol * max(abs(xi), abs(xi1))
    su = ctrl_tol * min(abs(s1), max(1.0, abs(s1 - xi1))) + U_ROUNDING * abs(s1)
    sum_sq = (ex / sx) ** 2 + ((es - ex) / su) ** 2
    if not with_tau:
        return math.sqrt(0.5 * sum_sq)
    return math.sqrt((sum_sq + (et / (ctrl_tol * tau1)) ** 2) / 3.0)


@njit(cache=True, fastmath=FAST, error_model="numpy")
def march(method, plan_mesh, p, tol, max_steps, samples):
    """Integrate one stop point along a mesh (module docstring).

    ``method``: :class:`Method`; ``plan_mesh``: :class:`Mesh`; ``p``: :class:`sweep.integrate.models.stop.StopParams`
    (its
    with_tau is set here from the samples); ``tol``: :class:`Tolerances`. Records into ``samples``
    (:class:`Samples`) xi and u = ln psi where tau crosses each of its increasing times and tau and the slip rate
    dxi/dtau where xi crosses each of its increasing slips; tau targets
    beyond the transient (E < TAIL_SAFETY rtol, relaxed slip known) come from the closed form. The closed-form
    tail is taken once its error bound is below TAIL_SAFETY (atol + TAIL_RTOL |xi|); stops when the tail is taken
    (if ``samples.limit``) and all targets are recorded.

    Returns a :class:`Run` (status, xi_inf, steps, tail error bound, mesh, n_mesh, continuation, track, n_track,
    at_mesh):
    xi_inf is NaN unless the tail was reached; in ADAPTIVE mode the returned mesh holds the n_mesh accepted steps;
    continuation = (first continued target, E, g = (mu1 + 2 m2 u)/A, u where it starts): targets from the first
    continued one on carry the closed form's own error in u = ln psi
    (:func:`sweep.integrate.models.stop.continuation_error`);
    track[:n_track] is (xi, s, E) at the end of each mesh step, at_mesh the mesh step in which each tau target was
    located (-1: continued).
    """
    fsal, q = method.fsal, method.q
    mode, h0, mesh, n_mesh, split = plan_mesh
    rtol, atol, ctrl_tol = tol
    tau_targets, xi_at, u_at, xi_targets, tau_at, rate_at, want_limit = samples
    k, a, bb = p.k, p.a, p.b
    stages = method.b.size
    K = np.empty((stages, 3))
    with_tau = tau_targets.size > 0 or xi_targets.size > 0
    p = StopParams(p.k, p.a, p.b, p.s_c, with_tau)
    p_tau = StopParams(p.k, p.a, p.b, p.s_c, True)  # located samples always carry tau
    xi, s, tau = 0.0, 0.0, 0.0
    dxi, ds, dtau, E = derivatives(xi, s, p)
    it, ix, at_mesh = 0, 0, np.full(tau_targets.size, -1)
    while it < tau_targets.size and tau_targets[it] <= 0.0:
        xi_at[it], u_at[it], at_mesh[it] = 0.0, 0.0, 0
        it += 1
    xi_inf, tail_err = math.nan, math.nan
    tail_done = not want_limit
    if mode == ADAPTIVE:
        mesh = np.empty(256)
        n_mesh = 0
    h, sigma, err_prev, rejected_nonfinite, rejected = h0, 0.0, 1e-4, False, False
    cont = Continuation(tau_targets.size, 0.0, 1.0, 0.0)
    track, n_track = np.empty((256, 3)), 0
    n, sub = 0, 0
    start = StepState(xi, s, tau, dxi, ds, dtau)  # at the start of the current mesh step
    while n < max_steps:
        if mode == REPLAY:
            h = mesh[min(n // split, n_mesh - 1)] / split
            sub = n % split
            if sub == 0:
                start = StepState(xi, s, tau, dxi, ds, dtau)
        else:
            start = StepState(xi, s, tau, dxi, ds, dtau)
        K[0, 0], K[0, 1], K[0, 2] = dxi, ds, dtau
        xi1, s1, tau1, ex, es, et = erk_step(method, K, xi, s, tau, h, p)
        if fsal:
            dxi1, ds1, dtau1 = K[stages - 1, 0], K[stages - 1, 1], K[stages - 1, 2]
            E = dxi1 / ds1
        else:
            dxi1, ds1, dtau1, E = derivatives(xi1, s1, p)
        finite = math.isfinite(xi1) and math.isfinite(dxi1) and math.isfinite(tau1) and math.isfinite(dtau1)
        if mode == ADAPTIVE:
            err = error_norm(ex, es, et, xi, xi1, s1, tau1, ctrl_tol, atol, with_tau) if finite else math.inf
            if not err <= 1.0:  # rejected (also when a stage left the finite range)
                rejected_nonfinite = not finite
                h *= rejected_factor(PI_CONTROLLER, err, q)
                rejected = True
                if h < H_FLOOR * max(1.0, sigma):
                    return Run(NONFINITE if rejected_nonfinite else STEP_UNDERFLOW, math.nan, n, tail_err, mesh,
                               n_mesh, cont, track, n_track, at_mesh)
                continue
            if n_mesh == mesh.size:
                mesh = np.concatenate((mesh, np.empty(mesh.size)))
            mesh[n_mesh] = h
            n_mesh += 1
        n += 1
        if not finite:
            return Run(NONFINITE, math.nan, n, tail_err, mesh, n_mesh, cont, track, n_track, at_mesh)
        if (n - 1) % split == split - 1:  # the end of a mesh step
            if n_track == track.shape[0]:
                track = np.concatenate((track, np.empty(track.shape)))
            track[n_track, 0], track[n_track, 1], track[n_track, 2] = xi1, s1, E
            n_track += 1
        # targets crossed in this substep, located from the mesh step's start (theta relative to the mesh step)
        while it < tau_targets.size and tau_targets[it] <= tau1:
            th = (sub + hermite_crossing(tau, tau1, h * dtau, h * dtau1, tau_targets[it])) / split
            xt, st, _, _ = state_where(method, K, 2, tau_targets[it], th, start, h * split, split, p_tau)
            xi_at[it], u_at[it], at_mesh[it] = xt, st - xt, (n - 1) // split
            it += 1
        while ix < xi_targets.size and xi_targets[ix] <= xi1:
            th = (sub + hermite_crossing(xi, xi1, h * dxi, h * dxi1, xi_targets[ix])) / split
            _, _, tau_at[ix], rate_at[ix] = state_where(method, K, 0, xi_targets[ix], th, start, h * split,
                                                        split, p_tau)
            ix += 1
        xi, s, tau, dxi, ds, dtau = xi1, s1, tau1, dxi1, ds1, dtau1
        sigma += h
        if mode == ADAPTIVE:
            factor, err_prev = accepted_factor(PI_CONTROLLER, err, err_prev, q, rejected)
            h *= factor
            rejected = False
        u = s - xi
        if not tail_done:
            bound = tail_error(k, a, bb, u, E)
            if bound <= TAIL_SAFETY * (atol + TAIL_RTOL * abs(xi)):
                xi_inf, tail_err, tail_done = xi + tail_slip(k, a, bb, u, E), bound, True
        if it < tau_targets.size and E < TAIL_SAFETY * rtol and math.isfinite(xi_inf):
            continue_in_closed_form(k, a, bb, xi_inf, u, tau, tau_targets[it:], xi_at[it:], u_at[it:])
            cont = Continuation(it, E, a + 2.0 * bb * u, u)
            it = tau_targets.size
        if tail_done and it == tau_targets.size and ix == xi_targets.size:
            return Run(OK, xi_inf, n, tail_err, mesh, n_mesh, cont, track, n_track, at_mesh)
    return Run(MAX_STEPS, xi_inf, n, tail_err, mesh, n_mesh, cont, track, n_track, at_mesh)


@njit(cache=True, fastmath=FAST, error_model="numpy")
def richardson_pair(method, adaptive, h, p, tol, max_steps, coarse_samples, fine_samples):
    """(coarse, fine) :class:`Run` of :func:`march`: the coarse run (adaptive from the first trial step h, building
    the mesh; fixed: step 2h) and the fine run on the same mesh halved, recording into ``coarse_samples`` and
    ``fine_samples``. Where the adaptive run fails on its first step there is no mesh, and the coarse result stands
    for both."""
    coarse = march(method, Mesh(ADAPTIVE if adaptive else REPLAY, h, np.full(1, 2.0 * h), 1, 1), p, tol, max_steps,
                   coarse_samples)
    if coarse.n_mesh == 0:
        return coarse, coarse
    fine = march(method, Mesh(REPLAY, h, coarse.mesh, coarse.n_mesh, 2), p, tol, max_steps, fine_samples)
    return coarse, fine


@njit(cache=True, fastmath=FAST, error_model="numpy")
def crossings(method, h, mesh, n_mesh, split, p, max_steps, targets, tau_at, rate_at):
    """Status of a replay of ``mesh`` (``split`` substeps per step) recording tau and dxi/dtau where xi crosses the
    increasing ``targets``."""
    none = np.empty(0)
    return march(method, Mesh(REPLAY, h, mesh, n_mesh, split), p, Tolerances(0.0, 0.0, 0.0), max_steps,
                 Samples(none, none, none, targets, tau_at, rate_at, False)).status


@njit(cache=True, fastmath=FAST)
def continued_error(run, j, u):
    """Bound on the closed-form continuation's error in u at sample j of a :class:`Run` (0 before it)."""
    cont = run.cont
    return continuation_error(cont.E, cont.g, u - cont.u) if j >= cont.first else 0.0


@njit(cache=True, fastmath=FAST)
def fine_share(order):
    """Bound on the fine run's error per unit of the pair's difference in a share of the error that converges at
    no less than half the asymptotic rate: 1/(2^(p-1) - 1) (asymptotically the fine error is 1/(2^p - 1) of it)."""
    return 1.0 / (2.0 ** (order - 1) - 1.0)


@njit(cache=True, fastmath=FAST)
def contributions(coarse, fine, k, a, bb):
    """(d, c, ln G, carried) over the common mesh points t of a pair (:func:`march`'s tracks): the pair's difference
    in the slip d[t], the contribution c[t] of mesh step t to it, the log of the propagation G[t] of a difference at
    t to the last common mesh point, and the sum of the |contributions| up to t carried to t [1].

    The slip's error is the sum of the contributions of every step, each carried on by the 1-D equation
    dxi/ds = E(xi, s), whose sensitivity to xi is dE/dxi = E (g - k), g = a + 2 b u: a difference carried over a
    step ds is multiplied by exp(E (g - k) ds) (damped along the creep manifold, g < 0; amplified from the unstable
    start on the stick-slip side). The runs are compared at equal contact-age time s, d = dxi - E ds at equal sigma
    (first order): at equal sigma they differ by a shift along the trajectory that is no error of the slip.
    """
    n = min(coarse.n_track, fine.n_track)
    tc, tf = coarse.track, fine.track
    d, c, log_g = np.empty(n), np.empty(n), np.empty(n)
    d_prev, s_prev = 0.0, 0.0
    for t in range(n):
        xi, s, E = tc[t, 0], tc[t, 1], tc[t, 2]
        d[t] = (xi - tf[t, 0]) - E * (s - tf[t, 1])
        log_g[t] = E * (a + 2.0 * bb * (s - xi) - k) * (s - s_prev)  # this step's propagation, for now
        c[t] = d[t] - d_prev * math.exp(log_g[t])
        d_prev, s_prev = d[t], s
    after = 0.0
    for t in range(n - 1, -1, -1):
        after, log_g[t] = after + log_g[t], after
    # carried[m] = sum over t <= m of |c[t]| exp(log_g[t] - log_g[m]): every contribution carried to mesh point m,
    # built forward in one pass (one exp a step) so that :func:`cancelled` costs O(1) a sample, not O(mesh); the
    # factors exp(log_g[t] - log_g[t + 1]) are one step's propagation each, so nothing overflows on the way
    carried = np.empty(n)
    total = 0.0
    for t in range(n):
        total = (total * math.exp(log_g[t - 1] - log_g[t]) if t > 0 else 0.0) + abs(c[t])
        carried[t] = total
    return d, c, log_g, carried


@njit(cache=True, fastmath=FAST)
def cancelled(pair_slip, m, d):
    """Sum of the |contributions| (:func:`contributions`) to the pair's slip difference d at a sample in mesh step
    m, each carried to it (m = -1 or beyond the common mesh: after its end, like xi_inf) [1].

    Where contributions of opposite signs cancel in the coarse run (the stiff start and the tail for m2 = 0 with
    chi/A >~ 1, slow tails), its error need not exceed the fine run's (chi/A = 3.16, mu1/A = 0.1, m2 = 0, dp5,
    rtol 1e-4: 1.4 % of the contributions left, estimate 0.05x the true error); the fine run's share of each
    (:func:`fine_share`) bounds its error whatever their signs.
    """
    dd, c, log_g, carried = pair_slip
    upto = c.size if m < 0 or m > c.size else m  # the common mesh points before the sample
    if upto == 0:
        return abs(d)
    return abs(d - dd[upto - 1]) + carried[upto - 1]


@njit(cache=True, fastmath=FAST)
def crossing_error(d_tau, d_target, order):
    """Estimate of the coarse run's error in t_f (reduced), from the pair's difference d_tau = tau_c - tau_f of
    the crossings of each run's own f xi_inf and the part of it due to the difference of those targets,
    d_target = f (xi_inf_c - xi_inf_f) / xi'(t_f).

    The error of t_f has two shares, the trajectory's near t_f and the relaxed slip's; late crossings see nearly
    the same error in both (xi(t) - xi_inf -> 0), so they cancel to ~10 %, and where the coarse run's cancel
    further its error need not exceed the fine run's: COARSE_GAIN |d_tau| alone came out at 0.5x the true error.
    The fine run's error is at most the sum of its two shares, each at most :func:`fine_share` of the pair's
    difference in that share [1]; that bound is added to |d_tau|.
    """
    hedge = (abs(d_tau - d_target) + abs(d_target)) * fine_share(order)
    return COARSE_GAIN * (abs(d_tau) + hedge)


class TimeSamples(NamedTuple):
    """A point's samples at the increasing reduced times ``tau``: xi and u = ln psi with their error estimates."""

    tau: np.ndarray
    xi_at: np.ndarray
    u_at: np.ndarray
    xi_at_err: np.ndarray
    u_at_err: np.ndarray


class FractionTimes(NamedTuple):
    """A point's reduced times tau where xi = f xi_inf for each f of ``fractions`` (t50, t90), with estimates."""

    fractions: np.ndarray
    tau_at: np.ndarray
    tau_at_err: np.ndarray


class PointResult(NamedTuple):
    status: int
    xi_inf: float
    xi_inf_err: float
    steps: int
    """Steps of the fine run of pass 1."""


@njit(cache=True, fastmath=FAST, error_model="numpy")
def solve_stop_point(method, h, p, tol, max_steps, finite, samples, times):
    """One stop point as a Richardson pair (module docstring): pass 1 gives xi_inf and the time-resolved
    samples with their error estimates; if ``times.fractions`` is not empty a second pass (same meshes) finds tau
    where xi = fraction * xi_inf (t50, t90).

    t_f is ill-conditioned where the slip creeps: an error d in xi_inf, or in xi near t_f, moves it by
    d / xi'(t_f), i.e. relatively by up to G = f xi_inf / (t_f xi'(t_f)) times rtol (G ~ 30 for t90 with
    m1/A = 0.3). Where G > 1 the pair is run again with tolerances / G (fixed steps: h G^(-1/p)) and the crossings
    are located on its meshes. Each run crosses the fraction of its own xi_inf (:func:`crossing_error`).

    ``method``: :class:`Method` (adaptive where it has an error estimate); ``h``: the fine step (fixed-step methods)
    or the first trial step of the coarse run (adaptive); ``p``: :class:`sweep.integrate.models.stop.StopParams`;
    ``tol``:
    :class:`Tolerances` (rtol of the scene, atol, the controller's local tolerance); ``samples``:
    :class:`TimeSamples`, ``times``: :class:`FractionTimes` (filled here). Returns a :class:`PointResult`.
    """
    none = np.empty(0)
    order, adaptive = method.order, method.q > 0
    k, a, bb = p.k, p.a, p.b
    fractions, tau_at_fraction, tau_at_fraction_err = times
    tau_targets, xi_at, u_at, xi_at_err, u_at_err = samples
    run_tol = Tolerances(TAIL_TIGHTENING * tol.rtol, tol.atol, tol.ctrl)
    tau_at_fraction[:] = math.nan
    tau_at_fraction_err[:] = math.nan
    # pass 1: the coarse run is returned, the fine one's samples go to (xf_at, uf_at)
    xf_at, uf_at = np.full(tau_targets.size, math.nan), np.full(tau_targets.size, math.nan)
    ret, partner = richardson_pair(method, adaptive, h, p, run_tol, max_steps,
                                   Samples(tau_targets, xi_at, u_at, none, none, none, finite),
                                   Samples(tau_targets, xf_at, uf_at, none, none, none, finite))
    mesh, n_mesh = ret.mesh, ret.n_mesh
    if n_mesh == 0:
        return PointResult(ret.status, math.nan, math.nan, 0)
    x_r, x_p = ret.xi_inf, partner.xi_inf
    pair_slip = contributions(ret, partner, k, a, bb)
    share = fine_share(order)
    for j in range(tau_targets.size):
        d = xi_at[j] - xf_at[j]
        xi_at_err[j] = COARSE_GAIN * (abs(d) + share * cancelled(pair_slip, ret.at_mesh[j], d))
        u_at_err[j] = COARSE_GAIN * abs(u_at[j] - uf_at[j]) + continued_error(ret, j, u_at[j]) + continued_error(
            partner, j, uf_at[j])
    st, n = (ret.status if ret.status != OK else partner.status), partner.steps
    if not finite:
        return PointResult(NO_FINITE_LIMIT if st == OK else st, math.nan, math.nan, n)
    xi_err = (COARSE_GAIN * (abs(x_r - x_p) + share * cancelled(pair_slip, -1, x_r - x_p)) + ret.tail_err
              + partner.tail_err)
    if fractions.size == 0 or st != OK:
        return PointResult(st, ret.xi_inf, xi_err, n)
    # pass 2: the crossings, on the same meshes, each run of the fractions of its own xi_inf
    rate_r, rate_p, tau_p = np.empty(fractions.size), np.empty(fractions.size), np.empty(fractions.size)
    st2 = crossings(method, h, mesh, n_mesh, 1, p, max_steps, fractions * x_r, tau_at_fraction, rate_r)
    cond = np.max(fractions * x_r / (tau_at_fraction * rate_r)) if st2 == OK else 0.0
    if cond > 1.0:  # ill-conditioned crossings: the whole pair again with tolerances / cond
        h = h * cond ** (-1.0 / order)
        nothing = Samples(none, none, none, none, none, none, True)
        c3, f3 = richardson_pair(method, adaptive, h, p, Tolerances(run_tol.rtol, tol.atol / cond, tol.ctrl / cond),
                                 max_steps, nothing, nothing)
        if c3.status != OK or f3.status != OK:
            return PointResult(c3.status if c3.status != OK else f3.status, x_r, xi_err, n)
        mesh, n_mesh, x_r, x_p = c3.mesh, c3.n_mesh, c3.xi_inf, f3.xi_inf
        st2 = crossings(method, h, mesh, n_mesh, 1, p, max_steps, fractions * x_r, tau_at_fraction, rate_r)
    st2p = crossings(method, h, mesh, n_mesh, 2, p, max_steps, fractions * x_p, tau_p, rate_p)
    if st2 != OK or st2p != OK:
        return PointResult(st2 if st2 != OK else st2p, ret.xi_inf, xi_err, n)
    for j in range(fractions.size):
        tau_at_fraction_err[j] = crossing_error(tau_at_fraction[j] - tau_p[j], fractions[j] * (x_r - x_p) / rate_r[j],
                                                order)
    return PointResult(st, ret.xi_inf, xi_err, n)


class StopPoints(NamedTuple):
    """Per-point arrays of a batch of stop points (reduced k = chi/A, a = mu1/A, b = m2/A, s_c, step h)."""

    k: np.ndarray
    a: np.ndarray
    b: np.ndarray
    s_c: np.ndarray
    h: np.ndarray


class StopOutputs(NamedTuple):
    """Flat per-point output arrays of :func:`stop_batch` (rows: points; sampled arrays: points x times)."""

    xi_inf: np.ndarray
    xi_inf_err: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    xi_at: np.ndarray
    u_at: np.ndarray
    xi_at_err: np.ndarray
    u_at_err: np.ndarray
    tau_at_fraction: np.ndarray
    tau_at_fraction_err: np.ndarray



pin_module(__name__)
