"""A history scene runs as any protocol's (issue 34): the same numbers whatever the chunking, on dask, and after an
interrupted run is resumed from its journal."""

from __future__ import annotations

import numpy as np
import pytest
from test_resume import assert_same_numbers

import sweep
from sweep.errors import InputError
from sweep.run.journal import journal_path

SHS = [{"V_ratio": 1, "displacement": 2e-5}, {"hold": 10.0}, {"V_ratio": 1, "displacement": 2e-5},
       {"hold": 100.0}, {"V_ratio": 3, "displacement": 3e-5}]


def history_scene(**kw) -> sweep.Scene:
    base = dict(protocol="history", params=sweep.presets["sample2"], K_over_M=np.geomspace(1e5, 1e6, 7),
                V=np.geomspace(1e-7, 1e-5, 5), model="quasistatic", options={"segments": SHS})
    return sweep.Scene(**{**base, **kw})


def test_history_results_do_not_depend_on_the_chunking():
    scene = history_scene()
    whole = sweep.run_sweep(scene, progress=False)
    assert int((whole["status"] == sweep.Status.OK).sum()) == scene.n_points
    for size in (1, 6):
        assert_same_numbers(whole, sweep.run_sweep(scene, progress=False, chunk_size=size))


def test_an_interrupted_history_run_resumes_to_the_uninterrupted_file(tmp_path, monkeypatch):
    import sweep.protocols.history.engine as engine
    import sweep.run.runner as runner

    scene, out = history_scene(), tmp_path / "h.nc"
    real, done = engine.history_chunk, []

    def interrupted(sc, plan):
        compute = real(sc, plan)

        def counted(points):
            if len(done) == 2:
                raise KeyboardInterrupt
            done.append(points.size)
            return compute(points)
        return counted

    monkeypatch.setattr(engine, "history_chunk", interrupted)
    with pytest.raises(runner.Interrupted, match="2 of 7 chunks are saved"):
        sweep.run_sweep(scene, progress=False, output=out, chunk_size=5)
    monkeypatch.setattr(engine, "history_chunk", real)
    assert len(list(journal_path(out).glob("chunk-*.npz"))) == 2 and not out.exists()
    with pytest.raises(InputError, match="differs in plan_hash, scene"):
        other = history_scene(options={"segments": SHS[:-1] + [{"V_ratio": 2, "displacement": 3e-5}]})
        sweep.run_sweep(other, progress=False, output=out, chunk_size=5, resume=True)
    resumed = sweep.run_sweep(scene, progress=False, output=out, chunk_size=5, resume=True)
    assert_same_numbers(resumed.load(), sweep.run_sweep(scene, progress=False))
    assert not journal_path(out).exists()


@pytest.mark.slow
def test_history_on_dask_gives_bitwise_the_same_numbers():
    scene = history_scene()
    assert_same_numbers(sweep.run_sweep(scene, progress=False),
                        sweep.run_sweep(scene, progress=False, backend="dask", workers=2, chunk_size=4))
