"""Record fits' 95 % intervals against the linearised (Fisher) ones and their coverage, and the global stage's
offset parameter (mu0): noise draws about the independent scipy reference (tests/reference_records.py, Radau rtol
1e-10), the Fisher half-widths 1.96 sigma sqrt(diag (J^T J)^-1) from the reference's own Jacobian (central
differences, relative step 1e-4: steps 1e-2..1e-5 agree to 3e-5 of the widths on this record).

Coverage of N draws is binomial: sd sqrt(0.95 x 0.05 / N) = 0.022 for N = 100, so 0.85 is 4.6 sd below the nominal
rate."""

from __future__ import annotations

import numpy as np
import pytest
from reference_records import record_reference

import sweep
from sweep.fit.records import Record

TRUE = {"a": 0.01, "b": 0.015, "Dc": 1e-5, "mu0": 0.6}
K, NOISE, V, DUR = 2e3, 2e-4, [1e-6, 1e-5], [20.0, 40.0]
START = sweep.FrictionParams.from_lab(0.008, 0.012, 2e-5, 0.6)
N_DRAWS = 100


@pytest.fixture(scope="module")
def step():
    """A 600-sample velocity step (1 -> 10 um/s) at irregular times, its displacement and the Fisher half-widths."""
    rng = np.random.default_rng(31)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 599))))
    mu, disp = record_reference(*TRUE.values(), K, V, DUR, t)
    theta = np.array(list(TRUE.values()))
    jac = np.empty((t.size, theta.size))
    for j in range(theta.size):
        h = 1e-4 * abs(theta[j])
        up, down = theta.copy(), theta.copy()
        up[j], down[j] = theta[j] + h, theta[j] - h
        jac[:, j] = (record_reference(*up, K, V, DUR, t)[0] - record_reference(*down, K, V, DUR, t)[0]) / (2 * h)
    fisher = 1.96 * NOISE * np.sqrt(np.diag(np.linalg.inv(jac.T @ jac)))
    return t, mu, disp, dict(zip(TRUE, fisher))


@pytest.fixture(scope="module")
def draws(step):
    """N_DRAWS noise draws of the step, each its own sample, fitted in one call (a, b, Dc, mu0 free, noise
    estimated)."""
    t, mu, disp, _ = step
    rng = np.random.default_rng(32)
    recs = [Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=K, name=f"d{i}")
            for i in range(N_DRAWS)]
    return sweep.fit(recs, free=tuple(TRUE), params=START, per_data_set=True)


def test_profile_widths_match_fisher(step, draws):
    """The mean 95 % half-width over the draws lies within 10 % of the Fisher half-width, per parameter (the issue
    asks for 2x; a noise estimate's scatter, sqrt(2/n) ~ 6 % a draw, averages out)."""
    fisher = step[3]
    for n in TRUE:
        half = float(np.mean((draws[f"{n}_upper"] - draws[f"{n}_lower"]).values) / 2)
        assert half / fisher[n] == pytest.approx(1.0, abs=0.1), (n, half, fisher[n])


def test_coverage_per_parameter(draws):
    """Every fit ok; each parameter's 95 % interval covers the truth in [0.85, 1] of the draws."""
    assert (draws["fit_status"].values == 0).all()
    for n, v in TRUE.items():
        rate = float(np.mean((draws[f"{n}_lower"].values <= v) & (v <= draws[f"{n}_upper"].values)))
        assert 0.85 <= rate <= 1.0, (n, rate)


def test_offset_landscape_equals_the_gridded_one(step):
    """mu0 projected out of the global stage: the misfit landscape over the full 4-D grid filled from the sums at
    the start's mu0 equals the one with mu0 gridded and every set solved (to 1e-9 relative), on a plain and on a
    detrended record, and the best set's misfit is no higher than the gridded stage's. A few sets
    are NaN in one and not the other (24 of 1296 here): friction_at's error check is relative to |mu| + A, and mu0
    moves |mu|."""
    from sweep.fit.globalstage import search_all
    from sweep.fit.problem import make_problems
    from sweep.fit.record_forward import RecordStack, make_record_space

    t, mu, disp, _ = step
    rng = np.random.default_rng(33)
    for detrend in (None, "time"):
        rec = Record(t, mu + NOISE * rng.standard_normal(t.size) + 1e-5 * t, displacement=disp, k=K,
                     detrend=detrend)
        space = make_record_space(tuple(TRUE), START, K)
        stack = RecordStack(make_problems([rec], space, False), 1e-4, estimates=False)
        assert stack.offset == 3
        projected = search_all(stack)[0]
        stack.offset = None
        gridded = search_all(stack)[0]
        p, g = projected.landscape, gridded.landscape
        both = np.isfinite(p) & np.isfinite(g)
        assert np.sum(np.isfinite(p) != np.isfinite(g)) <= 0.03 * g.size and both.sum() > 0.7 * g.size
        np.testing.assert_allclose(p[both], g[both], rtol=1e-9)
        assert projected.rss <= gridded.rss


