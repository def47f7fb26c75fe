"""Samples at given times in the adaptive lanes (sweep/integrate/lanes_sampled.py) against the independent scipy
reference (tests/reference.py): every ok sample's true error is below its estimate, error_above_tol exactly where an
estimate exceeds its tolerance, the premise of the estimate (the fine twin at least twice as accurate at the samples
too), convergence with the control tolerance, the routing (which scenes use the sampled lanes, which keep the
per-point path), and the fit's forward model through them."""

import functools

import numpy as np
import pytest
from cases import STOP_CASES, case_params
from reference import reference_stop

import sweep
import sweep.protocols.stop.engine as engine
from sweep.integrate.lanes_sampled import sampled_lane_kernels
from sweep.plan.plan import make_plan
from sweep.status import Status

FINITE_CASES = [c for c in STOP_CASES if c.expect_finite]
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
ATOL = sweep.scene.scene.DEFAULT_ATOL["trajectory"]
REFERENCE_FLOOR = 1e-9
"""Relative accuracy trusted of the reference's interpolated trajectory (tests/integrate/test_error_estimates.py)."""
TAUS = np.logspace(-2, 6, 17)
"""Sample times: from inside the first steps to far past the transient (closed-form continuation)."""


@functools.cache
def reference(name):
    case = next(c for c in STOP_CASES if c.name == name)
    return reference_stop(case.chi, case.A, case.mu1, case.m2)


def case_scene(case, rtol, **kw):
    c = case_params(case)
    params = sweep.FrictionParams(A=c["A"], m1=c["m1"], m2=c["m2"], D0=c["D0"])
    kw = {"observables": ("xi_inf", "trajectory"), "trajectory_tau": (TAUS[0], TAUS[-1], TAUS.size), **kw}
    return sweep.Scene(protocol="stop", params=params, K_over_M=[c["K_over_M"]], V=[c["V"]], model="quasistatic",
                       rtol=rtol, **kw)


def check_bounded(value, estimate, exact, floor, what):
    true = abs(value - exact)
    assert true <= max(estimate, floor), f"{what}: estimate {estimate:.3g} below the true error {true:.3g}"


def slip_at_scene(case, rtol):
    """slip_at alone at the times of TAUS (t = tau D0/V): psi not wanted, tau out of the error norm."""
    c = case_params(case)
    return case_scene(case, rtol, observables=("xi_inf", "slip_at"), t_obs=tuple(TAUS * c["D0"] / c["V"]))


@pytest.mark.parametrize("kind", ["trajectory", "slip_at"])
@pytest.mark.parametrize("rtol", RTOLS)
def test_sample_estimates_bound_the_errors(rtol, kind):
    """xi (and psi, for the trajectory) at 17 times from 1e-2 to 1e6 on every finite case: each estimate bounds the
    true error (above what the reference resolves), and the point is ok exactly where every estimate is within its
    tolerance. slip_at alone has no estimate for psi (NaN: its runs do not control tau)."""
    for case in FINITE_CASES:
        scene = case_scene(case, rtol) if kind == "trajectory" else slip_at_scene(case, rtol)
        plan = make_plan(scene)
        assert engine.samples_in_lanes(scene, plan)
        out = engine.run_points(scene, plan, np.array([0]))
        ref = reference(case.name)
        st = int(out.status[0])
        assert st in (Status.OK, Status.ERROR_ABOVE_TOL), (case.name, st)
        xi, xi_err, u, u_err = out.xi_at[0], out.xi_at_err[0], out.u_at[0], out.u_at_err[0]
        exact_xi, exact_psi = ref.xi(TAUS), ref.psi(TAUS)
        for j in range(TAUS.size):
            check_bounded(xi[j], xi_err[j], exact_xi[j], max(ATOL, REFERENCE_FLOOR * exact_xi[j]),
                          f"{case.name} rtol {rtol:g} xi[{j}]")
            if kind == "trajectory":  # u = ln psi: its error is psi's relative error
                check_bounded(np.exp(u[j]), np.exp(u[j]) * u_err[j], exact_psi[j], REFERENCE_FLOOR * exact_psi[j],
                              f"{case.name} rtol {rtol:g} psi[{j}]")
        assert kind == "trajectory" or np.all(np.isnan(u_err)), case.name
        within = (np.all(xi_err <= rtol * np.abs(xi) + ATOL) and (kind == "slip_at" or np.all(u_err <= rtol))
                  and out.xi_inf_err[0] <= rtol * abs(out.xi_inf[0]) + sweep.scene.scene.DEFAULT_ATOL["xi_inf"])
        engine.mark_error_above_tol(scene, out)
        assert int(out.status[0]) == (Status.OK if within else Status.ERROR_ABOVE_TOL), case.name


def lane_run(case, tol, twin=True):
    """One run of the sampled lanes at control tolerance ``tol`` (no ladder), with or without its fine twin: the
    SampledOutputs."""
    scene = case_scene(case, 1e-6)
    plan = make_plan(scene)
    _, batch = sampled_lane_kernels(sweep.plan.plan.LANES_METHOD)
    out = engine.SampledOutputs.empty(1, TAUS.size)
    pts = engine.LanePoints(plan.k, plan.a, plan.b, plan.s_c, plan.G)
    batch(pts, engine.SampledRuns(np.array([0]), np.array([0]), np.array([tol]), np.array([0.1]),
                                  np.ascontiguousarray(TAUS[None, :]), ATOL, 1e-6, plan.max_steps, True, twin), 1, out)
    assert out.status[0] == Status.OK, case.name
    return out


def first_run(case, tol):
    """(xi, fine xi, u, fine u) at TAUS of :func:`lane_run`."""
    out = lane_run(case, tol)
    return out.xi_at[0], out.xi_fine[0], out.u_at[0], out.u_fine[0]


