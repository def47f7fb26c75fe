"""The stop scene with inertia and the per-point model choice, against the scipy Radau reference
(tests/reference_inertial.py) and the quasi-static reference (tests/reference.py)."""

from __future__ import annotations

import numpy as np
import pytest
from reference import reference_stop
from reference_inertial import reference_inertial_stop

import sweep
from sweep import physics
from sweep.errors import InputError
from sweep.status import MODEL_FLAG

G_OVER_A = np.array([1e-3, 1e-2, 0.1, 1.0, 10.0])
PARAM_SETS = {
    # (A, m1, m2, D0): velocity weakening with m2 = 0; sample2 (m2 > 0); sample2's strengthening side (mu1 < 0)
    "m2zero": sweep.FrictionParams(A=0.01, m1=0.015, m2=0.0, D0=1e-6),
    "sample2": sweep.presets["sample2"],
}


def velocities_for(params: sweep.FrictionParams, g_over_A: np.ndarray) -> np.ndarray:
    """V giving gamma/A = g_over_A (gamma = V^2/(g D0))."""
    return np.sqrt(g_over_A * params.A * params.g * params.D0)


def reference_xi(params, K_over_M, V, inertial=True):
    chi = float(physics.reduced_stiffness(K_over_M, params.D0, params.g))
    mu1 = float(physics.mu1(V, params.m1, params.m2, params.V0))
    gamma = float(physics.inertia_number(V, params.D0, params.g))
    if inertial:
        return reference_inertial_stop(chi, params.A, mu1, params.m2, gamma).xi_inf
    return reference_stop(chi, params.A, mu1, params.m2).xi_inf


def stop(params, K_over_M, V, **kw) -> sweep.Scene:
    return sweep.Scene(protocol="stop", params=params, K_over_M=K_over_M, V=V, **kw)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(PARAM_SETS))
@pytest.mark.parametrize("rtol", [1e-5, 1e-8])
def test_inertial_stop_matches_the_radau_reference_for_gamma_over_A_1e3_to_10(name, rtol):
    """xi_inf with inertia within rtol of the reference at gamma/A 1e-3..10 (stiff at the low end and late in
    every stop), and its error estimate bounds the true error."""
    params = PARAM_SETS[name]
    V = velocities_for(params, G_OVER_A)
    K = np.array([1.5, 4.0]) * params.m1 * params.g / params.D0  # chi = 1.5 m1 and 4 m1
    ds = sweep.run_sweep(stop(params, K, V, rtol=rtol, model="inertial"), progress=False)
    assert np.all(ds["model"].values == 1) and "model_error" not in ds
    assert np.all(ds["status"].values == sweep.Status.OK)
    for i, km in enumerate(K):
        for j, v in enumerate(V):
            ref = reference_xi(params, km, v)
            got, est = float(ds["xi_inf"][i, j]), float(ds["xi_inf_error"][i, j])
            assert abs(got - ref) <= rtol * ref, (name, km, v, got, ref)
            assert est >= abs(got - ref), ("estimate below the true error", name, km, v, est, got - ref)


def test_inertial_stop_tends_to_the_quasistatic_one_as_gamma_goes_to_zero():
    """gamma/A = 1e-9: the inertial model and the quasi-static reference agree to rtol (sample2 and its
    strengthening side, where mu1(V) < 0)."""
    params = PARAM_SETS["sample2"]
    D0 = 100.0  # an absurdly large memory length makes gamma = V^2/(g D0) tiny at the usual velocities
    params = sweep.FrictionParams(A=params.A, m1=params.m1, m2=params.m2, D0=D0)
    V = np.array([1e-6, 1e-4])  # mu1 > 0 and mu1 < 0
    K = np.array([2.0, 6.0]) * params.m1 * params.g / D0
    ds = sweep.run_sweep(stop(params, K, V, rtol=1e-7, model="inertial"), progress=False)
    assert float(ds["gamma"].max()) / params.A < 1e-8
    for i, km in enumerate(K):
        for j, v in enumerate(V):
            ref = reference_xi(params, km, v, inertial=False)
            assert float(ds["xi_inf"][i, j]) == pytest.approx(ref, rel=1e-7)


