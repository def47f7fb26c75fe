"""A test matrix over the edges of the quasi-static stop model's parameter space (docs/physics.md 3a, 4, 6).

Edges: chi/A from 1e-5 to 1e4, m1/A (= mu1/A at m2 = 0) from 0.1 to 10, m2 of both signs (m2 < 0: no finite
limit), mu1(V) of both signs, points just above (and below) the quasi-static Hopf line chi = mu1, and grids mixing
easy and stiff points; every method (rk4, dp5, dop853) at rtol 1e-4, 1e-6, 1e-8.

The acceptance rule, for every point:

* status ok: xi_inf is finite, |xi_inf - ref| <= rtol |ref| + atol, and the error estimate bounds the true error,
  |xi_inf - ref| <= max(xi_inf_error, atol) (the contract of tests/integrate/test_error_estimates.py);
* any other status is an answer too (max_steps, step_underflow, nonfinite, no_finite_limit, error_above_tol):
  it says why there is no trusted value; the statuses met are recorded (pytest -s prints them);
* never NaN or inf with status ok, never an exception that stops the sweep, and no floating-point exception in
  the Python layer (numpy errstate raise on overflow, divide by zero and invalid operations).

References: the exact closed form for m2 = 0 (docs/physics.md 4, computed here independently of sweep.physics) covers
the whole chi/A x m1/A range cheaply; tests/reference.py (scipy) covers a smaller set with m2 > 0 and mu1 of both signs,
and is itself checked against the closed form over the whole range first. Property-based tests (hypothesis) over
random valid parameters: finite, consistent output; xi_inf decreasing in K/M at fixed V; results independent of how
the grid is split into chunks or subsets. pytest -s prints which statuses the matrix met.
"""

from __future__ import annotations

import functools
import math
from collections import Counter

import numpy as np
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st
from reference import reference_stop

import sweep
from sweep.plan.plan import make_plan
from sweep.protocols.stop.chunk import execute

G = 9.81  # m s-2 (FrictionParams default)
V0 = 1e-6  # m s-1 (FrictionParams default)
D0 = 1e-6  # m
ATOL = 1e-12  # = sweep.scene.scene.DEFAULT_ATOL["xi_inf"]
RTOLS = (1e-4, 1e-6, 1e-8)
METHODS = ("rk4", "dp5", "dop853")
Status = sweep.Status
NON_OK = {s for s in Status if s != Status.OK}
CLOSED_FORM_REL = 1e-14
"""Relative rounding error of the m2 = 0 closed form as evaluated here."""
REF_REL = 1e-12
"""Relative uncertainty allowed to tests/reference.py: within 5e-14 of the m2 = 0 closed form over chi/A 1e-5..1e4,
m1/A 0.1..10 (test_reference_is_right_at_the_extremes), and within 1.3e-12 of a forced Radau solution on the m2 > 0
matrix (Radau being the less accurate of the two at chi/A = 1e4)."""
FPE = {"over": "raise", "divide": "raise", "invalid": "raise"}
STATUS_LOG: Counter = Counter()
"""(test, status name) -> number of points, over the whole module (printed at the end with pytest -s)."""


# --- helpers ---------------------------------------------------------------------------------------------------

def xi_inf_closed_form(chi, A, m1):
    """Exact quasi-static relaxed slip for m2 = 0, m1 > 0 (docs/physics.md 4): A ln(chi/m1)/(chi - m1), A/m1 at
    chi = m1; written as (A/m1) ln(1 + x)/x, x = (chi - m1)/m1, accurate to a few ulps for every chi > 0."""
    x = (chi - m1) / m1
    if abs(x) < 1e-8:
        f = 1.0 - x / 2.0 + x * x / 3.0
    elif abs(x) < 0.5:
        f = math.log1p(x) / x
    else:
        f = math.log(chi / m1) / x
    return A / m1 * f


def K_over_M_for(chi_over_A, A, D0=D0):
    """K/M [s-2] giving reduced stiffness chi = chi_over_A * A (chi = (K/M) D0/g)."""
    return np.asarray(chi_over_A, dtype=float) * A * G / D0


