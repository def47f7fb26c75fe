"""The progress bar: quiet for short or non-interactive runs, rate and ETA otherwise."""

import io

import sweep.run.progress as progress_module
from sweep.run.progress import Progress


def test_quiet_when_disabled_or_short():
    stream = io.StringIO()
    with Progress(100, enabled=False, stream=stream) as bar:
        bar.update(100)
    assert stream.getvalue() == ""
    with Progress(100, enabled=True, stream=stream) as bar:  # finishes long before the threshold
        bar.update(100)
    assert stream.getvalue() == ""


def test_shows_rate_and_eta_on_long_runs(monkeypatch):
    monkeypatch.setattr(progress_module, "SHOW_AFTER_S", 0.0)
    stream = io.StringIO()
    with Progress(200, enabled=True, stream=stream) as bar:
        bar.update(50)
        bar.update(150)
    text = stream.getvalue()
    assert "25.0%" in text and "100.0%" in text and "pts/s" in text and "ETA" in text and text.endswith("\n")


def test_non_interactive_default_is_quiet():
    stream = io.StringIO()  # not a terminal
    bar = Progress(10, stream=stream)
    assert bar.enabled is False


def test_a_lone_chunks_inertial_points_show_their_progress(monkeypatch, capsys):
    """A small grid is one chunk (plan.ONE_CHUNK_POINTS), so the run's bar moves only at its end; the points that
    model "auto" solves with inertia (~1 ms each) are solved in batches with a bar of their own. Their numbers are
    those of a run in many chunks (no bar inside), bit for bit."""
    import numpy as np

    import sweep
    import sweep.protocols.stop.model_choice as model_choice

    scene = sweep.Scene(protocol="stop", params=sweep.presets["sample2"], K_over_M=np.logspace(3, 6, 8),
                        V=np.logspace(-4, -3, 6), rtol=1e-4)  # high V: inertia matters at most points
    monkeypatch.setattr(progress_module, "SHOW_AFTER_S", 0.0)
    monkeypatch.setattr(model_choice, "RELAX_BATCH", 8)
    one = sweep.run_sweep(scene, progress=True)
    inertia = [line for line in capsys.readouterr().err.split("\r") if line.startswith("inertia [")]
    n = int(one["model"].sum())
    assert n >= 16, "the scene should have inertial points"
    assert len(inertia) >= 2 * (n // 8) and "100.0%" in inertia[-1], inertia[-3:]
    many = sweep.run_sweep(scene, progress=False, chunk_size=7)
    for name in ("xi_inf", "xi_inf_error", "status", "model", "model_error"):
        np.testing.assert_array_equal(one[name].values, many[name].values, err_msg=name)
