"""Likely unit mistakes are caught before any work, ONE warning per call (issue 37): friction parameters of a scene
(sweep.scene.plausibility.warn_implausible_params) and the start and data of a fit (sweep.fit.checks)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import sweep
from sweep.fit import Curve, RelaxedSlips, stack
from sweep.fit.checks import check_problems
from sweep.fit.problem import make_problems
from sweep.fit.space import make_space
from sweep.scene import plausibility
from sweep.scene.plausibility import PlausibilityWarning, implausible_params, warn_implausible_params

S2 = sweep.presets["sample2"]


@pytest.fixture(autouse=True)
def fresh(monkeypatch):
    """Each test sees its warnings (the scene function warns once per process for the same text)."""
    monkeypatch.setattr(plausibility, "_ISSUED", set())


def _caught(fn, *args, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args, **kw)
    return out, [str(w.message) for w in caught if issubclass(w.category, PlausibilityWarning)]


def test_the_presets_are_plausible():
    for name, p in sweep.presets.items():
        messages, caught = _caught(warn_implausible_params, p)
        assert messages == [] and caught == [], name


@pytest.mark.parametrize("values, words", [
    (dict(D0=[0.7]), ["D0 = 0.7 m", "1e-08..0.001 m", "did you give µm"]),
    (dict(D0=[7e-13]), ["D0 = 7e-13 m", "twice"]),
    (dict(A=[0.5]), ["A = 0.5", "0.0001..0.1", "percent"]),
    (dict(A=[1e-5]), ["A = 1e-05", "0.0001..0.1"]),
    (dict(m1=[-0.8]), ["m1 = -0.8", "|m1| above 0.5"]),
    (dict(m2=[0.01, 0.6]), ["m2 0.01..0.6", "|m2| above 0.5"]),
])
def test_each_implausible_parameter_is_named_with_its_likely_mistake(values, words):
    (msg,) = implausible_params(**values)
    for w in words:
        assert w in msg, (w, msg)


@pytest.mark.parametrize("values", [dict(D0=[1e-8, 1e-3]), dict(A=[1e-4, 0.1]), dict(m1=[-0.5, 0.5]),
                                    dict(m2=[0.0, 0.5])])
def test_the_range_ends_are_plausible(values):
    assert implausible_params(**values) == []


def test_a_scene_D0_axis_in_um_gives_one_warning_naming_D0():
    """Issue 37: [params] D0 = 0.7 (meant um) and a [D0] axis of [0.5, 0.7, 1.0]: one warning for the call, naming
    D0 and its whole range; the other axes (K_over_M, V, ...) are not its business."""
    p = S2.replace(D0=0.7)
    messages, caught = _caught(warn_implausible_params, p, {"D0": [0.5, 0.7, 1.0], "K_over_M": [1e9], "V": [1.0]})
    assert len(caught) == 1 and len(messages) == 1
    assert "D0 0.5..1 m" in caught[0] and "did you give µm" in caught[0]


def test_several_implausible_parameters_are_still_one_warning():
    messages, caught = _caught(warn_implausible_params, S2.replace(A=0.5), {"m1": [0.1, 0.7], "A": [0.7]})
    assert len(messages) == 2 and len(caught) == 1
    assert "A 0.5..0.7" in caught[0] and "m1 0.0125..0.7" in caught[0]


def test_an_axis_alone_is_checked_and_plausible_values_say_nothing():
    messages, caught = _caught(warn_implausible_params, S2, {"A": [0.005, 0.02]})
    assert messages == [] and caught == []
    messages, caught = _caught(warn_implausible_params, None, {"A": [0.2]})
    assert len(messages) == 1 and len(caught) == 1


# --- fits: checked before any engine run ---------------------------------------------------------------------

@pytest.fixture
def no_engine(monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("the engine ran")
    monkeypatch.setattr(stack, "forward", forbidden)


def _check(data, params=S2, free=("A", "m1", "m2")):
    space = make_space(free, params)
    return _caught(check_problems, make_problems(data, space, False))


def _slips(scale, sample, n=6):
    km, v = np.geomspace(2e5, 2e6, n), np.full(n, 3e-6)
    return RelaxedSlips(km, v, scale * np.linspace(0.3e-6, 2e-6, n), sample=sample)


def test_forty_samples_of_slips_in_um_give_one_warning_listing_them(no_engine):
    """Relaxed slips given in um as if in m (values ~0.3-2 'm'): one warning for 40 samples (was one per sample),
    naming dx_inf, 'did you give µm' and the samples."""
    _, caught = _check([_slips(1e6, f"s{i}") for i in range(40)])
    assert len(caught) == 1, caught
    for w in ("dx_inf up to 2 m", "did you give µm", "samples s0, s1", "and 30 more"):
        assert w in caught[0], (w, caught[0])


def test_a_curve_in_um_and_an_implausible_start_in_one_warning(no_engine):
    t = np.logspace(-1, 3, 10)
    curves = [Curve(t, 0.3 * (1 - np.exp(-t)), 2.8e5, 1e-6, sample="c"), _slips(1.0, "fine")]
    _, caught = _check(curves, params=S2.replace(A=0.5))
    assert len(caught) == 1
    assert "x up to 0.3 m" in caught[0] and "sample c)" in caught[0] and "A = 0.5" in caught[0]
    assert "fine" not in caught[0]


def test_gamma_over_A_is_one_warning_for_many_samples(no_engine):
    """Inertia that may matter (gamma/A > 1e-2 at the start): one warning naming the samples, not one per sample."""
    data = [RelaxedSlips([1e6, 2e6, 3e6, 4e6], [3e-4, 1e-4, 1e-4, 1e-4], [1e-6, 2e-6, 2e-6, 3e-6], sample=f"fast{i}")
            for i in range(5)]
    _, caught = _check(data)
    assert len(caught) == 1 and "gamma/A" in caught[0] and "fast0, fast1, fast2, fast3, fast4" in caught[0]


def test_plausible_data_say_nothing(no_engine):
    _, caught = _check([_slips(1.0, f"s{i}") for i in range(3)])
    assert caught == []


@pytest.mark.parametrize("axes, words", [
    ({"a": [0.5, 1.0]}, ["a 0.5..1 is outside", "0.0001..0.1", "a is a number"]),
    ({"Dc": [10.0, 30.0]}, ["Dc 10..30 m", "did you give µm? Dc is in m"]),
    ({"b": [0.01, 1.5]}, ["b 0.01..1.5", "|b| above 0.5"]),
    ({"k": [1e-6, 1e-5]}, ["k 1e-06..1e-05 1/m", "K/M = k g", "per metre of load-point displacement"]),
    ({"k": [1e11, 1e12]}, ["k 1e+11..1e+12 1/m", "K in N/m"]),
])
def test_a_lab_axis_far_outside_its_range_is_warned_under_its_own_name(axes, words):
    """A scene's axes in the laboratory's parameters (a, b, Dc, k: docs/physics.md 7b) are checked as the paper's
    (a = A, Dc = D0, k g = K/M; b against SLOPE_MAX) and named as the user spelt them: one warning for the call."""
    messages, caught = _caught(warn_implausible_params, S2, axes)
    assert len(caught) == 1 and len(messages) == 1
    for w in words:
        assert w in caught[0], (w, caught[0])
    assert "A " not in caught[0].split(":")[0] and "D0 " not in caught[0].split(":")[0]


def test_plausible_lab_axes_are_quiet():
    """The usual laboratory ranges (a, b ~ 0.005-0.02, Dc ~ 1-100 um, k ~ 1e2-1e5 per m) give no warning."""
    axes = {"a": [0.005, 0.02], "b": [0.0, 0.02], "Dc": [1e-6, 1e-4], "k": [1e2, 1e5]}
    messages, caught = _caught(warn_implausible_params, S2, axes)
    assert messages == [] and caught == []