def V_for(mu1_over_A, A, m1, m2):
    """V [m s-1] giving mu1(V) = m1 - 2 m2 ln(V/V0) = mu1_over_A * A (m2 != 0)."""
    return V0 * np.exp((m1 - np.asarray(mu1_over_A, dtype=float) * A) / (2.0 * m2))


def reduced_axes(scene):
    """(chi, mu1) per flat point in C order over (K_over_M, V), from the scene's physical axes (docs/physics.md 2)."""
    p = scene.params
    chi = scene.K_over_M * p.D0 / p.g
    mu1 = p.m1 - 2.0 * p.m2 * np.log(scene.V / p.V0)
    return np.repeat(chi, scene.V.size), np.tile(mu1, scene.K_over_M.size)


def has_finite_limit(mu1, m2):
    return m2 > 0.0 or (m2 == 0.0 and mu1 > 0.0)


def reference(chi, A, mu1, m2):
    """(xi_inf, relative uncertainty) of the reference for one point with a finite limit."""
    if m2 == 0.0:
        return xi_inf_closed_form(chi, A, mu1), CLOSED_FORM_REL
    return reference_stop(chi, A, mu1, m2).xi_inf, REF_REL


@functools.cache
def _run(params, K_over_M, V, rtol, method, max_steps):
    scene = sweep.Scene(protocol="stop", params=params, K_over_M=K_over_M, V=V, rtol=rtol, method=method,
                        model="quasistatic",
                        max_steps=max_steps)
    with np.errstate(**FPE):
        ds = sweep.run_sweep(scene, progress=False)
    return scene, ds


def run(params, K_over_M, V, rtol=1e-6, method="auto", max_steps=1_000_000):
    """Run a scene once (cached: the value and the error-estimate tests share the runs); returns (scene, ds)."""
    return _run(params, tuple(np.atleast_1d(K_over_M).tolist()), tuple(np.atleast_1d(V).tolist()), rtol, method,
                max_steps)


def points(scene, ds):
    """One dict per grid point: reduced parameters and the engine's answer."""
    chi, mu1 = reduced_axes(scene)
    p = scene.params
    status = ds["status"].values.ravel()
    xi, err = ds["xi_inf"].values.ravel(), ds["xi_inf_error"].values.ravel()
    steps = ds["steps"].values.ravel()
    return [dict(chi=float(chi[i]), mu1=float(mu1[i]), m2=p.m2, A=p.A, status=Status(int(status[i])),
                 xi=float(xi[i]), err=float(err[i]), steps=int(steps[i])) for i in range(chi.size)]


def describe(pt):
    return (f"chi/A={pt['chi'] / pt['A']:.6g} mu1/A={pt['mu1'] / pt['A']:.6g} m2/A={pt['m2'] / pt['A']:.6g} "
            f"A={pt['A']:g} status={pt['status'].name} xi_inf={pt['xi']!r} err_est={pt['err']:.3g} steps={pt['steps']}")


def check_contract(pts, rtol, tag, with_reference=True):
    """The per-point rules that need no reference (and, if ``with_reference``, the value within rtol).
    Returns the list of violations (strings) and records the statuses met under ``tag``."""
    bad = []
    for pt in pts:
        STATUS_LOG[(tag, pt["status"].name)] += 1
        s, xi, err = pt["status"], pt["xi"], pt["err"]
        finite = has_finite_limit(pt["mu1"], pt["m2"])
        if s not in set(Status):
            bad.append(f"unknown status: {describe(pt)}")
        if not finite and s != Status.NO_FINITE_LIMIT:
            bad.append(f"no finite limit but status {s.name}: {describe(pt)}")
        if s == Status.NO_FINITE_LIMIT and finite:
            bad.append(f"status no_finite_limit where the limit is finite: {describe(pt)}")
        if s == Status.NO_FINITE_LIMIT and not math.isnan(xi):
            bad.append(f"no_finite_limit with a number: {describe(pt)}")
        if math.isinf(xi) or math.isinf(err):
            bad.append(f"inf in the output: {describe(pt)}")
        if s != Status.OK:
            continue
        if not (math.isfinite(xi) and math.isfinite(err) and xi > 0.0 and err >= 0.0):
            bad.append(f"status ok with a non-finite or non-positive value: {describe(pt)}")
            continue
        if err > rtol * abs(xi) + ATOL:
            bad.append(f"status ok but the estimate exceeds the tolerance (should be error_above_tol): {describe(pt)}")
        if with_reference:
            ref, ref_rel = reference(pt["chi"], pt["A"], pt["mu1"], pt["m2"])
            true = abs(xi - ref)
            if true > rtol * abs(ref) + ATOL + ref_rel * abs(ref):
                bad.append(f"status ok but |xi_inf - ref| = {true / abs(ref):.3g} |ref| > rtol = {rtol:g}: "
                           f"ref={ref!r} {describe(pt)}")
    return bad


