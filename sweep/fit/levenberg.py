"""Many small bounded least-squares problems at once: a projected Levenberg-Marquardt method vectorised over tasks.

Every task (a curve's fit, a profile point) minimises its sum of squared weighted residuals over its moving
parameters (the free parameters not held fixed), within the bound box. One round of :class:`ProblemStack` serves
one iteration of every unfinished task: each posts its trial parameter set and the forward-difference neighbours of
that set (the Jacobian is computed speculatively, at the trial point, so that an iteration costs one engine round),
or its trial set alone where the Jacobian follows Broyden's secants (``jac0``).
Then, per task, in scaled variables z = theta/scale (scale: ParamSpace.scale):

* g = J^T r, H = J^T J; a moving parameter at a bound whose gradient points out of the box is frozen for the step;
* the step solves (H + lambda diag(H)) dz = -g (Marquardt 1963), and the trial point is z + dz clipped to the box;
* the trial is accepted where it solves more of the data (fewer residuals the model gave no number for: a failed
  solve is never traded for a lower misfit, sweep.fit.stack) or as many and lowers the misfit; lambda then shrinks
  by max(1/3, 1 - (2 rho - 1)^3) (rho: actual over predicted decrease, 0 at least), else it grows by nu, and nu
  doubles (Nielsen 1999; Madsen, Nielsen & Tingleff, Methods for non-linear least squares problems, 2004, sec. 3.2);
* a task stops when its predicted or actual decrease falls below ftol x the misfit, when the step falls below xtol
  (relative, scaled variables), or after max_rounds rounds (status 0).

Jacobians: forward differences d r/d theta_j = (r(theta + h_j) - r(theta))/h_j, h_j = FD_STEP x scale_j (a stick-slip
problem's finer step instead: ProblemStack.fd_step, sweep.fit.event_fit; backward where the upper bound is closer),
m + 1 sets an iteration: the Jacobian steers the steps, and its error (~FD_STEP)
barely moves the optimum they stop at (sweep.fit.local). The Jacobian of the best set, which the last step used,
also gives its covariance (:attr:`Solutions.jac`): with the engine at rtol 1e-6 it carries a relative error
~rtol/FD_STEP ~ 1e-3 and a truncation error ~FD_STEP ~ 1e-3, far below what the noise of a measured curve (>~1e-3)
resolves (central differences, 2p sets more, moved the standard errors of 100 records and 30 stop curves by < 1.4e-3
of themselves and the 95 % bounds by < 4e-4 of their half-widths).

An offset parameter (ProblemStack.offset: a record's mu0, which shifts every weighted residual along a direction g
that depends on no parameter) is handled exactly: its Jacobian column is g (no forward solve: its neighbour set is
not posted), and after every forward solve it moves to its best value given the others, c = -sum r g / sum g^2
(clipped to its bounds; r += c g, exactly the residuals there). The others' columns do not depend on it, so the
forward-difference Jacobian of the trial set holds at the moved set too: 4 sets an iteration instead of 5 for a, b,
Dc, mu0. With :attr:`Tolerances.resolved` too, 100 records of their own
times (benchmarks/fit_records.py's, from its start: a, b 20 % low, Dc 2x high, search "local") took 6.3 rounds each
on average instead of 8.2 (at most 7 instead of 17), the least-squares stage 0.35 s instead of 0.53-0.60 s (A/B in
one process, 3 runs each); best values moved by < 7e-3 standard errors, interval ends by < 5e-4 of the half-widths.

Each task's numbers depend only on its own residuals: the sums over residuals (misfit, J^T r, J^T J, Broyden's
update) run per task over its own residuals, in order, in compiled loops (sweep.fit.stack pads shorter problems with
zeros, which would change the rounding of numpy's pairwise sums), and the small linear systems are solved one per
task; so a task takes exactly the path it would take alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from .space import ParamSpace
from .stack import ProblemStack

__all__ = ["FD_STEP", "FIT", "HOLD", "STATUS", "STATUS_FLAGS", "Solutions", "Tolerances", "solve"]

FD_STEP = 1e-3
"""Finite-difference step relative to each parameter's scale (ParamSpace.scale)."""


