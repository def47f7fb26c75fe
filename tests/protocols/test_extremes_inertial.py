"""The stop scene with inertia at the extremes (issue 37): random friction parameters over wide (K/M, V) grids with
model="auto", against the scipy Radau reference of tests/reference_inertial.py.

Where chi gamma/A^2 is large the slider swings inertially to xi ~ sqrt(gamma/chi) and the swing ends in a plunge
(xi' falls by up to e^-(sqrt(chi gamma)/A) in a span of time below the resolution of doubles); the inertial stop
steps it in the plunge-resolving time sigma of sweep/integrate/models/stop_inertial.py, and the reference in its own
time theta (S as a state). Checked here:

* a random-extremes table (seeded; parameter ranges of the issue: A 3e-4..5e-2, m1/A -3..10, m2/A 0 or 1e-3..3,
  D0 1e-7..1e-5 m, K/M 1e2..1e9 s^-2, V 1e-8..1e-3 m/s, rtol 1e-6): step_underflow and max_steps on fewer than
  0.1 % of the points where steady sliding is stable, and no status but ok or error_above_tol anywhere;
* a sample of its inertial points, the plunge corner first (chi gamma/A^2 >= 1e2): xi_inf within rtol of the
  reference and the error estimate at least the true error;
* the reference's time map itself: where the S form runs too, both agree to 1e-11;
* the pure-inertia limit (docs/physics.md 3c): xi_inf -> sqrt(gamma/chi) as chi gamma/A^2 grows, the friction's
  share of the swing ~ A/sqrt(chi gamma) (measured: |xi_inf sqrt(chi/gamma) - 1| <= 0.31/sqrt(chi gamma/A^2) on the
  grid below, with mu1/A = 2).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from reference_inertial import reference_inertial_stop

import sweep
from sweep.scene.plausibility import PlausibilityWarning

Status = sweep.Status
G_EARTH = 9.81  # m s-2 (FrictionParams default)
RTOL = 1e-6
SEED = 37
U_REACH = 20.0
"""Largest ln psi the inertial reference is asked to integrate to before its hand-over (test below)."""


def random_params(rng: np.random.Generator) -> sweep.FrictionParams:
    """One random parameter set of the issue's ranges: A log-uniform 3e-4..5e-2; half the sets m2 = 0 with
    m1/A uniform 0.05..10 (a finite limit everywhere), the others m2/A log-uniform 1e-3..3 with m1/A uniform -3..10;
    D0 log-uniform 1e-7..1e-5 m."""
    A = math.exp(rng.uniform(math.log(3e-4), math.log(5e-2)))
    if rng.random() < 0.5:
        m1, m2 = A * rng.uniform(0.05, 10.0), 0.0
    else:
        m1, m2 = A * rng.uniform(-3.0, 10.0), A * math.exp(rng.uniform(math.log(1e-3), math.log(3.0)))
    D0 = math.exp(rng.uniform(math.log(1e-7), math.log(1e-5)))
    return sweep.FrictionParams(A=A, m1=m1, m2=m2, D0=D0)


def extremes_table(seed: int, n_sets: int, n_k: int, n_v: int) -> list[tuple[sweep.FrictionParams, object]]:
    """(params, dataset) per random set, each on an n_k x n_v grid K/M 1e2..1e9 s^-2 x V 1e-8..1e-3 m/s."""
    rng = np.random.default_rng(seed)
    K, V = np.logspace(2, 9, n_k), np.logspace(-8, -3, n_v)
    out = []
    for _ in range(n_sets):
        p = random_params(rng)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PlausibilityWarning)  # A, D0 at the edges of the measured ranges
            ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=p, K_over_M=K, V=V, rtol=RTOL), progress=False)
        out.append((p, ds))
    return out


def reduced(p: sweep.FrictionParams, ds) -> dict[str, np.ndarray]:
    """chi, mu1, gamma per grid point (docs/physics.md 2), from the dataset's own axes."""
    chi = ds["chi"].values[:, None] * np.ones((1, ds.sizes["V"]))
    mu1 = np.ones((ds.sizes["K_over_M"], 1)) * ds["mu1"].values[None, :]
    gamma = np.ones((ds.sizes["K_over_M"], 1)) * ds["gamma"].values[None, :]
    return {"chi": chi, "mu1": mu1, "gamma": gamma}


@pytest.fixture(scope="module")
def table():
    """6 random sets on 24 x 16 grids (2,304 points), seed SEED."""
    return extremes_table(SEED, 6, 24, 16)


