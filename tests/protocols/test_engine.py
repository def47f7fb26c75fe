"""The engine's two batch paths agree, and results do not depend on how the grid is chunked."""

import numpy as np

import sweep
from sweep.plan.plan import make_plan
from sweep.protocols.stop.chunk import execute

PARAMS = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)


def scene(**kw):
    base = dict(protocol="stop", params=PARAMS, K_over_M=np.logspace(2, 7, 23), V=np.logspace(-8, -3, 17), step=0.12,
                model="quasistatic")  # the two quasi-static paths are compared
    return sweep.Scene(**{**base, **kw})


def test_lanes_path_matches_the_per_point_path():
    """xi_inf-only sweeps run in vectorised lanes (integrate/lanes.py, fine run of the pair returned); asking for
    slip_at at t = 0 forces the per-point path (integrate/stop_point.py, coarse run returned with 2|coarse - fine|).
    The values agree within both error estimates, and each path's status follows its own estimate."""
    lanes = sweep.run_sweep(scene(max_steps=3000, method="rk4"))
    per_point = sweep.run_sweep(scene(max_steps=3000, method="rk4", observables=("xi_inf", "slip_at"), t_obs=(0.0,)))
    finished = np.isin(lanes["status"].values, [sweep.Status.OK, sweep.Status.ERROR_ABOVE_TOL]) & np.isin(
        per_point["status"].values, [sweep.Status.OK, sweep.Status.ERROR_ABOVE_TOL])
    assert finished.sum() > 0.5 * finished.size
    diff = np.abs(lanes["xi_inf"] - per_point["xi_inf"]).values[finished]
    assert np.all(diff <= (lanes["xi_inf_error"] + per_point["xi_inf_error"]).values[finished])
    for ds in (lanes, per_point):
        # scene() keeps the default rtol = 1e-6
        st, val, err = ds["status"].values, ds["xi_inf"].values, ds["xi_inf_error"].values
        over = err > 1e-6 * np.abs(val) + sweep.scene.scene.DEFAULT_ATOL["xi_inf"]
        assert np.all(st[finished & over] == sweep.Status.ERROR_ABOVE_TOL)
        assert np.all(st[finished & ~over] == sweep.Status.OK)
    statuses = set(np.unique(lanes["status"]).tolist())
    assert {sweep.Status.OK, sweep.Status.MAX_STEPS} <= statuses, statuses


def test_auto_runs_the_stiff_corner_with_rosenbrock_and_agrees_with_rk4():
    """method="auto" with fixed-step lanes (float32 here; float64 takes the adaptive lanes) sends the stiff points
    (sweep.plan.plan.stiff_points) to the ros4 lanes: same values as RK4 within both error estimates, far fewer steps
    there, and the plan says which points went where."""
    s = scene(step=None, rtol=1e-4, precision="float32")
    plan = make_plan(s)
    assert plan.point_methods == ("rk4", "ros4")
    stiff = plan.points_of("ros4")
    assert 0 < stiff.size < plan.n_points and "ros4 at" in plan.describe()["method"]
    auto, rk4 = execute(s, plan, progress=False), execute(
        s, make_plan(scene(step=None, rtol=1e-4, precision="float32", method="rk4")), progress=False)
    # float32 at rtol 1e-4: the rounding bound flags some points error_above_tol, with their values kept
    finished = [sweep.Status.OK, sweep.Status.ERROR_ABOVE_TOL]
    assert np.all(np.isin(auto.status, finished)) and np.all(np.isin(rk4.status, finished))
    assert np.all(np.abs(auto.xi_inf - rk4.xi_inf) <= auto.xi_inf_err + rk4.xi_inf_err)
    assert np.median(rk4.steps[stiff] / auto.steps[stiff]) > 5.0


def test_adaptive_lanes_agree_with_the_rk4_ladder():
    """Float64 "auto" runs the relaxed slip in the adaptive dop853 lanes (sweep/integrate/lanes_adaptive.py): the
    same values as the rk4 step ladder within both error estimates, every point ok at rtol 1e-8."""
    s = scene(step=None, rtol=1e-8)
    plan = make_plan(s)
    assert plan.point_methods == ("dop853",) and plan.lanes and plan.adaptive
    assert "tolerance_ladder" in plan.describe()["error_estimate"]
    auto, rk4 = execute(s, plan, progress=False), execute(s, make_plan(scene(step=None, rtol=1e-8, method="rk4")),
                                                         progress=False)
    assert np.all(auto.status == sweep.Status.OK) and np.all(rk4.status == sweep.Status.OK)
    assert np.all(np.abs(auto.xi_inf - rk4.xi_inf) <= auto.xi_inf_err + rk4.xi_inf_err)


def test_no_limit_points_in_lanes():
    ds = sweep.run_sweep(scene(params=PARAMS.replace(m2=-0.001), K_over_M=[1e3, 1e5], V=[1e-6, 1e-4]))
    assert np.all(ds["status"] == sweep.Status.NO_FINITE_LIMIT) and np.all(np.isnan(ds["xi_inf"]))


def test_results_do_not_depend_on_chunking():
    for s in (scene(), scene(step=None), scene(observables=("xi_inf", "t50"))):
        plan = make_plan(s)
        whole = execute(s, plan, progress=False)
        pieces = execute(s, plan, progress=False, chunk_size=37)
        for name in ("xi_inf", "status", "steps", "tau_at_fraction"):
            np.testing.assert_array_equal(getattr(whole, name), getattr(pieces, name), err_msg=name)
