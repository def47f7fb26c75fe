"""The protocol seam: a third protocol, registered from outside the package (tests/protocol_echo.py), is validated,
planned, run chunk by chunk (threads, journal, resume), written, read back and drawn by the package's own machinery,
and the built-in protocols answer through the catalogue."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import sweep
import sweep.run.runner
from sweep import physics, protocols
from sweep.errors import InputError
from sweep.write.read import file_kind


@pytest.fixture
def echo(monkeypatch):
    monkeypatch.setitem(protocols._CATALOGUE, "echo", "protocol_echo")
    return protocols.get("echo")


def echo_scene(**kw):
    p = sweep.presets["sample2"]
    return sweep.Scene(protocol="echo", params=p, K_over_M=np.logspace(3, 6, 9), V=np.logspace(-7, -4, 5), **kw)


def test_a_registered_protocol_runs_through_the_chunk_loop_the_journal_and_the_file(echo, tmp_path):
    scene = echo_scene()
    expected = physics.reduced_stiffness(scene.K_over_M, scene.params.D0, scene.params.g)[:, None] * np.ones(5)
    out = tmp_path / "echo.nc"
    ds = sweep.run_sweep(scene, progress=False, output=out)
    np.testing.assert_allclose(ds["echo"].values, expected, rtol=1e-15)
    back = sweep.open(out)
    assert file_kind(back) == "echo"
    xr.testing.assert_identical(back["echo"], ds["echo"])
    assert 'protocol = "echo"' in back.attrs["scene"]
    assert sweep.plot.plot_file(back, tmp_path / "echo.png") == [tmp_path / "echo.png"]


def test_a_registered_protocol_resumes_from_its_journal(echo, tmp_path, monkeypatch):
    """Interrupted after 2 of its chunks (chunk size 7 on a 9 x 5 grid: 9 blocks of one V row each), the run resumes
    with only the rest and gives the same file."""
    scene = echo_scene()
    out = tmp_path / "echo.nc"
    real, calls = echo.chunk, []

    def interrupting(scene, plan, progress=False):
        compute = real(scene, plan, progress)

        def wrapped(rows):
            calls.append(rows.size)
            if len(calls) == 3:
                raise KeyboardInterrupt
            return compute(rows)
        return wrapped

    monkeypatch.setattr(echo, "chunk", interrupting)
    with pytest.raises(sweep.run.runner.Interrupted, match="2 of 9 chunks are saved"):
        sweep.run_sweep(scene, progress=False, output=out)
    calls.clear()
    monkeypatch.setattr(echo, "chunk", real)
    resumed = sweep.run_sweep(scene, progress=False, output=out, resume=True)
    whole = sweep.run_sweep(scene, progress=False)
    xr.testing.assert_identical(resumed["echo"], whole["echo"])


def test_a_registered_protocol_owns_its_observables_and_its_refusals(echo):
    with pytest.raises(InputError, match=r"unknown observable\(s\) \['xi_inf'\] in observables of protocol 'echo'"):
        echo_scene(observables=("xi_inf",))
    with pytest.raises(InputError,
                       match="extra axes are offered for protocol 'stop' and 'history' only, got protocol 'echo'"):
        echo_scene(axes={"A": [0.005, 0.01]})
    with pytest.raises(InputError, match=r"state_law 'slip' is not offered on protocol 'echo'; supported: \['aging'\]"):
        echo_scene(state_law="slip")
    assert echo_scene().observables == ("echo",)


def test_a_registered_protocol_has_its_own_scene_fields(echo, tmp_path):
    """Its field ``scale`` is held in Scene.options (its default filled in), checked by the protocol, written into
    the canonical TOML as a top-level key and read back from a scene file; a field it does not have is refused."""
    assert echo_scene().options.scale == 1.0
    scene = echo_scene(options={"scale": 2.5})
    assert scene.options == {"scale": 2.5}
    again = sweep.load_scene(scene.to_toml())
    assert again.options == {"scale": 2.5} and again.to_toml() == scene.to_toml()
    expected = 2.5 * physics.reduced_stiffness(scene.K_over_M, scene.params.D0, scene.params.g)[:, None] * np.ones(5)
    np.testing.assert_allclose(sweep.run_sweep(again, progress=False)["echo"].values, expected, rtol=1e-15)
    with pytest.raises(InputError, match="scale must be > 0, got -1"):
        echo_scene(options={"scale": -1})
    with pytest.raises(InputError, match=r"options \['speed'\] are not fields of protocol 'echo'; its fields: "
                                         r"\['scale'\]"):
        echo_scene(options={"speed": 1})
    with pytest.raises(InputError, match=r"options \['scale'\] are not fields of protocol 'stop'"):
        sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=[1e4], V=[1e-6],
                    options={"scale": 2.0})


def test_an_unknown_protocol_is_refused_with_the_catalogue():
    with pytest.raises(InputError, match=r"protocol must be one of \('stop', 'driven', 'history'\), got 'hold'"):
        sweep.Scene(protocol="hold", params=sweep.presets["sample2"], K_over_M=[1e4], V=[1e-6])


@pytest.mark.parametrize("name, marker", [("stop", "xi_inf"), ("driven", "regime")])
def test_the_built_in_protocols_answer_through_the_catalogue(name, marker):
    protocol = protocols.get(name)
    assert protocol.name == name and protocol.marker == marker and protocol.always in protocol.observables
    assert set(protocol.default_observables) <= set(protocol.observables)


@pytest.fixture
def dummy_law(monkeypatch):
    from sweep.integrate.models.state_laws import STATE_LAWS, StateLaw, aging

    law = StateLaw("dummy", aging, aging_identity=False, stop_family=None, inertial=False, finite_at_zero_m2=False)
    monkeypatch.setitem(STATE_LAWS, "dummy", law)
    return law


def test_a_registered_state_law_is_refused_where_no_kernel_runs_it(dummy_law):
    """A law without a stop kernel or an inertial model: the stop scene refuses it listing the laws it runs, the
    driven scene takes it quasi-statically only; an unknown law lists every law."""
    p = sweep.presets["sample2"]
    grid = dict(params=p, K_over_M=[1e4, 1e5], V=[1e-6, 1e-5])
    with pytest.raises(InputError, match=r"state_law 'dummy' is not offered on protocol 'stop'; supported: "
                                         r"\['aging', 'slip'\]"):
        sweep.Scene(protocol="stop", state_law="dummy", model="quasistatic", **grid)
    with pytest.raises(InputError, match="state_law 'dummy' runs with model 'quasistatic' only on protocol 'driven', "
                                         "got model='auto'"):
        sweep.Scene(protocol="driven", state_law="dummy", **grid)
    assert sweep.Scene(protocol="driven", state_law="dummy", model="quasistatic", **grid).state_law == "dummy"
    with pytest.raises(InputError, match=r"state_law must be one of \['aging', 'dummy', 'slip'\], got 'ageing'"):
        sweep.Scene(protocol="driven", state_law="ageing", **grid)
