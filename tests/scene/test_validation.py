"""Bad input is refused before any work, with an error naming the field and the allowed range."""

import math

import numpy as np
import pytest

import sweep
from sweep import InputError

P = dict(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6)
GOOD = dict(protocol="stop", K_over_M=[1e4, 1e5], V=[1e-6, 1e-5])


def scene(**changes):
    kw = {**GOOD, "params": sweep.FrictionParams(**P), **changes}
    return sweep.Scene(**kw)


@pytest.mark.parametrize("field", ["A", "D0"])
@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf])
def test_params_must_be_positive_and_finite(field, value):
    with pytest.raises(InputError, match=field):
        sweep.FrictionParams(**{**P, field: value})


@pytest.mark.parametrize("field", ["m1", "m2"])
def test_params_must_be_finite(field):
    with pytest.raises(InputError, match=field):
        sweep.FrictionParams(**{**P, field: math.nan})


@pytest.mark.parametrize("axis", ["K_over_M", "V"])
@pytest.mark.parametrize("values, words", [
    ([], "empty"), ([1.0, math.nan], "finite"), ([1.0, math.inf], "finite"), ([0.0, 1.0], "> 0"),
    ([-1.0, 1.0], "> 0"), ([2.0, 1.0], "increasing"), ([1.0, 1.0], "increasing"), ([[1.0, 2.0]], "1-D"),
])
def test_axes(axis, values, words):
    with pytest.raises(InputError, match=axis) as info:
        scene(**{axis: values})
    assert words in str(info.value)


def test_unknown_protocol_and_observable():
    with pytest.raises(InputError, match="protocol"):
        scene(protocol="slide")
    with pytest.raises(InputError, match="observable"):
        scene(observables=("xi_inf", "velocity"))


@pytest.mark.parametrize("rtol", [0.0, -1e-6, 1e-13, 0.5, math.nan])
def test_rtol_range(rtol):
    with pytest.raises(InputError, match="rtol"):
        scene(rtol=rtol)


def test_slip_at_needs_times_and_times_must_be_valid():
    with pytest.raises(InputError, match="t_obs"):
        scene(observables=("slip_at",))
    with pytest.raises(InputError, match="t_obs"):
        scene(observables=("slip_at",), t_obs=(1.0, -2.0))


@pytest.mark.parametrize("toml, field", [
    ('protocol = "stop"\npreset = "sample2"\n[V]\nvalues=[1e-6]\n[K_over_M]\nstart = 1e3\nstop = 1e6\n', "K_over_M"),
    ('preset = "sample9"\n[K_over_M]\nvalues=[1e3]\n[V]\nvalues=[1e-6]\n', "preset"),
    ('preset = "sample2"\n[K_over_M]\nvalues=[1e3]\n', "V"),
    ('preset = "sample2"\nrtol = 1e-6\nbogus = 1\n[K_over_M]\nvalues=[1e3]\n[V]\nvalues=[1e-6]\n', "bogus"),
    ('preset = "sample2"\n[params]\nA = -1\n[K_over_M]\nvalues=[1e3]\n[V]\nvalues=[1e-6]\n', "A"),
    ('preset = "sample2"\n[params]\nq = 1\n[K_over_M]\nvalues=[1e3]\n[V]\nvalues=[1e-6]\n', "q"),
    ('preset = "sample2"\n[K_over_M]\nstart=1e3\nstop=1e4\nnum=3\nspacing="cubic"\n[V]\nvalues=[1e-6]\n', "spacing"),
    ('preset = "sample2"\n[K_over_M = 3\n', "TOML"),
])
def test_malformed_toml(toml, field):
    with pytest.raises(InputError, match=field):
        sweep.load_scene(toml + "\n")


def test_toml_round_trip_is_canonical():
    s = scene(observables=("xi_inf", "t50"), rtol=1e-5)
    again = sweep.load_scene(s.to_toml())
    assert again.to_toml() == s.to_toml()
    np.testing.assert_array_equal(again.K_over_M, s.K_over_M)


def test_rosenbrock_is_for_the_relaxed_slip_only():
    with pytest.raises(InputError, match="relaxed slip only"):
        sweep.Scene(protocol="stop", params=sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6),
                    K_over_M=[1e4], V=[1e-6], method="ros4", observables=("xi_inf", "t50"))


def test_run_sweep_of_something_else_than_a_scene_names_scene():
    with pytest.raises(TypeError, match=r"scene must be a sweep.Scene .* got dict"):
        sweep.run_sweep({"protocol": "stop"})


@pytest.mark.parametrize("threads", ["0", "-1", "two"])
def test_a_bad_numba_thread_count_is_one_line_and_exit_2(threads, monkeypatch, capsys):
    from sweep.cli import main

    monkeypatch.setenv("NUMBA_NUM_THREADS", threads)
    assert main(["run", "--dry-run"]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert "NUMBA_NUM_THREADS must be a whole number >= 1" in line and repr(threads) in line