def check_estimates(pts):
    """Status ok: the error estimate bounds the true error (or both sit below the atol floor)."""
    bad = []
    for pt in pts:
        if pt["status"] != Status.OK:
            continue
        ref, ref_rel = reference(pt["chi"], pt["A"], pt["mu1"], pt["m2"])
        true = abs(pt["xi"] - ref)
        if true > max(pt["err"], ATOL) + ref_rel * abs(ref):
            bad.append(f"estimate {pt['err']:.3g} < true error {true:.3g} (ratio {pt['err'] / true:.3g}, true/|ref| = "
                       f"{true / abs(ref):.3g}): ref={ref!r} {describe(pt)}")
    return bad


def assert_no_violations(bad, what):
    bad = list(dict.fromkeys(bad))  # identical V columns (m2 = 0) repeat the same message
    assert not bad, f"{len(bad)} violation(s) in {what}:\n  " + "\n  ".join(bad)


def assert_not_vacuous(pts, min_ok_fraction=0.5):
    """Guard against a matrix that passes because nothing came back ok."""
    n_ok = sum(pt["status"] == Status.OK for pt in pts)
    counts = Counter(pt["status"].name for pt in pts)
    assert n_ok >= min_ok_fraction * len(pts), f"only {n_ok} of {len(pts)} points ok: {dict(counts)}"


@pytest.fixture(scope="module", autouse=True)
def print_statuses(request):
    """Not a check: after the module, with pytest -s, prints which statuses the matrix met, so that a reader sees
    why points were not ok."""
    yield
    if request.config.getoption("capture") != "no":
        return
    by_test: dict[str, Counter] = {}
    for (tag, name), n in sorted(STATUS_LOG.items()):
        by_test.setdefault(tag, Counter())[name] += n
    for tag, counts in by_test.items():
        if set(counts) != {"OK"}:
            print(f"\n  statuses [{tag}]: {dict(counts)}", end="")


# --- m2 = 0: the closed form over the whole chi/A x m1/A range -------------------------------------------------

A0 = 0.01
M1_OVER_A = (0.1, 0.3, 1.0, 3.0, 10.0)
CHI_OVER_A = tuple(np.logspace(-5, 4, 19).tolist())  # half decades
HOPF_EPS = (-1e-3, -1e-7, 1e-9, 1e-7, 1e-4, 1e-2)
"""chi = mu1 (1 + eps): just below (stick-slip side) and just above (stable side) the quasi-static Hopf line."""


@pytest.mark.parametrize("chi_over_A", (1e-5, 1e-3, 1.0, 1e4))
def test_reference_is_right_at_the_extremes(chi_over_A):
    """tests/reference.py (its automatic method choice) against the m2 = 0 closed form over chi/A 1e-5..1e4 and
    m1/A 0.1..10. Deep on the stick-slip side (chi << mu1) xi_inf depends on u = ln psi to ~1e-19 while the slider
    leaves the unstable steady state; the reference's state (xi, ln(psi/(1 + tau))) lost that in rounding and was
    2.4e-7 off at chi/A = 1e-5, m1/A = 10 (it now carries u itself early on)."""
    for m1_over_A in M1_OVER_A:
        chi, m1 = chi_over_A * A0, m1_over_A * A0
        ref = reference_stop(chi, A0, m1, 0.0).xi_inf
        exact = xi_inf_closed_form(chi, A0, m1)
        assert abs(ref - exact) <= REF_REL * exact, (m1_over_A, ref, exact)