@dataclass(frozen=True)
class Tolerances:
    """Stopping rules: relative decrease of the misfit (``ftol``), relative step in scaled variables (``xtol``),
    rounds at most (``max_rounds``), and ``resolved``: a task stops where the decrease that the undamped
    (Gauss-Newton) step of its free parameters predicts, bounds ignored, is below resolved^2 noise variances (s^2 =
    misfit/(n - m)), i.e. where its optimum lies within ~``resolved`` standard errors by its own Jacobian: closer, the
    misfit's changes are the forward solves' own error (with the engine at 10 rtol, benchmarks/fit_records.py's
    records rose by ~2e-7 on every trial past a predicted 3e-7, and ftol 1e-10 alone took ~6 rejected rounds more).
    An optimum beyond a bound predicts a large decrease: the steps go on until the bound holds that parameter."""

    ftol: float
    xtol: float
    max_rounds: int
    resolved: float = 1e-2


FIT = Tolerances(ftol=1e-10, xtol=1e-9, max_rounds=100)
"""A best fit, whose Jacobian gives the covariance."""
HOLD = Tolerances(ftol=1e-6, xtol=1e-5, max_rounds=100)
"""A profile point, whose misfit only is kept: its rise over the best fit is read against 3.84 to ~1e-3, and ftol
1e-6 of a misfit of ~n = 200 is 2e-4 of it; a parameter 1e-5 (relative, xtol) off its optimum changes the misfit by
~(1e-5/0.01)^2 for a 1 % standard error. On 30 curves of benchmarks/fit.py the 95 % bounds moved by < 1.3e-4 of
their half-widths against ftol 1e-8, xtol 1e-6, for 12 % fewer forward solves."""
LAMBDA0 = 1e-4
"""Initial damping lambda (relative to diag(J^T J), Marquardt's scaling). From the global grid's best point the 100
curves of benchmarks/fit.py took 9 forward-difference iterations (median; the slowest 19) at 1e-3, 7 (17) at 1e-4."""
STATUS = {0: "max_rounds reached", 1: "nothing to move", 2: "ftol: the misfit no longer decreases",
          3: "xtol: the step is below xtol"}
STATUS_FLAGS = {0: "max_rounds_reached", 1: "nothing_to_move", 2: "misfit_converged", 3: "step_converged"}
"""CF flag_meanings of STATUS."""


@dataclass
class Solutions:
    """Per task: best parameter set (T, p) (held parameters at their values), its weighted residuals (T, n_max),
    misfit (T,), function evaluations (rounds in which the task posted sets), whether sliding was stable before every
    stop, the status (a key of STATUS), the number of residuals the model gave no number for at the best set
    (MODEL_FAILED stands in for them in ``residuals`` and ``rss``) and the Jacobian (T, n_max, m) of the residuals
    over the moving parameters (in their order in theta) at the best set that the last step used: forward
    differences, with the offset parameter's exact column (None where :func:`solve` had ``jac0``: Broyden's)."""

    theta: np.ndarray
    residuals: np.ndarray
    rss: np.ndarray
    nfev: np.ndarray
    stable: np.ndarray
    status: np.ndarray
    failures: np.ndarray
    jac: np.ndarray | None


def _neighbours(theta: np.ndarray, cols: np.ndarray, sp: ParamSpace, step: float | np.ndarray = FD_STEP
                ) -> tuple[np.ndarray, np.ndarray]:
    """(sets (T, 1 + m, p): theta then its forward-difference neighbours along ``cols`` (T, m), widths (T, m): signed
    distance from theta to its neighbour); ``step`` relative to the scale, one or per task (T, 1)."""
    T, m = cols.shape
    ti = np.arange(T)[:, None]
    base = theta[ti, cols]
    h = step * sp.scale[cols]
    up, down = np.minimum(base + h, sp.upper[cols]), np.maximum(base - h, sp.lower[cols])
    sets = np.repeat(theta[:, None, :], 1 + m, axis=1)
    k = np.arange(m)[None, :]
    one = np.where(up > base, up, down)
    sets[ti, 1 + k, cols] = one
    return sets, one - base