def test_a_start_far_off_reaches_the_truth(step):
    """From a start 3x off in a, b and Dc and 0.1 off in mu0, bounds two decades wide: the global stage finds the
    basin, the truth inside every 95 % interval."""
    t, mu, disp, _ = step
    rng = np.random.default_rng(34)
    rec = Record(t, mu + NOISE * rng.standard_normal(t.size), displacement=disp, k=K)
    far = {"a": 0.003, "b": 0.045, "Dc": 3e-5, "mu0": 0.5}
    bounds = {"a": (1e-3, 0.1), "b": (-0.05, 0.1), "Dc": (1e-6, 1e-4), "mu0": (0.3, 0.9)}
    ds = sweep.fit(rec, free=tuple(TRUE), params=START, start=far, bounds=bounds)
    assert int(ds["fit_status"][0]) == 0
    for n, v in TRUE.items():
        assert float(ds[f"{n}_lower"][0]) <= v <= float(ds[f"{n}_upper"][0]), (n, float(ds[n][0]))


@pytest.mark.parametrize("alone", [64, 0])
def test_a_round_in_one_call_gives_friction_at_per_record(alone, monkeypatch):
    """A round's records in one compiled call per number of segments (RecordStack, sample_friction_rows) give
    friction_at's numbers per record, bit for bit: records of their own times with 2 and 3 segments, two records
    sharing parameters (one problem), a detrended record (its model minus friction_at's is a line in its times), a
    record with its machine's g whose slide has gamma/A > INERTIA_LIMIT and a soft spring's stick-slip record (both
    with inertia, friction_at alone), with and without estimates; and each record by itself (its sets above ALONE:
    a global stage's grid)."""
    from sweep.accuracy import TIGHTER
    from sweep.fit import record_forward
    from sweep.fit.problem import make_problems
    from sweep.fit.record_forward import RecordStack, make_record_space
    from sweep.fit.segments import load_history
    from sweep.protocols.history.forward import friction_at

    monkeypatch.setattr(record_forward, "ALONE", alone)
    rng = np.random.default_rng(5)

    def times(n, end):
        return np.sort(np.concatenate(([0.0], rng.uniform(0.0, end, n - 1))))

    t2, t3, t4 = times(300, 60.0), times(250, 60.0), times(200, 60.0)
    steps3 = ((0.0, 1e-6), (20.0, 1e-5), (40.0, 1e-6))
    recs = [Record(t2, np.full(t2.size, 0.6), steps=((0.0, 1e-6), (20.0, 1e-5)), k=K, name="two", sample="s0"),
            Record(t3, np.full(t3.size, 0.6), steps=steps3, k=K, name="three", sample="s0"),
            Record(t4, 0.6 + 1e-4 * t4, steps=steps3, k=K, name="trend", detrend="time", sample="s1"),
            Record(t3, np.full(t3.size, 0.6), steps=((0.0, 1e-5), (20.0, 1e-3)), k=K, g=1.0, name="fast",
                   sample="s2"),
            Record(t2, np.full(t2.size, 0.6), steps=((0.0, 1e-6), (20.0, 1e-5)), k=100.0, name="soft", sample="s3")]
    space = make_record_space(("a", "b", "Dc", "mu0"), START, K)
    problems = make_problems(recs, space, per_data_set=False)
    sets = np.array([[0.01, 0.015, 1e-5, 0.6], [0.011, 0.014, 2e-5, 0.61]])
    for estimates in (False, True):
        stack = RecordStack(problems, 1e-6, estimates=estimates)
        layout = np.repeat(stack.layout, sets.shape[0])
        params = stack._params(np.tile(sets, (len(problems), 1)))
        got = stack._model(layout, params, errors=estimates)
        rtol = 1e-6 if estimates else 1e-6 * TIGHTER  # (the rounds' rtol, as the stack computes it)
        for q, pr in enumerate(problems):
            col = 0
            for d in pr.data:
                a, b, dc, mu0 = params[2 * q:2 * q + 2, :4].T  # (the space's sets as the stack sees them)
                g = d.g or START.g
                lab = {"A": a, "m1": b - a, "m2": np.zeros(2), "D0": dc, "m0": mu0, "V0": np.full(2, START.V0),
                       "K_over_M": d.k * g * np.ones(2), "g": np.full(2, g)}
                ref = friction_at(lab, load_history(d), d.t - d.t[0], rtol=rtol, estimates=estimates,
                                  inertia="auto" if d.g else "breakdown")
                rows = slice(2 * q, 2 * q + 2)
                mine = got[0][rows, col:col + d.t.size]
                if d.detrend:
                    line = mine - ref.mu
                    assert np.allclose(line, line[:, -1:] * (d.t - d.t[0]) / (d.t[-1] - d.t[0]), atol=1e-12)
                else:
                    assert np.array_equal(mine, ref.mu, equal_nan=True), d.name
                    if estimates:
                        assert np.array_equal(got[2][rows, col:col + d.t.size], ref.error, equal_nan=True)
                if d.name in ("fast", "soft"):
                    assert np.all(ref.model == 1), d.name  # the fallback was exercised
                col += d.t.size