def m2zero_points(method, rtol):
    pts = []
    for mA in M1_OVER_A:
        chi_over_A = np.unique(np.concatenate([CHI_OVER_A, mA * (1.0 + np.array(HOPF_EPS))]))
        params = sweep.FrictionParams(A=A0, m1=mA * A0, m2=0.0, D0=D0)
        # V does not matter at m2 = 0 (mu1 = m1): three decades of V must give identical columns
        scene, ds = run(params, K_over_M_for(chi_over_A, A0), V0 * np.array([1e-3, 1.0, 1e3]), rtol, method)
        xi = ds["xi_inf"].values
        np.testing.assert_array_equal(xi, np.broadcast_to(xi[:, :1], xi.shape))
        pts += points(scene, ds)
    return pts


@pytest.mark.parametrize("rtol", (1e-2, 1e-10))
def test_m2zero_matrix_at_the_ends_of_the_rtol_range(rtol):
    pts = m2zero_points("auto", rtol)
    bad = check_contract(pts, rtol, f"m2zero auto {rtol:g}") + check_estimates(pts)
    assert_no_violations(bad, f"m2 = 0, auto, rtol {rtol:g}")
    assert_not_vacuous(pts)


# --- m2 > 0, mu1 of both signs: the scipy reference -----------------------------------------------------------

M2_OVER_A = (0.05, 0.5)
M2POS_CHI_OVER_A = (1e-5, 1e-3, 1e-1, 10.0, 1e4)
M2POS_MU1_OVER_A = (10.0, 1.0, -1.0, -3.0)  # decreasing mu1 = increasing V


def m2pos_points(method, rtol):
    pts = []
    for m2A in M2_OVER_A:
        params = sweep.FrictionParams(A=A0, m1=1.0 * A0, m2=m2A * A0, D0=D0)
        scene, ds = run(params, K_over_M_for(M2POS_CHI_OVER_A, A0), V_for(M2POS_MU1_OVER_A, A0, params.m1,
                                                                          params.m2), rtol, method)
        pts += points(scene, ds)
    return pts


MATRICES = {"m2zero": m2zero_points, "m2pos": m2pos_points}
"""The two matrices: m2 = 0 against the closed form, m2 > 0 (mu1 of both signs) against the scipy reference."""


@pytest.mark.slow
@pytest.mark.parametrize("rtol", RTOLS)
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("matrix", MATRICES)
def test_matrix_within_rtol_of_reference(matrix, method, rtol):
    pts = MATRICES[matrix](method, rtol)
    assert_no_violations(check_contract(pts, rtol, f"{matrix} {method} {rtol:g}"), f"{matrix}, {method}, rtol {rtol:g}")
    assert_not_vacuous(pts)


@pytest.mark.parametrize("rtol", RTOLS)
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("matrix", MATRICES)
def test_matrix_error_estimates_bound_the_error(matrix, method, rtol):
    """m2pos includes chi/A = 1e4, mu1/A = -3, m2/A = 0.5, where the rk4 pair (0.173, 0.086) is pre-asymptotic
    (errors -1.6e-12 and -5.3e-12: |fine - coarse| is 0.7x the fine error): the lanes' step ladder
    (sweep/integrate/ladder.py) sees the ratio of successive differences off the asymptotic one and goes on down."""
    pts = MATRICES[matrix](method, rtol)
    assert_no_violations(check_estimates(pts), f"{matrix} estimates, {method}, rtol {rtol:g}")


# --- just above (and below) the Hopf line, m2 > 0 ------------------------------------------------------------

