"""Every problem of a fit side by side: the residuals of many parameter sets of many problems from one engine round.

A round takes tasks (each belongs to one problem) with S parameter sets each, shape (T, S, p), and returns their
weighted residuals (T, S, n) and whether steady sliding was stable before every stop (T, S). Nothing in it loops
over tasks or problems in Python: the problems' layouts (which forward row and which sampled time each residual
reads, sweep.fit.problem) are concatenated once into index tables, and a round is a few numpy gathers around the
engine calls. That is what makes a fit of 100 curves cost about its forward solves (with a scipy least_squares per
task in a thread of its own, 95 % of a 100-curve fit was Python).

Each distinct forward point is solved once: a point is keyed by its six parameters and its row of times (rows of
times are numbered once, when the stack is built), so curves that share (K/M, V) and times share their global grid,
and profile and perturbed sets that repeat are solved once. Points go to one engine call per length of their rows of
times (0: relaxed-slip only), so a problem's numbers never depend on the problems beside it: a point's numbers do not
depend on its batch (sweep/integrate/batch.py), and a problem's residual rows are reduced only with those of problems
of the same length (sweep.fit.levenberg). Many curves in one call give, bit for bit, the
estimates of one call per curve.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numba
import numpy as np

from .forward import ForwardPoints, forward
from .problem import MODEL_FAILED, Problem

__all__ = ["Misfits", "ProblemStack", "distinct_rows"]


@numba.njit(cache=True, nogil=True, parallel=True)
def _misfit_sums(model, block_of, observed, weights, direction, n_res, out, failures, cross,
                 norm):  # pragma: no cover (compiled)
    """out[t, s] = sum over i < n_res[t] of the squared weighted residual r = (model[block_of[t, s], i] -
    observed[t, i]) weights[t, i] over the residuals the model solved, failures[t, s] the number it did not (no
    finite value): one pass, no temporaries (numpy needed 6 passes over 100 curves x 730 grid sets x 200 samples, 85 %
    of the global stage), tasks split over the threads (each sum runs in order). Where ``direction`` (T, n) has
    columns (an offset parameter, ProblemStack.offset): also cross[t, s] = sum r g and norm[t, s] = sum g^2 over the
    solved residuals, g = direction[t, i]."""
    along = direction.shape[1] > 0
    for t in numba.prange(block_of.shape[0]):
        for s in range(block_of.shape[1]):
            row = model[block_of[t, s]]
            acc = 0.0
            rg = 0.0
            gg = 0.0
            bad = 0
            for i in range(n_res[t]):
                r = (row[i] - observed[t, i]) * weights[t, i]
                if np.isfinite(r):
                    acc += r * r
                    if along:
                        g = direction[t, i]
                        rg += r * g
                        gg += g * g
                else:
                    bad += 1
            out[t, s] = acc
            failures[t, s] = bad
            if along:
                cross[t, s] = rg
                norm[t, s] = gg


@numba.njit(cache=True, nogil=True)
def _residual_rows(model, block_of, observed, weights, failed, out, failures):  # pragma: no cover (compiled)
    """out[t, s, i] = (model[block_of[t, s], i] - observed[t, i]) weights[t, i], ``failed`` where that is not finite
    (the model gave no number) and 0 where the weight is 0 (beyond a problem's residuals); and failures[t, s] the
    number of residuals the model gave no number for: one pass, no temporaries (as numpy: 4 passes and a gather)."""
    for t in range(block_of.shape[0]):
        for s in range(block_of.shape[1]):
            row = model[block_of[t, s]]
            bad = 0
            for i in range(row.size):
                w = weights[t, i]
                if w > 0:
                    r = (row[i] - observed[t, i]) * w
                    if np.isfinite(r):
                        out[t, s, i] = r
                    else:
                        out[t, s, i] = failed
                        bad += 1
                else:
                    out[t, s, i] = 0.0
            failures[t, s] = bad


@numba.njit(cache=True, nogil=True)
def _in_residual_order(sampled, relaxed, point, col, out):  # pragma: no cover (compiled)
    """out[u, i] = sampled[point[u, i], col[u, i]] where col >= 0 (a sample of a curve), else relaxed[point[u, i]]
    (a relaxed slip): the model value of each residual of each block, one pass."""
    for u in range(point.shape[0]):
        for i in range(point.shape[1]):
            c = col[u, i]
            out[u, i] = sampled[point[u, i], c] if c >= 0 else relaxed[point[u, i]]


def distinct_rows(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(index of the first of each distinct row of the 2-D float array ``a``, the number of each row's distinct row):
    rows compared by their bytes, one memcmp-sorted key a row (np.unique(axis=0) compares a row field by field, ~50x
    slower on rows of 200 times). Rows equal in value but not in bits (0.0 and -0.0) stay apart: they are solved
    twice, with the same numbers."""
    rows = np.ascontiguousarray(a).reshape(a.shape[0], -1)
    if rows.shape[1] == 0:  # no columns: every row is the same
        return np.zeros(min(1, rows.shape[0]), np.intp), np.zeros(rows.shape[0], np.intp)
    keys = rows.view(np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))).reshape(-1)
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return first, inverse.reshape(-1)


