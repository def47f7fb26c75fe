"""Every point ends with a status that says why; never NaN with status ok, never an exception."""

import math

import numpy as np
import pytest

import sweep
from sweep.integrate.models.stop import StopParams
from sweep.integrate.solvers import RK4
from sweep.integrate.stop_point import REPLAY, Mesh, Method, Samples, Tolerances, march

P = sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=1e-6)


@pytest.mark.parametrize("changes, V", [
    ({"m2": -0.001}, 1e-6),              # m2 < 0: never converges (docs/physics.md 6)
    ({"m2": -0.001, "m1": -0.004}, 1e-6),
    ({"m2": 0.0, "m1": 0.0}, 1e-6),      # m2 = 0 needs m1 > 0
    ({"m2": 0.0, "m1": -0.003}, 1e-5),
])
def test_no_finite_limit_gets_a_status_not_a_number(changes, V):
    pt = sweep.solve_point(P.replace(**changes), K_over_M=1e4, V=V, observables=("xi_inf", "slip_at", "t50"),
                           t_obs=(0.0, 1.0, 100.0, 1e4))
    assert int(pt["status"]) == sweep.Status.NO_FINITE_LIMIT
    assert math.isnan(float(pt["xi_inf"])) and math.isnan(float(pt["t50"]))
    assert math.isnan(float(pt["slip_inf"])) and math.isnan(float(pt["stress_relaxation"]))
    slip = pt["slip_at"].values  # finite-time observables are still computed
    assert slip[0] == 0.0 and np.all(np.diff(slip) > 0) and np.all(np.isfinite(slip))


def test_no_finite_limit_costs_nothing_when_only_xi_inf_is_asked():
    pt = sweep.solve_point(P.replace(m2=-0.001), K_over_M=1e4, V=1e-6, observables=("xi_inf",))
    assert int(pt["status"]) == sweep.Status.NO_FINITE_LIMIT and int(pt["steps"]) == 0


def test_step_budget_exhausted_is_max_steps():
    pt = sweep.solve_point(P, K_over_M=1e3, V=1e-4, observables=("xi_inf",), max_steps=50)
    assert int(pt["status"]) == sweep.Status.MAX_STEPS and math.isnan(float(pt["xi_inf"]))


def test_blow_up_is_caught_before_overflow():
    """A deliberately bad step (h = 2 on a time map 50x too coarse, m2 < 0 so E grows like exp(|m2| u^2/A))
    drives the exponent of E past EXP_MAX; the kernel flags the point nonfinite instead of returning inf/NaN."""
    none = np.empty(0)
    run = march(Method.of(RK4), Mesh(REPLAY, 2.0, np.full(1, 2.0), 1, 1), StopParams(29.5, 1.2, -84.3, 16.7, False),
                Tolerances(1e-6, 0.0, 1e-6), 1000, Samples(none, none, none, none, none, none, False))
    status, xi_inf, n = run.status, run.xi_inf, run.steps
    assert status == sweep.Status.NONFINITE and math.isnan(xi_inf) and n < 1000


def test_mixed_grid_has_only_ok_or_flagged_points():
    params = P.replace(m2=-0.0005)
    scene = sweep.Scene(protocol="stop", params=params, K_over_M=np.logspace(2, 7, 6), V=np.logspace(-8, -3, 5))
    ds = sweep.run_sweep(scene)
    assert np.all(ds["status"] == sweep.Status.NO_FINITE_LIMIT)
    scene = sweep.Scene(protocol="stop", params=P, K_over_M=np.logspace(2, 7, 6), V=np.logspace(-8, -3, 5),
                        max_steps=200)
    ds = sweep.run_sweep(scene)
    ok = ds["status"].values == sweep.Status.OK
    assert ok.any() and (~ok).any()
    assert np.all(np.isfinite(ds["xi_inf"].values[ok]))
    assert np.all(ds["status"].values[~ok] == sweep.Status.MAX_STEPS)


@pytest.mark.parametrize("observables, flagged", [(("xi_inf", "trajectory", "slip_at"), True),
                                                  (("xi_inf", "slip_at"), False)])
def test_psi_is_judged_only_where_it_is_an_output(observables, flagged):
    """error_above_tol from u = ln psi only at the trajectory's times (the file's psi); at the slip_at times only the
    slip is an output, so a large u estimate there (a point solved one per thread) leaves the point ok."""
    from sweep.protocols.stop.engine import RawResult, mark_error_above_tol

    scene = sweep.Scene(protocol="stop", params=P, K_over_M=[1e5], V=[1e-6], observables=observables,
                        trajectory_tau=(1e-2, 1e2, 3), t_obs=(1.0, 10.0), rtol=1e-6)
    n_traj = scene.tau_samples.size
    out = RawResult.empty(1, n_traj + 2)
    out.xi_inf[:], out.xi_inf_err[:] = 1.0, 1e-9
    out.xi_at[:], out.xi_at_err[:], out.u_at[:] = 0.5, 1e-12, 0.1
    out.u_at_err[:] = 1e-9
    out.u_at_err[0, -1] = 1e-3  # far above rtol, at a slip_at time
    if n_traj:
        out.u_at_err[0, 0] = 1e-3  # and at a trajectory time
    mark_error_above_tol(scene, out)
    assert int(out.status[0]) == (int(sweep.Status.ERROR_ABOVE_TOL) if flagged else int(sweep.Status.OK))