@pytest.mark.parametrize("method", METHODS)
def test_hopf_line_neighbourhood_with_m2(method):
    """chi = mu1(V) (1 + eps) at three stiffnesses, V chosen per point (m2/A = 0.2): the growth rate of the
    linearised dynamics vanishes on the line, and the stop starts on a marginal fixed point."""
    A, m1, m2 = 0.007, 0.0125, 0.2 * 0.007
    params = sweep.FrictionParams(A=A, m1=m1, m2=m2, D0=0.7e-6)
    pts = []
    for chi_over_A in (0.1, 1.5, 30.0):
        mu1_over_A = chi_over_A / (1.0 + np.array(HOPF_EPS))
        V = np.sort(V_for(mu1_over_A, A, m1, m2))
        for rtol in RTOLS:
            scene, ds = run(params, K_over_M_for([chi_over_A], A, params.D0), V, rtol, method)
            new = points(scene, ds)
            assert_no_violations(check_contract(new, rtol, f"hopf {method}") + check_estimates(new),
                                 f"Hopf neighbourhood, {method}, chi/A = {chi_over_A:g}, rtol {rtol:g}")
            pts += new
    assert_not_vacuous(pts)


# --- no finite limit ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("method", ("auto",) + METHODS)
@pytest.mark.parametrize("m1_over_A, m2_over_A", [(3.0, -0.1), (-1.0, -0.1), (10.0, -1e-12), (0.1, -3.0),
                                                  (0.0, 0.0), (-0.5, 0.0), (-1e-9, 0.0)])
def test_no_finite_limit_is_a_status_with_nan(method, m1_over_A, m2_over_A):
    """m2 < 0 (however small), or m2 = 0 with mu1 <= 0: status no_finite_limit and NaN, over chi/A 1e-5..1e4 and
    six decades of V (mu1(V) of both signs when m2 < 0)."""
    params = sweep.FrictionParams(A=A0, m1=m1_over_A * A0, m2=m2_over_A * A0, D0=D0)
    scene, ds = run(params, K_over_M_for(np.logspace(-5, 4, 10), A0), V0 * np.logspace(-3, 3, 4), 1e-6, method)
    pts = points(scene, ds)
    assert_no_violations(check_contract(pts, 1e-6, f"nolimit {method}"), "no finite limit")
    assert all(pt["status"] == Status.NO_FINITE_LIMIT for pt in pts)
    for name in ("xi_inf", "slip_inf", "stress_relaxation"):
        assert np.all(np.isnan(ds[name].values)), name


# --- grids mixing easy and stiff points -----------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("method", ("auto",) + METHODS)
def test_mixed_grid_every_point(method):
    """One scene whose grid spans K/M over 8 decades (chi/A 3e-5..3e3) and mu1(V)/A from 6 to -4.7 (sample2's
    A, m1, m2, D0; the costly corner of small chi with mu1 < 0 sits in the same chunk as easy points): every point
    meets the contract, and each point's answer is the one it gets when run alone."""
    rtol = 1e-6
    params = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)
    K = np.logspace(1.5, 9.5, 9)
    V = np.array([1e-8, 1e-6, 3e-5, 1e-3])
    scene, ds = run(params, K, V, rtol, method, 300_000)
    pts = points(scene, ds)
    assert_no_violations(check_contract(pts, rtol, f"mixed {method}") + check_estimates(pts),
                         f"mixed grid, {method}")
    assert_not_vacuous(pts)
    plan = make_plan(scene)
    full = execute(scene, plan, progress=False)
    for i in range(plan.n_points):
        alone = execute(scene, plan, indices=np.array([i]), progress=False)
        for name in ("xi_inf", "xi_inf_err", "status", "steps"):
            assert getattr(alone, name).tobytes() == getattr(full, name)[i:i + 1].tobytes(), (name, describe(pts[i]))


@pytest.mark.parametrize("method", METHODS)
def test_mixed_grid_m2zero_against_closed_form(method):
    """60 stiffnesses over 9 decades in one scene (chi/A 1e-5..1e4), m1/A = 0.3 (slow tail): every point."""
    rtol = 1e-8
    params = sweep.FrictionParams(A=A0, m1=0.3 * A0, m2=0.0, D0=D0)
    scene, ds = run(params, K_over_M_for(np.logspace(-5, 4, 60), A0), [V0], rtol, method)
    pts = points(scene, ds)
    assert_no_violations(check_contract(pts, rtol, f"mixed m2zero {method}") + check_estimates(pts),
                         f"mixed m2 = 0 grid, {method}")
    assert_not_vacuous(pts)


