"""Analytic limits of docs/physics.md section 4 checked on the engine's own outputs (trajectory and xi_inf)."""

import numpy as np
import pytest

import sweep
from sweep import physics

A, M1, D0, G = 0.007, 0.0125, 1e-6, 9.81
CHI = 0.02  # the worked example of docs/physics.md 4


def point(chi=CHI, m2=0.0, V=1e-6, rtol=1e-10, tau=(1e-8, 1e12, 801)):
    params = sweep.FrictionParams(A=A, m1=M1, m2=m2, D0=D0)
    return sweep.solve_point(params, K_over_M=chi * G / D0, V=V, rtol=rtol, trajectory_tau=tau)


def test_m2zero_relaxed_slip_is_the_closed_form():
    pt = point()
    assert float(pt["xi_inf"]) == pytest.approx(0.43865, abs=5e-5)  # docs/physics.md 4: exact 0.4387
    assert float(pt["xi_inf"]) == pytest.approx(physics.xi_inf_m2zero(CHI, A, M1), rel=1e-9)


def test_eq9_integral_identity_from_the_trajectory():
    """xi_inf = (A/chi) ln(1 + chi I/A), I = int_0^inf psi^-(1 + m1/A) dtau, with I from the engine's psi(tau)."""
    pt = point()
    tau, psi = pt["tau"].values, pt["psi"].values
    beta = 1 + M1 / A
    integrand = psi ** -beta * tau  # d tau = tau d ln tau
    body = np.sum(0.5 * (integrand[1:] + integrand[:-1]) * np.diff(np.log(tau)))
    head = tau[0]  # psi = 1 + O(tau) before the first sample
    tail = psi[-1] ** -beta * tau[-1] / (beta - 1)  # psi ~ tau late: int tau^-beta
    xi_eq9 = physics.xi_inf_from_integral(CHI, A, head + body + tail)
    assert xi_eq9 == pytest.approx(float(pt["xi_inf"]), rel=2e-5)


def test_eq12_early_stage_limit():
    pt = point(tau=(1e-9, 1e-3, 7))
    early = physics.xi_early(pt["tau"].values, CHI, A)
    rel = np.abs(pt["xi"].values / early - 1)
    assert rel[0] < 1e-12, "the early-stage formula is the exact tau -> 0 limit"
    # the departure is O(tau^2) (psi - 1 = O(tau) enters at second order): a hundredfold per decade
    tau = pt["tau"].values
    visible = rel > 1e-11
    assert visible.sum() >= 3
    assert np.allclose(rel[visible] / tau[visible] ** 2, rel[-1] / tau[-1] ** 2, rtol=0.05)


def test_eq13_late_stage_ratio():
    pt = point(tau=(10.0, 1e3, 3))
    xi_inf = float(pt["xi_inf"])
    deficit = xi_inf - pt["xi"].values
    ratio = deficit / physics.xi_late_deficit(pt["tau"].values, CHI, A, M1, xi_inf)
    assert ratio[0] == pytest.approx(0.94, abs=0.005)  # docs/physics.md 4
    assert ratio[-1] == pytest.approx(0.9994, abs=2e-4)


def test_m2zero_trajectory_does_not_depend_on_V():
    params = sweep.FrictionParams(A=A, m1=M1, m2=0.0, D0=D0)
    scene = sweep.Scene(protocol="stop", params=params, K_over_M=[CHI * G / D0], V=[1e-7, 1e-6, 1e-4],
                        rtol=1e-8, observables=("trajectory",), trajectory_tau=(1e-3, 1e6, 19))
    xi = sweep.run_sweep(scene)["xi"].values[0]
    np.testing.assert_allclose(xi, np.broadcast_to(xi[0], xi.shape), rtol=1e-13)
    # with m2 > 0 it does (mu1 depends on V): the check above is not vacuous
    scene2 = sweep.Scene(protocol="stop", params=params.replace(m2=0.0033), K_over_M=[CHI * G / D0],
                         V=[1e-7, 1e-4], rtol=1e-8, observables=("trajectory",), trajectory_tau=(1e-3, 1e6, 19))
    xi2 = sweep.run_sweep(scene2)["xi"].values[0]
    assert np.max(np.abs(xi2[1] / xi2[0] - 1)) > 1e-2