@pytest.mark.slow
@pytest.mark.parametrize("name, model_tol", [("m2zero", 1e-2), ("sample2", 3e-4)])
def test_auto_model_choice_bounds_the_true_model_error(name, model_tol):
    """model="auto": each quasi-static point's true model error (vs the inertial reference) is within model_tol
    and within 2x of its model_error estimate; each inertial point matches the inertial reference to rtol and its
    model_error (the measured gap) the reference gap; both kinds occur (sample2: mu1 < 0 above 6.6 um/s, where the
    gap stays ~1e-4 even at gamma/A = 10, docs/physics.md 3a)."""
    params, rtol = PARAM_SETS[name], 1e-6
    V = velocities_for(params, np.array([1e-3, 5e-3, 2e-2, 0.2]))
    K = np.array([1.2, 3.0, 10.0]) * params.m1 * params.g / params.D0
    ds = sweep.run_sweep(stop(params, K, V, rtol=rtol, model_tol=model_tol), progress=False)
    assert ds["model"].attrs["flag_meanings"] == MODEL_FLAG["flag_meanings"]
    model, estimate = ds["model"].values, ds["model_error"].values
    assert 0 < model.sum() < model.size, "both models should be used on this grid"
    assert np.all(ds["status"].values == sweep.Status.OK)
    for i, km in enumerate(K):
        for j, v in enumerate(V):
            ref = reference_xi(params, km, v)
            got = float(ds["xi_inf"][i, j])
            if model[i, j] == 0:
                true_error = abs(got / ref - 1.0)
                assert true_error <= model_tol
                assert estimate[i, j] / 2 <= true_error <= 2 * estimate[i, j], (km, v, true_error, estimate[i, j])
            else:  # solved with inertia: model_error is the gap measured between the two models
                gap = abs(ref / reference_xi(params, km, v, inertial=False) - 1.0)
                assert estimate[i, j] / 2 <= gap <= 2 * estimate[i, j], (km, v, gap, estimate[i, j])
                assert got == pytest.approx(ref, rel=rtol)


def test_auto_dataset_follows_the_model_used():
    """chi_c is the inertial line mu1 (1 + gamma/A) where gamma/A > model_tol, chi_c_quasistatic = mu1 is kept,
    stable follows chi_c; a forced model stores no model_error."""
    params = PARAM_SETS["m2zero"]
    V = velocities_for(params, np.array([1e-3, 0.2]))
    chi_c_in = params.m1 * (1.0 + 0.2)
    K = np.array([0.5, 1.1, 2.0]) * params.m1 * params.g / params.D0  # chi between the two lines at 1.1
    ds = sweep.run_sweep(stop(params, K, V), progress=False)
    np.testing.assert_allclose(ds["chi_c_quasistatic"].values, params.m1)
    np.testing.assert_allclose(ds["chi_c"].values, [params.m1, chi_c_in], rtol=1e-12)
    np.testing.assert_array_equal(ds["stable"].values, [[0, 0], [1, 0], [1, 1]])
    forced = sweep.run_sweep(stop(params, K, V, model="quasistatic"), progress=False)
    assert "model_error" not in forced and np.all(forced["model"].values == 0)
    np.testing.assert_allclose(forced["chi_c"].values, params.m1)


def test_auto_with_time_resolved_observables_flags_the_points_that_need_inertia():
    """The inertial stop computes xi_inf only: a trajectory sweep keeps quasi-static values where inertia is
    needed, with status model_error_above_tol, never silently."""
    params = PARAM_SETS["m2zero"]
    V = velocities_for(params, np.array([1e-3, 0.2]))
    K = np.array([3.0]) * params.m1 * params.g / params.D0
    ds = sweep.run_sweep(stop(params, K, V, observables=("xi_inf", "trajectory")), progress=False)
    status = ds["status"].values[0]
    assert status[0] == sweep.Status.OK and status[1] == sweep.Status.MODEL_ERROR_ABOVE_TOL
    assert float(ds["model_error"][0, 1]) > 1e-2 and np.all(ds["model"].values == 0)


def test_model_tol_is_checked_before_any_work():
    params = PARAM_SETS["m2zero"]
    for bad in (0.0, 1.0, float("nan")):
        with pytest.raises(InputError, match="model_tol"):
            stop(params, [1e3], [1e-6], model_tol=bad)