@pytest.mark.slow
def test_random_extremes_leave_no_holes_where_steady_sliding_is_stable(table):
    """step_underflow + max_steps < 0.1 % of the stable points (chi > chi_c = mu1 (1 + gamma/A)); every point ok or
    error_above_tol (the statuses that carry a value or say why its estimate is too large)."""
    stable_n, holes, counts = 0, 0, {}
    for p, ds in table:
        r = reduced(p, ds)
        status = ds["status"].values
        stable = r["chi"] > r["mu1"] * (1.0 + r["gamma"] / p.A)
        stable_n += int(stable.sum())
        holes += int(np.isin(status[stable], (Status.STEP_UNDERFLOW, Status.MAX_STEPS)).sum())
        for s in np.unique(status):
            counts[Status(int(s)).name] = counts.get(Status(int(s)).name, 0) + int((status == s).sum())
    assert stable_n > 1000
    assert holes < 1e-3 * stable_n, counts
    assert set(counts) <= {"OK", "ERROR_ABOVE_TOL"}, counts
    assert counts.get("OK", 0) >= 0.99 * sum(counts.values()), counts
    assert sum(int((ds["model"].values == 1).sum()) for _, ds in table) > 200  # the inertial stop does work here


@pytest.mark.slow
def test_random_extremes_inertial_points_match_the_reference(table):
    """10 inertial ok points of the table, 6 of them in the plunge corner (chi gamma/A^2 >= 1e2, where the stop
    underflowed in s), drawn with a fixed seed: |xi_inf - ref| <= rtol |ref| and the estimate >= the true error.
    Points within the reference's reach only: its hand-over needs mu1 + 2 m2 u >= 0, i.e. u = ln psi >= U_REACH
    where mu1 < 0 (the engine's does not)."""
    rows = []
    for p, ds in table:
        r = reduced(p, ds)
        ok = (ds["status"].values == Status.OK) & (ds["model"].values == 1)
        for i, j in zip(*np.nonzero(ok)):
            if r["mu1"][i, j] < 0.0 and -r["mu1"][i, j] / (2.0 * p.m2) > U_REACH:
                continue  # beyond the reference's reach
            kG = r["chi"][i, j] * r["gamma"][i, j] / p.A**2
            rows.append((kG, p, r["chi"][i, j], r["mu1"][i, j], r["gamma"][i, j], float(ds["xi_inf"].values[i, j]),
                         float(ds["xi_inf_error"].values[i, j])))
    rng = np.random.default_rng(SEED)
    plunge = [row for row in rows if row[0] >= 1e2 and row[0] <= 1e8]
    other = [row for row in rows if row[0] < 1e2]
    assert len(plunge) >= 6 and len(other) >= 4
    sample = [plunge[i] for i in rng.choice(len(plunge), 6, replace=False)]
    sample += [other[i] for i in rng.choice(len(other), 4, replace=False)]
    bad = []
    for kG, p, chi, mu1, gamma, got, est in sample:
        ref = reference_inertial_stop(chi, p.A, mu1, p.m2, gamma, time_map=True if kG >= 1e2 else None).xi_inf
        true = abs(got - ref)
        if not (true <= RTOL * abs(ref) and est >= true):
            bad.append(f"chi/A={chi / p.A:.4g} mu1/A={mu1 / p.A:.4g} m2/A={p.m2 / p.A:.4g} gamma/A={gamma / p.A:.4g}: "
                       f"xi_inf={got!r} ref={ref!r} true/ref={true / ref:.3g} estimate={est:.3g}")
    assert not bad, "\n".join(bad)


@pytest.mark.slow
def test_reference_time_map_agrees_with_the_S_form_where_both_run():
    """The reference in theta (S a state) and in S: xi_inf within 1e-11 at chi/A = 2 and 10, gamma/A 1 and 0.1."""
    A = 0.01
    for k, a, b, G in ((2.0, 1.5, 0.0, 1.0), (10.0, 2.0, 0.5, 0.1)):
        in_s = reference_inertial_stop(k * A, A, a * A, b * A, G * A, time_map=False)
        in_theta = reference_inertial_stop(k * A, A, a * A, b * A, G * A, time_map=True)
        assert not in_s.time_map and in_theta.time_map
        assert in_theta.xi_inf == pytest.approx(in_s.xi_inf, rel=1e-11)


def test_plunge_corner_tends_to_the_pure_inertial_stop():
    """chi gamma/A^2 from 1e2 to 1e9 (gamma/A 1..1e3, chi/A 1e2..1e6, mu1/A = 2, m2 = 0), model="inertial":
    every point ok (the plunge at the end of the swing resolved), and xi_inf -> sqrt(gamma/chi), the pure-inertia
    slip of docs/physics.md 3c, with |xi_inf sqrt(chi/gamma) - 1| <= 0.4/sqrt(chi gamma/A^2) (measured: <= 0.31/...)."""
    p = sweep.FrictionParams(A=0.01, m1=0.02, m2=0.0, D0=1e-6)
    k = np.array([1e2, 1e4, 1e6])
    G = np.array([1.0, 1e3])
    K = k * p.A * G_EARTH / p.D0
    V = np.sqrt(G * p.A * G_EARTH * p.D0)
    ds = sweep.run_sweep(sweep.Scene(protocol="stop", params=p, K_over_M=K, V=V, rtol=RTOL, model="inertial"),
                         progress=False)
    assert np.all(ds["status"].values == Status.OK)
    ratio = ds["xi_inf"].values * np.sqrt(k[:, None] / G[None, :])
    bound = 0.4 / np.sqrt(k[:, None] * G[None, :])
    assert np.all(np.abs(ratio - 1.0) <= bound), (ratio - 1.0, bound)