def _jacobian(r: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """(T, n, m) from the residuals (T, S, n) of :func:`_neighbours`' sets."""
    return np.swapaxes((r[:, 1:] - r[:, :1]) / widths[:, :, None], 1, 2)


@numba.njit(cache=True, nogil=True)
def _sumsq_rows(r, n, out):  # pragma: no cover (compiled)
    """out[t] = sum over i < n[t] of r[t, i]^2, in order."""
    for t in range(r.shape[0]):
        acc = 0.0
        for i in range(n[t]):
            acc += r[t, i] * r[t, i]
        out[t] = acc


@numba.njit(cache=True, nogil=True)
def _normal_rows(J, r, n, g, H):  # pragma: no cover (compiled)
    """g[t] = J[t]^T r[t], H[t] = J[t]^T J[t], each sum over i < n[t], in order."""
    for t in range(J.shape[0]):
        m = J.shape[2]
        for a in range(m):
            acc = 0.0
            for i in range(n[t]):
                acc += J[t, i, a] * r[t, i]
            g[t, a] = acc
            for b in range(a, m):
                acc = 0.0
                for i in range(n[t]):
                    acc += J[t, i, a] * J[t, i, b]
                H[t, a, b] = acc
                H[t, b, a] = acc


@numba.njit(cache=True, nogil=True)
def _normal_rows_of(Jq, problem, cols, scale, r, n, g, H):  # pragma: no cover (compiled)
    """:func:`_normal_rows` of the Jacobians J[t] = Jq[problem[t]][:, cols[t]] scale[t], read in place (the same
    products in the same order: the same bits as of J built first)."""
    m = cols.shape[1]
    for t in range(r.shape[0]):
        q = problem[t]
        for a in range(m):
            ca, sa = cols[t, a], scale[t, a]
            acc = 0.0
            for i in range(n[t]):
                acc += (Jq[q, i, ca] * sa) * r[t, i]
            g[t, a] = acc
            for b in range(a, m):
                cb, sb = cols[t, b], scale[t, b]
                acc = 0.0
                for i in range(n[t]):
                    acc += (Jq[q, i, ca] * sa) * (Jq[q, i, cb] * sb)
                H[t, a, b] = acc
                H[t, b, a] = acc


@numba.njit(cache=True, nogil=True)
def _broyden_rows(J, dr, dz, n):  # pragma: no cover (compiled)
    """Broyden's rank-one secant update in place, J[t] += (dr[t] - J[t] dz[t]) dz[t]^T / (dz[t]^T dz[t]), over the
    rows i < n[t] (the padding beyond stays zero)."""
    for t in range(J.shape[0]):
        m = J.shape[2]
        dd = 0.0
        for k in range(m):
            dd += dz[t, k] * dz[t, k]
        for i in range(n[t]):
            s = 0.0
            for k in range(m):
                s += J[t, i, k] * dz[t, k]
            c = dr[t, i] - s
            for k in range(m):
                J[t, i, k] += c * (dz[t, k] / dd)


@numba.njit(cache=True, nogil=True)
def _dot_rows(x, y, n, out):  # pragma: no cover (compiled)
    """out[t] = sum over i < n[t] of x[t, i] y[t, i], in order."""
    for t in range(x.shape[0]):
        acc = 0.0
        for i in range(n[t]):
            acc += x[t, i] * y[t, i]
        out[t] = acc


def _offset_column(stack: ProblemStack, problem: np.ndarray) -> np.ndarray | None:
    """(T, n_max): d(weighted residual)/d(offset parameter) of each task's problem (ProblemStack.offset_direction),
    None where the stack has no offset parameter."""
    return None if stack.offset is None else stack.offset_direction()[problem]


def _to_best_offset(stack: ProblemStack, g: np.ndarray, theta: np.ndarray, r: np.ndarray, n: np.ndarray) -> None:
    """Move each task's offset parameter (column ``stack.offset`` of ``theta`` (T, p)) to its best value given the
    others, within its bounds, and its residuals ``r`` (T, n_max) with it, in place: c = -sum r g / sum g^2 over its
    own n residuals (the misfit is exactly quadratic in it). The caller passes only tasks that move it and whose
    residuals the model solved."""
    j, sp = stack.offset, stack.space
    rg, gg = np.empty(theta.shape[0]), np.empty(theta.shape[0])
    _dot_rows(np.ascontiguousarray(r), np.ascontiguousarray(g), n, rg)
    _dot_rows(np.ascontiguousarray(g), np.ascontiguousarray(g), n, gg)
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.where(gg > 0, -rg / gg, 0.0)
    new = np.clip(theta[:, j] + c, sp.lower[j], sp.upper[j])
    c = new - theta[:, j]
    theta[:, j] = new
    r += c[:, None] * g


def _sumsq(r: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Per task, sum of r^2 over its own n residuals (in order: a task's sum never depends on the tasks beside it,
    as numpy's pairwise sums over padded rows would)."""
    out = np.empty(r.shape[0])
    _sumsq_rows(np.ascontiguousarray(r), np.ascontiguousarray(n), out)
    return out


def _normal_equations(J: np.ndarray, r: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(g = J^T r (T, m), H = J^T J (T, m, m)), summed per task over its own n residuals, in order (one compiled
    pass; as stacked numpy products, contiguous copies per group of equal length were needed for the same bits)."""
    T, _, m = J.shape
    g, H = np.empty((T, m)), np.empty((T, m, m))
    _normal_rows(np.ascontiguousarray(J), np.ascontiguousarray(r), np.ascontiguousarray(n), g, H)
    return g, H


def _predicted(g: np.ndarray, H: np.ndarray, dz: np.ndarray) -> np.ndarray:
    """Decrease of the misfit sum r^2 that the linear model predicts for the step dz (twice that of r^2/2)."""
    # sums over the last axis only (einsum's loop order changed with the number of tasks: a task's last bits did)
    return -(2.0 * np.sum(g * dz, axis=1) + np.sum(np.sum(H * dz[:, None, :], axis=2) * dz, axis=1))


def _gauss_newton_decrease(g: np.ndarray, H: np.ndarray, frozen: np.ndarray) -> np.ndarray:
    """Decrease of the misfit that the linear model predicts for the undamped (Gauss-Newton) step of the parameters
    not ``frozen``, bounds ignored, g^T H^+ g (pseudo-inverse: H may be singular): the distance to the model's
    optimum in noise variances, large where the optimum lies beyond a bound (no stop there: the step goes on to it)."""
    free = ~frozen
    gf = np.where(free, g, 0.0)
    Hf = np.where(free[:, :, None] & free[:, None, :], H, 0.0)
    return np.sum(gf * np.einsum("tij,tj->ti", np.linalg.pinv(Hf), gf), axis=1)


def _within_bounds(z, dz, lo, hi, g, H) -> tuple[np.ndarray, np.ndarray]:
    """(step, predicted decrease) kept inside the box: the step projected onto the box where that still decreases
    the linear model, else the step shortened along its direction until it meets the first bound (a Levenberg-
    Marquardt step decreases the model all along its direction, so the shortened step always does)."""
    inside = np.all((z + dz >= lo) & (z + dz <= hi), axis=1)
    proj = np.clip(z + dz, lo, hi) - z
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(dz > 0, (hi - z) / dz, np.where(dz < 0, (lo - z) / dz, np.inf))
    short = dz * np.clip(np.min(room, axis=1), 0.0, 1.0)[:, None]
    p_proj, p_short = _predicted(g, H, proj), _predicted(g, H, short)
    use_proj = inside | (p_proj > 0)
    return np.where(use_proj[:, None], proj, short), np.where(use_proj, p_proj, p_short)


def _step(z, g, H, frozen, lam, lo, hi, eye) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(the damped step (T, m) with the ``frozen`` parameters held, that step kept inside the box, its predicted
    decrease) (:func:`solve`)."""
    free = ~frozen
    Hf = np.where(free[:, :, None] & free[:, None, :], H, 0.0)
    diag = np.diagonal(Hf, axis1=1, axis2=2)
    floor = 1e-12 * np.maximum(np.max(diag, axis=1, keepdims=True), 1e-300)
    damped = Hf + np.where(eye, (lam[:, None] * np.maximum(diag, floor))[:, :, None] + frozen[:, :, None], 0.0)
    raw = np.linalg.solve(damped, -np.where(free, g, 0.0)[:, :, None])[:, :, 0]
    dz, pred = _within_bounds(z, raw, lo, hi, g, H)
    return raw, dz, pred


def solve(stack: ProblemStack, problem: np.ndarray, theta0: np.ndarray, hold: np.ndarray | None = None,
          tol: Tolerances = FIT, jac0: np.ndarray | None = None) -> Solutions:
    """Minimise every task's misfit; task i belongs to problem ``problem[i]`` and starts at ``theta0[i]`` (clipped
    to the bounds). ``hold`` (T, p) bool marks parameters held at their start (a profile point); every task must
    move the same number of parameters.

    ``jac0`` (Q, n_max, p): each problem's Jacobian over every free parameter (a profile point: its problem's best
    fit's); a task starts from its problem's columns of its moving parameters, read in place (a copy per task was
    ~0.1 s of 800 profile points x 1,000 samples x 3 parameters, and most of them stop at their first trial) and
    copied only for the tasks that go on. The tasks then post their trial sets only, one forward solve an iteration
    instead of m + 1, and the Jacobian follows Broyden's rank-one secant update J += (dr - J dz) dz^T/(dz^T dz)
    after every trial (Dennis & Schnabel, Numerical Methods for Unconstrained Optimization, 1983, sec. 8.1).
    """
    sp = stack.space
    problem = np.asarray(problem, dtype=np.intp)
    T, p = len(problem), sp.p
    theta = np.clip(np.array(theta0, dtype=float).reshape(T, p), sp.lower, sp.upper)
    hold = np.zeros((T, p), bool) if hold is None else np.asarray(hold, dtype=bool)
    moving = ~hold
    m = int(moving[0].sum()) if T else 0
    if T and np.any(moving.sum(axis=1) != m):
        raise ValueError("every task must move the same number of parameters")
    cols = np.nonzero(moving)[1].reshape(T, m)
    n = stack.n_res[problem]
    scale = sp.scale[cols]  # (T, m)
    lo, hi = sp.lower[cols] / scale, sp.upper[cols] / scale

    broyden = jac0 is not None
    g_off = _offset_column(stack, problem)  # the offset parameter (module docstring): its column, where it moves
    k_off = np.where(cols == stack.offset, np.arange(m)[None, :], m).min(axis=1) if g_off is not None \
        else np.full(T, m)

    def post(idx, th):
        """Residuals (and the Jacobian) of the tasks ``idx`` at ``th`` (their offset parameter then moved to its
        best value, ``th`` updated in place)."""
        if broyden:
            r, ok, bad = stack.residuals(problem[idx], th[:, None, :])
            r, J = r[:, 0], None
        else:
            sets, widths = _neighbours(th, cols[idx], sp, FD_STEP if stack.fd_step is None  # (a stick-slip
                                       else stack.fd_step[problem[idx]][:, None])  # problem's: sweep.fit.event_fit)
            at = np.flatnonzero(k_off[idx] < m)
            sets[at, 1 + k_off[idx[at]]] = th[at]  # no solve: the same set as the trial (solved once)
            widths[at, k_off[idx[at]]] = 1.0
            r, ok, bad = stack.residuals(problem[idx], sets)
            J = _jacobian(r, widths) * scale[idx][:, None, :]
            r = r[:, 0]
            if at.size:
                J[at, :, k_off[idx[at]]] = g_off[idx[at]] * scale[idx[at], k_off[idx[at]]][:, None]
        move = np.flatnonzero((k_off[idx] < m) & (bad[:, 0] == 0))
        if move.size:
            th_m, r_m = th[move], r[move]
            _to_best_offset(stack, g_off[idx[move]], th_m, r_m, n[idx[move]])
            th[move], r[move] = th_m, r_m
        return r, J, ok[:, 0], bad[:, 0]

    nfev = np.ones(T, np.intp)
    if m == 0:  # nothing to move: the residuals at the start
        r, ok, bad = stack.residuals(problem, theta[:, None, :])
        return Solutions(theta, r[:, 0], _sumsq(r[:, 0], n), nfev, ok[:, 0], np.ones(T, np.intp), bad[:, 0],
                         np.zeros((T, stack.n_max, 0)))
    status = np.zeros(T, np.intp)
    r, J, stable, failures = post(np.arange(T), theta)
    rss = _sumsq(r, n)
    if broyden:
        jac0 = np.ascontiguousarray(jac0, dtype=float)
        g, H = np.empty((T, m)), np.empty((T, m, m))
        _normal_rows_of(jac0, problem, cols, scale, np.ascontiguousarray(r), n, g, H)
        J, copied = np.zeros((T, stack.n_max, m)), np.zeros(T, bool)  # (zero pages: untouched until copied)
    else:
        g, H = _normal_equations(J, r, n)
    lam = np.full(T, LAMBDA0)
    nu = np.full(T, 2.0)
    active = np.ones(T, bool)
    eye = np.eye(m, dtype=bool)
    for _ in range(tol.max_rounds):
        a = np.flatnonzero(active)
        if not a.size:
            break
        z = theta[a[:, None], cols[a]] / scale[a]
        ga, Ha = g[a], H[a]
        frozen = ((z <= lo[a]) & (ga > 0)) | ((z >= hi[a]) & (ga < 0))
        raw, dz, pred = _step(z, ga, Ha, frozen, lam[a], lo[a], hi[a], eye)
        tiny = np.max(np.abs(dz) / (np.abs(z) + tol.xtol), axis=1) <= tol.xtol
        # a step that a bound stopped (its projection onto the box no longer descends, and the step shortened to the
        # bound is nil): the parameters on a bound that the step points out of are frozen too, and the step solved
        # again (a projected Newton step need not descend where parameters are correlated; issue 37's A held by its
        # bound stopped 100x above the misfit's minimum in m1, m2)
        blocked = ((z >= hi[a]) & (raw > 0)) | ((z <= lo[a]) & (raw < 0))
        again = tiny & np.any(blocked & ~frozen, axis=1)
        if again.any():
            _, dz2, pred2 = _step(z[again], ga[again], Ha[again], frozen[again] | blocked[again], lam[a[again]],
                                  lo[a[again]], hi[a[again]], eye)
            dz[again], pred[again] = dz2, pred2
            tiny = np.max(np.abs(dz) / (np.abs(z) + tol.xtol), axis=1) <= tol.xtol
        resolved = _gauss_newton_decrease(ga, Ha, frozen) <= tol.resolved ** 2 * rss[a] / np.maximum(n[a] - m, 1)
        flat = (pred <= tol.ftol * rss[a]) | resolved
        stop = tiny | flat
        status[a[stop]] = np.where(tiny[stop], 3, 2)
        active[a[stop]] = False
        go = ~stop
        a, dz, pred, z = a[go], dz[go], pred[go], z[go]
        if not a.size:
            break
        trial = theta[a].copy()
        ca, rows = cols[a], np.arange(a.size)[:, None]
        moved = np.clip((z + dz) * scale[a], sp.lower[ca], sp.upper[ca])
        trial[rows, ca] = np.where(dz == 0.0, trial[rows, ca], moved)  # z * scale may miss theta by an ulp
        shifted = trial[:, stack.offset].copy() if g_off is not None else None
        rt, Jt, st, ft = post(a, trial)
        if shifted is not None:  # the offset parameter's move after the solve is part of the step (Broyden's dz)
            at = np.flatnonzero(k_off[a] < m)
            dz[at, k_off[a[at]]] += (trial[at, stack.offset] - shifted[at]) / scale[a[at], k_off[a[at]]]
        nfev[a] += 1
        rss_t = _sumsq(rt, n[a])
        fewer = ft < failures[a]  # solves more of the data: better whatever the misfit
        better = fewer | ((ft == failures[a]) & np.isfinite(rss_t) & (rss_t < rss[a]))
        rho = np.maximum((rss[a] - rss_t) / np.where(pred > 0, pred, np.inf), 0.0)
        acc, rej = a[better], a[~better]
        decrease = np.where(fewer[better], np.inf, rss[acc] - rss_t[better])
        failures[acc] = ft[better]
        if broyden:  # the secant through the trial, accepted or not
            fresh = a[~copied[a]]
            J[fresh] = jac0[problem[fresh][:, None, None], np.arange(stack.n_max)[None, :, None],
                            cols[fresh][:, None, :]] * scale[fresh][:, None, :]
            copied[fresh] = True
            Ja = J[a]
            _broyden_rows(Ja, rt - r[a], np.ascontiguousarray(dz), n[a])
            at = np.flatnonzero(k_off[a] < m)  # the offset parameter's column stays the exact one
            if at.size:
                Ja[at, :, k_off[a[at]]] = g_off[a[at]] * scale[a[at], k_off[a[at]]][:, None]
            J[a] = Ja
            theta[acc], r[acc], stable[acc] = trial[better], rt[better], st[better]
            g[a], H[a] = _normal_equations(Ja, r[a], n[a])
        else:
            theta[acc], r[acc], J[acc], stable[acc] = trial[better], rt[better], Jt[better], st[better]
            g[acc], H[acc] = _normal_equations(Jt[better], rt[better], n[acc])
        lam[acc] *= np.maximum(1.0 / 3.0, 1.0 - (2.0 * rho[better] - 1.0) ** 3)
        nu[acc] = 2.0
        lam[rej] *= nu[rej]
        nu[rej] *= 2.0
        done = decrease <= tol.ftol * rss[acc]
        rss[acc] = rss_t[better]
        status[acc[done]] = 2
        active[acc[done]] = False
    return Solutions(theta, r, rss, nfev, stable, status, failures, None if broyden else J / scale[:, None, :])
