"""Convergence order of the fixed-step lane kernels (RK4, Rosenbrock ros4), measured against the exact m2 = 0
relaxed slip."""

import math

import numpy as np
import pytest

import sweep

A, M1, D0, G = 0.007, 0.0125, 1e-6, 9.81


def exact_m2zero(chi: float) -> float:
    # independent of the package: separable form of the stop equation in s = int dtau/psi (docs/physics.md 3a)
    return A * math.log(chi / M1) / (chi - M1)


@pytest.mark.parametrize("method", ["rk4", "ros4"])
def test_fixed_step_order_is_four_on_a_smooth_case(method):
    params = sweep.FrictionParams(A=A, m1=M1, m2=0.0, D0=D0)
    chi = 0.02
    steps = np.array([0.4, 0.2, 0.1, 0.05])
    errors = []
    for h in steps:
        pt = sweep.solve_point(params, K_over_M=chi * G / D0, V=1e-6, rtol=1e-10, observables=("xi_inf",), step=h,
                              method=method)
        # steps this coarse cannot meet rtol = 1e-10: the error estimate must say so (status error_above_tol)
        err = abs(float(pt["xi_inf"]) - exact_m2zero(chi))
        assert err <= float(pt["xi_inf_error"]), (h, err, float(pt["xi_inf_error"]))
        expected = sweep.Status.OK if float(pt["xi_inf_error"]) <= 1e-10 * exact_m2zero(chi) + 1e-12 else \
            sweep.Status.ERROR_ABOVE_TOL
        assert int(pt["status"]) == expected
        errors.append(err / exact_m2zero(chi))
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 3.7 <= slope <= 4.3, (slope, errors)