def lane_estimate(k: float, a: float, b: float, G: float) -> tuple[float, float, int]:
    """(xi_inf, first-order correction, status) as model="auto" estimates them for one point where the ladder did not
    carry the correction (time-resolved scenes): the RK4 lane run at ESTIMATE_STEP."""
    from sweep.accuracy import ESTIMATE_RTOL, ESTIMATE_STEP
    from sweep.integrate.lanes import LaneOutputs, LanePoints, LaneRuns, lane_kernels
    from sweep.plan.plan import time_scale
    from sweep.protocols.stop.model_choice import ESTIMATE_MAX_STEPS

    relax_runs = lane_kernels(np.dtype(np.float64), "rk4", True)[0]
    one = lambda x: np.array([float(x)])  # noqa: E731
    out = LaneOutputs(one(np.nan), one(np.nan), one(np.nan), np.zeros(1, np.int8), np.zeros(1, np.int32))
    relax_runs(LanePoints(one(k), one(a), one(b), one(time_scale(k, a)), one(G)),
               LaneRuns(np.zeros(1, np.int64), one(ESTIMATE_STEP), ESTIMATE_RTOL, 1e-12, 10**7), np.arange(1), out)
    assert out.steps[0] <= ESTIMATE_MAX_STEPS  # else auto falls back to the per-point module
    return out.xi_inf[0], out.correction[0], int(out.status[0])


def test_lane_estimate_of_the_first_order_correction_matches_a_tight_integration():
    """The correction riding in the RK4 lanes at ESTIMATE_STEP agrees with the per-point RODAS3 integration of the
    same equation at rtol 1e-10 to a small fraction of itself (it only routes points, with margins >= 1.5), over
    chi/A 0.1..1e3, mu1/A -4..10, m2/A 0..2 and gamma/A up to the trusted range."""
    from sweep.integrate.stop_inertial import relax
    from sweep.protocols.stop.model_choice import FIRST_ORDER_TRUST

    errors = []
    for k in np.logspace(-1, 3, 5):
        for a in (-4.0, -1.0, 0.1, 1.0, 10.0):
            for b in (0.0, 0.5, 2.0):
                if (b == 0.0 and a <= 0.0) or k <= a:
                    continue
                for tau in (0.1, FIRST_ORDER_TRUST):
                    G = tau / (1.0 + k + abs(a))
                    xi, correction, status = lane_estimate(k, a, b, G)
                    tight = relax(k, a, b, G, False, 1e-10, 1e-16, 10**7)
                    assert status == tight[2] == sweep.Status.OK
                    errors.append(abs(correction / xi / (tight[1] / tight[0]) - 1.0))
    assert len(errors) > 40
    assert max(errors) < 0.03, max(errors)


def test_first_order_estimate_where_trusted_is_within_the_routing_margin_of_the_true_gap():
    """Where model="auto" trusts the first-order estimate (tau = gamma/A (1 + (chi + |mu1|)/A) <= FIRST_ORDER_TRUST),
    the true gap (inertial vs quasi-static model, both solved tightly) is within [1/margin, margin] of the estimate,
    margin = routing_margin(tau) (1.5 up to tau = 2, 2 up to 4), so routing on margin x estimate <= model_tol keeps
    the true error within model_tol, over chi/A 0.1..1e3, mu1/A -4..10 and m2/A 0..2; and well beyond the trusted
    range it is not (the expansion fails where the slider rebounds inertially), which is why such points are
    measured instead. The estimate is the one auto computes: the lanes' RK4 run at ESTIMATE_STEP."""
    from sweep.integrate.stop_inertial import relax
    from sweep.protocols.stop.model_choice import CLOSE_TRUST, FIRST_ORDER_TRUST, routing_margin

    def ratio(k, a, b, G):
        inertial = relax(k, a, b, G, True, 1e-9, 1e-15, 10**7)
        quasi = relax(k, a, b, G, False, 1e-9, 1e-15, 10**7)
        xi, correction, status = lane_estimate(k, a, b, G)
        assert inertial[2] == quasi[2] == status == sweep.Status.OK
        return (inertial[0] / quasi[0] - 1.0) / abs(correction / xi)

    ratios, margins = [], []
    for k in np.logspace(-1, 3, 5):
        for a in (-4.0, -1.0, 0.1, 1.0, 10.0):
            for b in (0.0, 0.5, 2.0):
                if (b == 0.0 and a <= 0.0) or k <= a:
                    continue
                for tau in (0.5 * CLOSE_TRUST, CLOSE_TRUST, 0.5 * (CLOSE_TRUST + FIRST_ORDER_TRUST), FIRST_ORDER_TRUST):
                    ratios.append(ratio(k, a, b, tau / (1.0 + k + abs(a))))
                    margins.append(routing_margin(np.array(tau)))
    ratios, margins = np.array(ratios), np.array(margins)
    assert ratios.size > 80
    assert np.all((ratios >= 1.0 / margins) & (ratios <= margins)), (ratios / margins).max()
    assert routing_margin(np.array(1.01 * FIRST_ORDER_TRUST)) == np.inf
    assert ratio(1e3, 2.0, 0.0, 1.0) > 10.0  # a rebound: gamma/A (1 + (chi + |mu1|)/A) = 1e3
