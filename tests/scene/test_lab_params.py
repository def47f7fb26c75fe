"""The laboratory's parameters (a, b, Dc, mu0, V0; k in 1/m) and the paper's (docs/physics.md 7b)."""

import math

import numpy as np
import pytest

import sweep
from sweep.errors import InputError
from sweep.physics import mu_d
from sweep.scene.params import FrictionParams, K_over_M_from_k, k_from_K_over_M


def test_lab_law_is_the_papers_law_at_m2_zero():
    """mu_ss(v) of the lab's law, mu0 + (a - b) ln(v/V0), equals the paper's steady friction mu_d(v) (eq. 6) of the
    converted parameters at every v, and the round trip gives back the lab's numbers."""
    lab = {"a": 0.011, "b": 0.015, "Dc": 3e-6, "mu0": 0.62, "V0": 1e-5}
    p = FrictionParams.from_lab(**lab)
    v = np.geomspace(1e-9, 1e-2, 15)
    lab_ss = lab["mu0"] + (lab["a"] - lab["b"]) * np.log(v / lab["V0"])
    np.testing.assert_allclose(mu_d(v, p.m0, p.m1, p.m2, p.V0), lab_ss, rtol=1e-14)
    assert p.to_lab() == pytest.approx(lab, rel=1e-15)


def test_stiffness_in_per_metre_is_K_over_M_over_g():
    k = np.array([1e2, 1e4])
    np.testing.assert_allclose(K_over_M_from_k(k, 9.81), k * 9.81)
    np.testing.assert_allclose(k_from_K_over_M(K_over_M_from_k(k, 9.81), 9.81), k)
    assert math.isclose(float(K_over_M_from_k(1.0, 1.62)), 1.62)


@pytest.mark.parametrize("kwargs, words", [({"a": 0.0, "b": 0.01, "Dc": 1e-6}, "a must be > 0"),
                                           ({"a": 0.01, "b": float("nan"), "Dc": 1e-6}, "b must be finite"),
                                           ({"a": 0.01, "b": 0.01, "Dc": -1e-6}, "Dc must be > 0")])
def test_bad_lab_parameters_are_named(kwargs, words):
    with pytest.raises(InputError, match=words):
        FrictionParams.from_lab(**kwargs)


def test_a_quadratic_law_has_no_lab_equivalent():
    with pytest.raises(InputError, match="m2 = 0.0033"):
        sweep.presets["sample2"].to_lab()