# --- far outside the physical range: no exception, no overflow, an honest status -------------------------------

@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("A, mu1_over_A, m2_over_A", [
    (1e-8, 1e6, 0.0),        # huge weakening, tiny A: exponents (chi xi + mu1 u)/A of order 1e6
    (1e-8, -1e6, 1e-6),      # huge strengthening, tiny curvature: the exponent of E = xi' psi starts growing
    (0.01, -300.0, 1e-3),    # minimum of dmu at u = 1.5e5: a creep over astronomically many decades
    (10.0, 1e-6, 1e6),       # dmu dominated by m2 u^2
    (1e-3, 0.1, 1e-9),       # slow tail (tau^-0.1) cut off only far out
])
def test_absurd_parameters_give_a_status_not_an_exception(method, A, mu1_over_A, m2_over_A):
    params = sweep.FrictionParams(A=A, m1=mu1_over_A * A, m2=m2_over_A * A, D0=D0)
    chi_over_A = np.logspace(-12, 12, 7)
    scene, ds = run(params, K_over_M_for(chi_over_A, A), [V0], 1e-6, method, 20_000)
    pts = points(scene, ds)
    assert_no_violations(check_contract(pts, 1e-6, f"absurd {method}", with_reference=False), "absurd parameters")
    ok = [pt for pt in pts if pt["status"] == Status.OK]
    if m2_over_A == 0.0:  # the closed form still holds there
        assert_no_violations(check_contract(ok, 1e-6, "absurd-ref") + check_estimates(ok), "absurd, m2 = 0")


# --- property-based tests ----------------------------------------------------------------------------------------

PROPERTY = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
log_uniform = lambda lo, hi: st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)  # noqa: E731
signed = lambda lo, hi: st.tuples(st.sampled_from((-1.0, 1.0)), log_uniform(lo, hi)).map(  # noqa: E731
    lambda t: t[0] * t[1])
M2_OVER_A_ANY = st.one_of(st.just(0.0), log_uniform(1e-3, 1.0), log_uniform(1e-3, 1.0).map(lambda x: -x))


@st.composite
def scenes(draw, m2_over_A=M2_OVER_A_ANY, n_K=(1, 5), n_V=(1, 4)):
    """A random valid scene over the issue's ranges: chi/A 1e-5..1e4, |m1|/A 0.1..10, m2 of both signs (or 0),
    |ln(V/V0)| <= 4, with its method and rtol."""
    A = draw(log_uniform(1e-4, 0.1))
    m1 = draw(signed(0.1, 10.0)) * A
    m2 = draw(m2_over_A) * A
    chi_over_A = draw(st.lists(st.floats(-5.0, 4.0), min_size=n_K[0], max_size=n_K[1], unique=True))
    lnV = draw(st.lists(st.floats(-4.0, 4.0), min_size=n_V[0], max_size=n_V[1], unique=True))
    params = sweep.FrictionParams(A=A, m1=m1, m2=m2, D0=D0)
    K = np.unique(K_over_M_for(10.0 ** np.array(chi_over_A), A))
    V = np.unique(V0 * np.exp(np.array(lnV)))
    rtol = draw(log_uniform(1e-8, 1e-3))
    method = draw(st.sampled_from(("auto",) + METHODS))
    return sweep.Scene(protocol="stop", params=params, K_over_M=K, V=V, rtol=rtol, method=method, max_steps=50_000,
                       model="quasistatic")


