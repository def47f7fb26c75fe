"""The progress bar: quiet for short or non-interactive runs, rate and ETA otherwise."""

import io

import sweep.progress as progress_module
from sweep.progress import Progress


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