@dataclass
class Misfits:
    """:meth:`ProblemStack.misfits`: the misfit over the solved residuals ``rss`` (T, S), stability and the number of
    residuals not solved (T, S); where the stack has an offset parameter (index j), ``cross`` = sum r g and ``norm``
    = sum g^2 (T, S) over the solved residuals r, g their derivative along it: the misfit at theta_j + c is then
    rss + 2 c cross + c^2 norm exactly (None without)."""

    rss: np.ndarray
    stable: np.ndarray
    failures: np.ndarray
    cross: np.ndarray | None = None
    norm: np.ndarray | None = None


class ProblemStack:
    """The problems of a fit (one shared :class:`sweep.fit.space.ParamSpace`) and their engine settings.

    ``rounds`` counts the engine rounds (a round is one engine call per length of the rows of times);
    ``on_round`` (if given) is called after each with (round number, distinct points solved). ``estimates``: the
    engine estimates each model value's error (:meth:`engine_errors`); without, the forward solves cost ~0.6x
    (sweep.fit.forward), each one run at the ladder's first control tolerance (the optimisations' rounds: the best
    fits are checked by a stack with estimates, sweep.fit.core).
    """

    offset: int | None = None
    """Index (in the space's names) of a free parameter that every weighted residual depends on linearly, along a
    direction that depends on no parameter (:meth:`offset_direction`): the global stage then solves its grid with
    that parameter at its start only and puts it at its best value per set (sweep.fit.globalstage). None: none
    (relaxation curves and relaxed slips)."""
    fd_step: np.ndarray | None = None
    """Per problem, the least squares' forward-difference step relative to each parameter's scale (None:
    sweep.fit.levenberg.FD_STEP for all; sweep.fit.event_fit sets a finer one for stick-slip problems)."""

    def __init__(self, problems: Sequence[Problem], rtol: float,
                 on_round: Callable[[int, int], None] | None = None, estimates: bool = True):
        self.problems = list(problems)
        self.space = self.problems[0].space
        self.rtol, self.on_round, self.rounds, self.estimates = rtol, on_round, 0, estimates
        sp = self.space
        self.V0, self.g = sp.V0, sp.g
        self.rows = np.array([pr.rows for pr in self.problems])
        self.row_start = np.concatenate(([0], np.cumsum(self.rows)[:-1]))
        self.n_res = np.array([pr.n_residuals for pr in self.problems])
        n_max, n_t = int(self.n_res.max()), max(pr.n_t for pr in self.problems)
        Q = len(self.problems)
        km, v, times, lengths = [], [], [], []
        res_row, res_col = np.zeros((Q, n_max), np.intp), np.full((Q, n_max), -1, np.intp)
        self.observed = np.zeros((Q, n_max))
        self.weights = np.zeros((Q, n_max))  # 0 on the padding beyond a problem's n_residuals
        for q, pr in enumerate(self.problems):
            k, vv = pr.stiffness_velocity()
            km.append(k)
            v.append(vv)
            t, length, rows_q, cols_q = pr.layout(n_t)
            times.append(t)
            lengths.append(length)
            res_row[q, :pr.n_residuals], res_col[q, :pr.n_residuals] = rows_q, cols_q
            self.observed[q, :pr.n_residuals], self.weights[q, :pr.n_residuals] = pr.observed, pr.weights
        self.row_km, self.row_v = np.concatenate(km), np.concatenate(v)
        lengths = np.concatenate(lengths)
        rows_t = np.column_stack((np.concatenate(times), lengths))
        first, self.row_tid = distinct_rows(rows_t)
        self.templates, self.template_length = rows_t[first, :-1], lengths[first]
        self.res_row, self.res_col = res_row, res_col
        self.n_max = n_max
        # problems with the same rows (K/M, V, times) and residual order share a layout, hence their model values
        layout_keys = [np.concatenate((k, vv, self.row_tid[s0:s0 + nr], res_row[q], res_col[q])).astype(float)
                       for q, (k, vv, s0, nr) in enumerate(zip(km, v, self.row_start, self.rows))]
        width = max(len(k) for k in layout_keys)
        padded = np.array([np.concatenate((k, np.full(width - len(k), np.nan), [len(k)])) for k in layout_keys])
        self.representative, self.layout = distinct_rows(padded)

    def with_settings(self, rtol: float, estimates: bool) -> ProblemStack:
        """The same problems and index tables (shared, read only) at another engine ``rtol`` and ``estimates``,
        rounds counted from 0: the fit's stages differ only in these."""
        other = copy.copy(self)
        other.rtol, other.estimates, other.rounds = rtol, estimates, 0
        return other

    def residuals(self, problem: np.ndarray, sets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Weighted residuals (T, S, n_max) [noise units] of the parameter sets ``sets`` (T, S, p) of tasks of the
        problems ``problem`` (T,), MODEL_FAILED where the model gave no number and 0 beyond a problem's residuals;
        per set whether sliding was stable before every stop (T, S) (eq. 3); and per set the number of residuals
        the model gave no number for (T, S): a failed forward solve, which no misfit may outweigh (the callers
        rank by it first)."""
        problem = np.asarray(problem, dtype=np.intp)
        model, stable, block_of = self._blocks(problem, sets)
        T, S = sets.shape[:2]
        r = np.empty((T, S, self.n_max))
        failures = np.empty((T, S), np.intp)
        _residual_rows(model, block_of.reshape(T, S), self.observed[problem], self.weights[problem], MODEL_FAILED, r,
                       failures)
        return r, stable[block_of].reshape(T, S), failures

    def misfits(self, problem: np.ndarray, sets: np.ndarray) -> Misfits:
        """Sums of squared weighted residuals over the residuals the model solved (T, S), stability (T, S) and the
        number of residuals it did not solve (T, S), for ``sets`` (T, S, p), or (S, p) the same for every task (the
        global grid: its blocks are then the layouts times the sets, without sorting T S keys), summed in order, not
        pairwise (the global stage's misfits only rank its grid), without holding the residuals (100 curves x 730
        sets x 200 samples would be a 117 MB temporary). Where the stack has an :attr:`offset` parameter, also the
        sums that give each set's misfit at any value of it (:class:`Misfits`)."""
        problem = np.asarray(problem, dtype=np.intp)
        T, S = problem.size, sets.shape[-2]
        if sets.ndim == 2:  # one row of sets for every task (the global grid): blocks per layout, no key sort
            layouts, which = np.unique(self.layout[problem], return_inverse=True)
            model, stable = self._model(np.repeat(layouts, S), self._params(np.tile(sets, (layouts.size, 1))))
            block_of = (which.reshape(-1)[:, None] * S + np.arange(S)).reshape(-1)
        else:
            model, stable, block_of = self._blocks(problem, sets)
        rss, failures = np.empty((T, S)), np.empty((T, S), np.intp)
        along = self.offset is not None
        direction = self.offset_direction()[problem] if along else np.zeros((T, 0))
        cross, norm = (np.empty((T, S)), np.empty((T, S))) if along else (None, None)
        _misfit_sums(model, block_of.reshape(T, S), self.observed[problem], self.weights[problem], direction,
                     self.n_res[problem], rss, failures, cross if along else rss, norm if along else rss)
        return Misfits(rss, stable[block_of].reshape(T, S), failures, cross, norm)

    def offset_direction(self) -> np.ndarray:
        """(Q, n_max): the derivative of each problem's weighted residuals along the :attr:`offset` parameter (0 on
        the padding); a stack with an offset parameter defines it."""
        raise NotImplementedError

    def engine_errors(self, problem: np.ndarray, theta: np.ndarray, used: np.ndarray | None = None) -> np.ndarray:
        """Per task (``problem`` (T,), parameter set ``theta`` (T, p)): the largest error estimate of the engine's
        model values over the task's residuals, in units of each residual's noise (NaN where the engine gave no
        estimate: a failed point); the stack must have ``estimates``. ``used`` (T, n_max): the weighted residuals
        the caller computed at ``theta`` without estimates (the ladder's first run, which may differ from the
        estimated values where the ladder ran a point again): then the bound is |used - these| + their estimate,
        which bounds the error of the values used."""
        problem = np.asarray(problem, dtype=np.intp)
        params = self._params(np.asarray(theta, dtype=float).reshape(problem.size, -1))
        model, _, err = self._model(self.layout[problem], params, errors=True)
        w = self.weights[problem]
        with np.errstate(invalid="ignore"):
            scaled = np.abs(err) * w
            if used is not None:
                scaled += np.abs(used - (model - self.observed[problem]) * w)
        scaled[w == 0] = 0.0  # padding beyond a problem's residuals
        return np.max(scaled, axis=1, initial=0.0) if scaled.shape[1] else np.zeros(problem.size)

    def _blocks(self, problem: np.ndarray, sets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(model values of the distinct (layout, set) blocks (U, n_max), their stability (U,), the block of each set
        (T S,)): a parameter set's model values depend on its problem's layout only, so the global stage's grid is
        modelled once for every problem of a layout."""
        T, S, p = sets.shape
        params = self._params(sets.reshape(T * S, p))
        first, block_of = distinct_rows(np.column_stack((np.repeat(self.layout[problem], S).astype(float), params)))
        model, stable = self._model(self.layout[np.repeat(problem, S)[first]], params[first])
        return model, stable, block_of

    def _params(self, sets: np.ndarray) -> np.ndarray:
        """(A, m1, m2, D0, K/M factor) of each parameter set (rows of ``sets``)."""
        full = self.space.full(sets)
        return np.column_stack([full[k] for k in ("A", "m1", "m2", "D0", "K_over_M_factor")])

    def _model(self, layout: np.ndarray, params: np.ndarray, errors: bool = False):
        """Model values (U, n_max) [m] in residual order, and stability before every stop (U,), of U blocks: each a
        layout and a parameter set (A, m1, m2, D0, K/M factor); with ``errors`` also their error estimates (U, n_max)
        [m] (a stack with ``estimates`` only)."""
        if errors and not self.estimates:
            raise ValueError("error estimates need a ProblemStack with estimates=True")
        U = layout.size
        q = self.representative[layout]
        rows = self.rows[q]
        block_start = np.concatenate(([0], np.cumsum(rows)[:-1]))
        block = np.repeat(np.arange(U), rows)
        row = self.row_start[q][block] + np.arange(block.size) - block_start[block]
        pb = params[block]
        keys = np.column_stack((pb[:, :4], self.row_km[row] * pb[:, 4], self.row_v[row], self.row_tid[row]))
        first, inverse = distinct_rows(keys)
        x, dx, stable, x_err, dx_err = self._solve(keys[first])
        d = inverse[block_start[:, None] + self.res_row[q]]  # (U, n_max) distinct point of each residual
        col = self.res_col[q]

        def in_residual_order(sampled, relaxed):
            out = np.empty(d.shape)
            _in_residual_order(sampled, relaxed, d, col, out)
            return out

        ok = np.logical_and.reduceat(stable[inverse], block_start) if block.size else np.ones(U, bool)
        if errors:
            return in_residual_order(x, dx), ok, in_residual_order(x_err, dx_err)
        return in_residual_order(x, dx), ok

    def _solve(self, keys: np.ndarray) -> tuple[np.ndarray, ...]:
        """Slip at the template times, relaxed slip, stability and the two error estimates (None without
        ``estimates``) of the distinct points ``keys`` (A, m1, m2, D0, K/M, V, time row), one engine call per length
        of the rows of times (0: relaxed slip only): a point's numbers
        depend on its own times only (the sampled lanes' switch to the closed-form continuation counts the samples
        left: a row padded with its last time gave other numbers)."""
        n = keys.shape[0]
        x, dx, stable = np.full((n, self.templates.shape[1]), np.nan), np.full(n, np.nan), np.zeros(n, bool)
        x_err, dx_err = (np.full_like(x, np.nan), np.full_like(dx, np.nan)) if self.estimates else (None, None)
        tid = keys[:, 6].astype(np.intp)
        length = self.template_length[tid]
        for L in np.unique(length):
            pick = np.flatnonzero(length == L)
            res = forward(ForwardPoints(*keys[pick, :6].T, t=self.templates[tid[pick], :L]), rtol=self.rtol,
                          V0=self.V0, g=self.g, estimates=self.estimates)
            x[pick, :L], dx[pick], stable[pick] = res.x, res.dx_inf, res.stable
            if self.estimates:
                x_err[pick, :L], dx_err[pick] = res.x_err, res.dx_inf_err
        self.rounds += 1
        if self.on_round is not None:
            self.on_round(self.rounds, n)
        return x, dx, stable, x_err, dx_err