@PROPERTY
@given(scene=scenes())
def test_random_scenes_give_finite_consistent_output(scene):
    note(scene.to_toml())
    with np.errstate(**FPE):
        ds = sweep.run_sweep(scene, progress=False)
    pts = points(scene, ds)
    bad = check_contract(pts, scene.rtol, "hypothesis finite", with_reference=False)
    p = scene.params
    if p.m2 == 0.0 and p.m1 > 0.0:  # the closed form is cheap: check the value too
        bad += check_contract(pts, scene.rtol, "hypothesis closed form")
    assert_no_violations(bad, "random scene")
    ok = ds["status"].values == Status.OK
    np.testing.assert_allclose(ds["slip_inf"].values[ok], p.D0 * ds["xi_inf"].values[ok], rtol=1e-15)
    assert np.all(np.isfinite(ds["stress_relaxation"].values[ok]))
    assert np.all(ds["steps"].values[ok] > 0)


@PROPERTY
@given(A=log_uniform(1e-4, 0.1), m1_over_A=signed(0.1, 10.0), m2_over_A=st.one_of(st.just(0.0),
       log_uniform(1e-3, 1.0)), lnV=st.floats(-4.0, 4.0), start=st.floats(-5.0, 3.0),
       steps=st.lists(st.floats(0.01, 1.5), min_size=2, max_size=6),
       method=st.sampled_from(("auto",) + METHODS), rtol=log_uniform(1e-8, 1e-3))
def test_xi_inf_decreases_with_K_over_M(A, m1_over_A, m2_over_A, lnV, start, steps, method, rtol):
    """docs/physics.md 4: at fixed V, xi_inf decreases with K/M (m2 >= 0 where finite). With s = int dtau/psi,
    dxi/ds = exp(-(chi xi + dmu(s - xi))/A) decreases with chi at xi > 0, so by comparison xi(s) does too.
    Stiffnesses at least 0.01 decade apart; tolerance: the two error estimates and atol."""
    params = sweep.FrictionParams(A=A, m1=m1_over_A * A, m2=m2_over_A * A, D0=D0)
    chi_over_A = 10.0 ** (start + np.cumsum([0.0] + steps))
    scene, ds = run(params, K_over_M_for(chi_over_A, A), [V0 * math.exp(lnV)], rtol, method, 50_000)
    pts = points(scene, ds)
    assert_no_violations(check_contract(pts, rtol, "hypothesis monotone", with_reference=False), "monotonicity scene")
    ok = [pt for pt in pts if pt["status"] == Status.OK]
    for lo, hi in zip(ok, ok[1:]):  # sorted by chi
        assert hi["xi"] < lo["xi"] + lo["err"] + hi["err"] + ATOL, \
            f"not decreasing:\n  {describe(lo)}\n  {describe(hi)}"


@PROPERTY
@given(scene=scenes(n_K=(1, 6), n_V=(1, 5)), time_resolved=st.booleans(), data=st.data())
def test_results_do_not_depend_on_chunking(scene, time_resolved, data):
    """Chunk sizes 1, 7 and 4096, and any subset of the points in any order, give bitwise the same per-point
    results (both batch paths: the relaxed-slip lanes, and one point per thread when t50 is asked for)."""
    if time_resolved:
        scene = sweep.Scene(protocol="stop", params=scene.params, K_over_M=scene.K_over_M, V=scene.V,
                            rtol=scene.rtol, method=scene.method, max_steps=scene.max_steps,
                            observables=("xi_inf", "t50"))
    note(scene.to_toml())
    plan = make_plan(scene)
    names = ("xi_inf", "xi_inf_err", "status", "steps", "tau_at_fraction", "tau_at_fraction_err")
    runs = [execute(scene, plan, progress=False, chunk_size=c) for c in (1, 7, 4096)]
    for other in runs[1:]:
        for name in names:
            assert getattr(other, name).tobytes() == getattr(runs[0], name).tobytes(), name
    subset = np.array(data.draw(st.permutations(range(plan.n_points)))[: data.draw(st.integers(1, plan.n_points))])
    part = execute(scene, plan, indices=subset, progress=False, chunk_size=data.draw(st.sampled_from((1, 3, 4096))))
    for name in names:
        assert getattr(part, name).tobytes() == getattr(runs[0], name)[subset].tobytes(), name
