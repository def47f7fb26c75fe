"""The engine's slip state law (Scene(state_law="slip")) against the independent scipy reference
tests/reference_slip.py (whose own checks are tests/integrate/test_reference_slip.py).

Slip law (Ruina 1983): dphi/dt = -(xdot phi/D0) ln(xdot phi/D0); reduced psi' = -xi' psi ln(xi' psi). The force
balance is the aging law's. What the engine must reproduce (derivations: reference_slip.py's docstring):

* stop: xi_inf is finite iff m2 > 0 (NOT "m2 > 0 or m2 = 0 with mu1 > 0" as for aging: with m2 = 0 the slip law
  has no finite limit whatever mu1); otherwise status no_finite_limit and NaN xi_inf. Where finite, xi_inf within
  rtol of the reference, with an error estimate that bounds the true error;
* state_law="aging" given explicitly is the default, bit for bit;
* driven: both laws share the linearisation A s^2 + (chi - mu1) s + chi = 0 (Hopf line chi_c = mu1): steady above
  the line, stick-slip below it for m2 > 0 (a limit cycle), neutral at the line for m2 = 0; per-cycle growth rate
  and period as the reference measures them from the same perturbation;
* state_law must be "aging" or "slip": anything else is an InputError naming state_law and the allowed values.

These tests are written against that API before it exists: on a branch without state_law they fail with
TypeError (unexpected keyword argument 'state_law'), except test_driven_cycles_are_counted_as_the_reference_counts
(aging law, today's API), which checks that the reference measures cycles exactly as the engine does.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import reference_slip as rs
from cases import NO_LIMIT_CASES, STOP_CASES, V0, G, case_params

import sweep
from sweep.integrate.driven import Regime

ATOL = sweep.scene.scene.DEFAULT_ATOL["xi_inf"]
REFERENCE_REL = 1e-12
"""Relative accuracy trusted of the reference's xi_inf (Airy closed form, DOP853/Radau and the tail checks agree to
< 3e-13 on the table: tests/integrate/test_reference_slip.py)."""
SHARPNESS = 100.0
"""The estimate may overstate the true error by at most this factor (the contract of
tests/integrate/test_error_estimates.py)."""

FINITE = [c for c in STOP_CASES if c.m2 > 0.0]
"""The slip law has a finite xi_inf iff m2 > 0."""
NO_LIMIT = [c for c in STOP_CASES if c.m2 == 0.0][:4] + NO_LIMIT_CASES
"""m2 <= 0: no finite limit for the slip law (the first four are finite for the aging law: m2 = 0, mu1 > 0)."""


def params_of(case) -> tuple[sweep.FrictionParams, dict]:
    c = case_params(case)
    return sweep.FrictionParams(A=c["A"], m1=c["m1"], m2=c["m2"], D0=c["D0"]), c


def stop_point(case, rtol, **kw):
    """The 0-d Dataset of one stop case through run_sweep, slip law unless state_law is given."""
    params, c = params_of(case)
    scene = sweep.Scene(protocol="stop", params=params, K_over_M=[c["K_over_M"]], V=[c["V"]], rtol=rtol,
                        model="quasistatic", **{"state_law": "slip", **kw})
    return sweep.run_sweep(scene, progress=False).isel(K_over_M=0, V=0)


@functools.cache
def reference(name: str) -> rs.StopSolution:
    case = next(c for c in STOP_CASES + NO_LIMIT_CASES if c.name == name)
    return rs.stop(case.chi, case.A, case.mu1, case.m2)


# ---------------------------------------------------------------------------------------------------------
# stop scene


@pytest.mark.parametrize("rtol", (1e-6, 1e-9))
@pytest.mark.parametrize("case", FINITE, ids=lambda c: c.name)
def test_slip_xi_inf_within_rtol_of_reference(case, rtol):
    pt = stop_point(case, rtol)
    ref = reference(case.name)
    assert ref.finite
    assert int(pt["status"]) == sweep.Status.OK, int(pt["status"])
    err = abs(float(pt["xi_inf"]) - ref.xi_inf)
    assert err <= rtol * abs(ref.xi_inf) + ATOL, (err / ref.xi_inf, int(pt["steps"]))
    # the estimate bounds the true error (down to what the reference resolves) and is not more than 100x it
    estimate = float(pt["xi_inf_error"])
    floor = REFERENCE_REL * ref.xi_inf + ATOL
    assert err <= estimate + floor, (err, estimate)
    assert estimate <= SHARPNESS * max(err, floor), (err, estimate)
    assert int(pt["steps"]) > 0


@pytest.mark.parametrize("case", NO_LIMIT, ids=lambda c: c.name)
def test_slip_no_finite_limit(case):
    """m2 <= 0: no finite limit for the slip law, including m2 = 0 with mu1 > 0 where the aging law has one."""
    assert not rs.has_finite_limit(case.mu1, case.m2)
    pt = stop_point(case, 1e-6)
    assert int(pt["status"]) == sweep.Status.NO_FINITE_LIMIT
    assert math.isnan(float(pt["xi_inf"]))
    if case.m2 == 0.0 and case.mu1 > 0.0:  # the aging law does converge here
        aging = stop_point(case, 1e-6, state_law="aging")
        assert int(aging["status"]) == sweep.Status.OK and math.isfinite(float(aging["xi_inf"]))


@pytest.mark.parametrize("name", ["g_chiA1_mA0.3_m2A0.05", "s2_KM1e3_V100um_corner"])
def test_slip_law_slides_further_than_aging(name):
    """xi_inf(slip) > xi_inf(aging) on the same case (no healing at rest; reference_slip.py section 2)."""
    case = next(c for c in STOP_CASES if c.name == name)
    slip, aging = stop_point(case, 1e-6), stop_point(case, 1e-6, state_law="aging")
    assert float(slip["xi_inf"]) > float(aging["xi_inf"])


@pytest.mark.parametrize("observable", ["trajectory", "t50", "t90"])
def test_slip_time_resolved_observables_are_refused_before_any_work(observable):
    """The slip-law stop computes the relaxed slip only (its general path works in the phase plane, without time):
    a time-resolved observable is refused by the Scene, naming state_law and the allowed observables. (The slip
    law's late fractions are astronomically late anyway: xi_inf - xi ~ 1/(b u), ln tau ~ b u^2, t90 = 8e27 for
    s1_KM7.4e4_V10um; reference_slip.py computes them.)"""
    case = next(c for c in STOP_CASES if c.name == "s1_KM7.4e4_V10um")
    with pytest.raises(sweep.InputError, match=r"state_law 'slip'.*xi_inf"):
        stop_point(case, 1e-6, observables=("xi_inf", observable))


def test_explicit_aging_is_the_default():
    """state_law="aging" given explicitly changes nothing: every variable equal (NaN where NaN), same attrs apart
    from timing/history and the state_law record itself."""
    kw = dict(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, 4), V=np.logspace(-7, -4, 3),
              rtol=1e-6, observables=("xi_inf", "t50"))
    default = sweep.run_sweep(sweep.Scene(**kw), progress=False)
    explicit = sweep.run_sweep(sweep.Scene(state_law="aging", **kw), progress=False)
    assert set(default.data_vars) == set(explicit.data_vars)
    for name in default.data_vars:
        np.testing.assert_array_equal(default[name].values, explicit[name].values, err_msg=name)
    for name in default.coords:
        np.testing.assert_array_equal(default[name].values, explicit[name].values, err_msg=name)
    assert sweep.Scene(**kw).state_law == "aging"


@pytest.mark.parametrize("bad", ["ageing", "Slip", "", "ruina"])
def test_bad_state_law_names_the_parameter_and_the_allowed_values(bad):
    case = FINITE[0]
    params, c = params_of(case)
    for protocol in ("stop", "driven"):
        with pytest.raises(sweep.InputError, match="state_law") as info:
            sweep.Scene(protocol=protocol, params=params, K_over_M=[c["K_over_M"]], V=[c["V"]], state_law=bad)
        assert "aging" in str(info.value) and "slip" in str(info.value)


# ---------------------------------------------------------------------------------------------------------
# driven scene

A, MU1, M2, D0 = 0.007, 0.0125, 0.0033, 1e-6  # sample2's A, m1, m2 at V = V0 (mu1 = m1): chi_c = mu1
FACTORS = (0.9, 1.05, 1.2)  # chi/chi_c: below (stick-slip for m2 > 0), just above, above


def driven_grid(state_law: str, m2: float = M2, factors=FACTORS, **kw):
    params = sweep.FrictionParams(A=A, m1=MU1, m2=m2, D0=D0)
    K_over_M = np.array(factors) * MU1 * G / D0
    scene_kw = dict(protocol="driven", params=params, K_over_M=K_over_M, V=[V0], model="quasistatic", **kw)
    if state_law != "default":
        scene_kw["state_law"] = state_law
    scene = sweep.Scene(**scene_kw)
    return scene, sweep.run_sweep(scene, progress=False).isel(V=0)


def check_against_reference(scene, ds, m2, aging):
    """Per point: the reference run from the same perturbation for the engine's number of cycles; growth rate,
    period (and amplitude) of that cycle within 1e-3 (growth rates near 0 on a limit cycle: 1e-6 absolute)."""
    chi = ds["K_over_M"].values * D0 / G
    for i, regime in enumerate(ds["regime"].values):
        n = int(ds["cycles"].values[i])
        assert n >= 2, (i, n)
        ref = rs.driven(chi[i], A, MU1, m2, scene.perturbation, aging=aging, cycles=n, stop_when_decided=False)
        assert len(ref.amplitude) - 1 >= n, (i, n, ref.regime)
        assert float(ds["period"].values[i]) == pytest.approx(ref.period[n], rel=1e-3), i
        assert float(ds["growth_rate"].values[i]) == pytest.approx(ref.growth[n], rel=1e-3, abs=1e-6), i
        if regime == Regime.STICK_SLIP:
            assert float(ds["amplitude"].values[i]) == pytest.approx(ref.amplitude[n], rel=1e-3), i


def test_driven_explicit_aging_is_the_default():
    _, default = driven_grid("default")
    _, explicit = driven_grid("aging")
    for name in default.data_vars:
        np.testing.assert_array_equal(default[name].values, explicit[name].values, err_msg=name)


def test_driven_cycles_are_counted_as_the_reference_counts():
    """Today's API, aging law: the reference (aging=True) measures the engine's cycles the same way (first cycle
    ends at the second maximum of z after the start), so the slip-law comparison below compares like with like."""
    scene, ds = driven_grid("default")
    assert list(ds["regime"].values) == [Regime.STICK_SLIP, Regime.STEADY, Regime.STEADY]
    check_against_reference(scene, ds, M2, aging=True)


def test_driven_slip_law_across_the_hopf_line():
    """m2 > 0: steady above the line (chi > mu1), a stick-slip limit cycle below it; growth rates and periods as
    the reference's, and near the line as the linear theory's (the same for both laws)."""
    scene, ds = driven_grid("slip")
    assert scene.perturbation == sweep.Scene.__dataclass_fields__["perturbation"].default
    assert list(ds["regime"].values) == [Regime.STICK_SLIP, Regime.STEADY, Regime.STEADY]
    assert np.all(ds["status"].values == sweep.Status.OK)
    check_against_reference(scene, ds, M2, aging=False)
    steady = ds["regime"].values == Regime.STEADY
    np.testing.assert_allclose(ds["growth_rate"].values[steady], ds["growth_rate_linear"].values[steady], rtol=2e-3)
    np.testing.assert_allclose(ds["period"].values[steady], ds["period_linear"].values[steady], rtol=2e-3)
    # the slip law's limit cycle is smaller than the aging law's at the same point (1.02 vs 1.55 at 0.9 chi_c)
    _, aging = driven_grid("aging")
    assert 0.5 < float(ds["amplitude"].values[0]) < 0.9 * float(aging["amplitude"].values[0])


def test_driven_slip_law_m2_zero_is_neutral_at_the_line():
    """m2 = 0: the quasi-static Hopf point is degenerate for the slip law too: orbits neutral at chi = mu1."""
    scene, ds = driven_grid("slip", m2=0.0, factors=(1.0,))
    assert int(ds["regime"].values[0]) == Regime.NEUTRAL
    assert abs(float(ds["growth_rate"].values[0])) < 1e-8
    ref = rs.driven(MU1, A, MU1, 0.0, scene.perturbation, cycles=10)
    assert ref.regime == "neutral"
    assert float(ds["period"].values[0]) == pytest.approx(ref.period[-1], rel=1e-3)