@pytest.mark.parametrize("tol", [1e-4, 1e-7])
def test_without_the_twin_the_run_is_the_same(tol):
    """The fit's iterations run the lanes without the fine twin (sweep.fit.stack): everything of the twin NaN (no
    estimate can be formed from it), and the run's samples and relaxed slip those it has beside its twin: to
    rounding (1e-10) where both took as many steps and switched to the closed form at the same sample (most cases;
    bit for bit unless the twin's exponent moved a rejection), else (the twin's exponent rejected a step, or its E
    delayed the switch) within 10 tol of them."""
    same = 0
    for case in FINITE_CASES:
        both, alone = lane_run(case, tol), lane_run(case, tol, twin=False)
        assert all(np.all(np.isnan(getattr(alone, name))) for name in ("xi_fine", "u_fine", "fine")), case.name
        if both.steps[0] == alone.steps[0] and both.first_continued[0] == alone.first_continued[0]:
            same += 1
            for name in ("xi_at", "u_at", "xi_inf"):
                np.testing.assert_allclose(getattr(alone, name), getattr(both, name), rtol=1e-10, atol=1e-300,
                                           err_msg=case.name)
        else:
            np.testing.assert_allclose(alone.xi_at, both.xi_at, rtol=10 * tol, atol=ATOL, err_msg=case.name)
            assert abs(alone.xi_inf[0] / both.xi_inf[0] - 1) <= 10 * tol, case.name
    assert same >= len(FINITE_CASES) / 2, same


def test_points_run_without_estimates_carry_none():
    """run_points(estimates=False): each point once (its steps those of a single run), status ok, every estimate
    NaN (never a number that is not one)."""
    for case in FINITE_CASES:
        scene = slip_at_scene(case, 1e-5)
        plan = make_plan(scene)
        out = engine.run_points(scene, plan, np.array([0]), estimates=False)
        assert int(out.status[0]) == Status.OK and out.work[0] == out.steps[0], case.name
        assert np.all(np.isnan(out.xi_at_err)) and np.isnan(out.xi_inf_err[0]), case.name
        assert np.all(np.isfinite(out.xi_at)) and np.isfinite(out.xi_inf[0]), case.name


def test_samples_converge_with_the_control_tolerance():
    """The largest relative error of the samples falls with the control tolerance: not at all from 1e-4 to 1e-6
    where the costly corner's errors stagnate (s2_KM1e3_V100um_corner: 1.6e-6, 3.7e-7; the reason for the twin,
    sweep/integrate/tolerance_ladder.py), at least 100x from 1e-4 to 1e-8 (measured: 120x to 1.6e5x), until the
    reference's floor."""
    for case in FINITE_CASES:
        exact = reference(case.name).xi(TAUS)
        e4, e6, e8 = (np.max(np.abs(first_run(case, tol)[0] - exact) / exact) for tol in (1e-4, 1e-6, 1e-8))
        assert e6 <= max(e4, REFERENCE_FLOOR) and e8 <= max(1e-2 * e4, REFERENCE_FLOOR), (case.name, e4, e6, e8)


def test_slip_at_of_the_forward_model_matches_the_reference():
    """The fit's forward model (per-point times, slip_at) through the sampled lanes: within the estimates of the
    reference at rtol 1e-8, every point ok."""
    from sweep.fit.forward import ForwardPoints, forward

    cases = [c for c in FINITE_CASES if c.preset is not None]
    c = [case_params(case) for case in cases]
    t = np.logspace(-1, 3.5, 200)
    pts = ForwardPoints(*(np.array([p[k] for p in c]) for k in ("A", "m1", "m2", "D0", "K_over_M", "V")),
                        t=np.tile(t, (len(c), 1)))
    res = forward(pts, rtol=1e-8)
    assert np.all(res.status == Status.OK)
    for i, case in enumerate(cases):
        exact = c[i]["D0"] * reference(case.name).xi(c[i]["V"] * t / c[i]["D0"])
        floor = np.maximum(ATOL * c[i]["D0"], REFERENCE_FLOOR * exact)
        assert np.all(np.abs(res.x[i] - exact) <= np.maximum(res.x_err[i], floor)), case.name
        assert np.all(res.x_err[i] <= 1e-8 * np.abs(res.x[i]) + ATOL * c[i]["D0"]), case.name


@pytest.mark.parametrize("kw, lanes", [({}, True),
                                       ({"observables": ("xi_inf", "slip_at"), "t_obs": (1.0, 10.0)}, True),
                                       ({"observables": ("xi_inf", "trajectory", "t50")}, False),
                                       ({"method": "dp5"}, False), ({"method": "rk4"}, False),
                                       ({"step": 0.01}, False)])
def test_which_scenes_sample_in_lanes(kw, lanes):
    """Method "auto" in float64 without t50/t90 samples in the lanes; t50/t90, named methods and a given step keep
    the per-point path."""
    scene = case_scene(FINITE_CASES[0], 1e-6, **kw)
    assert engine.samples_in_lanes(scene, make_plan(scene)) == lanes


def test_points_without_a_finite_limit_keep_the_per_point_path():
    """No finite relaxed slip (m2 < 0): the per-point path samples the trajectory, status no_finite_limit."""
    scene = sweep.Scene(protocol="stop", params=sweep.FrictionParams(A=0.01, m1=0.01, m2=-0.001, D0=1e-6),
                        K_over_M=[1e4], V=[1e-6], model="quasistatic", rtol=1e-6,
                        observables=("xi_inf", "trajectory"), trajectory_tau=(1e-2, 1e2, 5))
    out = engine.run_points(scene, make_plan(scene), np.array([0]))
    assert out.status[0] == Status.NO_FINITE_LIMIT and np.all(np.isfinite(out.xi_at))
