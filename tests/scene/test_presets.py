"""Tests of sweep.presets (docs/physics.md section 5)."""

from __future__ import annotations

import math

import pytest

from sweep import physics as ph
from sweep.scene.params import FrictionParams
from sweep.scene.presets import presets, provenance


def test_presets_exist_and_are_params():
    assert set(presets) == {"sample1", "sample2"}
    for p in presets.values():
        assert isinstance(p, FrictionParams)
        assert p.V0 == 1e-6 and p.g == 9.81
    s1, s2 = presets["sample1"], presets["sample2"]
    assert (s1.A, s1.m1, s1.m2, s1.D0, s1.m0) == (0.012, 0.010, 0.0014, 1e-6, 0.2)
    assert (s2.A, s2.m1, s2.m2, s2.D0, s2.m0) == (0.007, 0.0125, 0.0033, 0.7e-6, 0.3)


def test_presets_are_immutable():
    with pytest.raises(TypeError):
        presets["sample3"] = presets["sample1"]
    with pytest.raises(TypeError):
        del presets["sample1"]
    with pytest.raises(TypeError):
        provenance["sample1"] = "x"


@pytest.mark.parametrize("name", ["sample1", "sample2"])
def test_provenance_states_the_caveat(name):
    text = provenance[name]
    for needle in ("Table I", "illegible", "20 %", "A = 0.013", "m1 = 0.013", "our reading", "Fig."):
        assert needle in text, needle
    assert "35.7 um/s" in provenance["sample1"]
    assert "6.6 um/s" in provenance["sample2"]


def test_sample2_mu1_changes_sign_near_6p6_um_s():
    p = presets["sample2"]
    V_zero = p.V0 * math.exp(p.m1 / (2 * p.m2))  # mu1(V) = m1 - 2 m2 ln(V/V0) = 0
    assert V_zero == pytest.approx(6.6e-6, rel=0.01)
    assert ph.mu1(0.99 * V_zero, p.m1, p.m2, p.V0) > 0 > ph.mu1(1.01 * V_zero, p.m1, p.m2, p.V0)
    assert math.isnan(ph.chi_c_quasistatic(ph.mu1(1e-4, p.m1, p.m2, p.V0)))


def test_sample1_eq10_domain_ends_near_35p7_um_s():
    p = presets["sample1"]
    chi = ph.reduced_stiffness(7.4e4, p.D0, p.g)  # Fig. 3b
    V_end = p.V0 * math.exp(p.m1 / (2 * p.m2))
    assert V_end == pytest.approx(35.7e-6, rel=0.01)
    assert math.isfinite(ph.xi_inf_crude(chi, p.A, ph.mu1(0.99 * V_end, p.m1, p.m2, p.V0)))
    assert math.isnan(ph.xi_inf_crude(chi, p.A, ph.mu1(1.01 * V_end, p.m1, p.m2, p.V0)))
    # Fig. 3b is in stick-slip below ~2.4 um/s: mu1(V) = chi there
    V_hopf = p.V0 * math.exp((p.m1 - chi) / (2 * p.m2))
    assert V_hopf == pytest.approx(2.4e-6, rel=0.05)
    assert not ph.stable_sliding(chi, ph.mu1(0.9 * V_hopf, p.m1, p.m2, p.V0), p.A)
    assert ph.stable_sliding(chi, ph.mu1(1.1 * V_hopf, p.m1, p.m2, p.V0), p.A)


def test_a_misspelt_preset_raises_a_KeyError_listing_the_presets_and_the_closest_name():
    with pytest.raises(KeyError) as info:
        presets["sampel2"]
    text = str(info.value)
    assert "'sample1'" in text and "'sample2'" in text and "did you mean 'sample2'" in text
    with pytest.raises(KeyError) as info:
        presets["granite"]
    assert "did you mean" not in str(info.value) and "'sample1'" in str(info.value)
    assert presets.get("sampel2") is None and "sampel2" not in presets and [] not in presets
    assert dict(presets) == {name: presets[name] for name in ("sample1", "sample2")}
