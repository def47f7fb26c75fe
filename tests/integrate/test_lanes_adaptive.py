"""The adaptive lanes (sweep/integrate/lanes_adaptive.py) and their estimate (sweep/integrate/tolerance_ladder.py)
against the independent scipy reference (tests/reference.py): the premise of the estimate (the fine twin on the mesh
halved is at least twice as accurate as the run), the per-lane independence of the results, the step limit, and the
branch-free log2 of the step-size controller."""

import dataclasses
import functools

import numpy as np
import pytest
from cases import STOP_CASES, case_params
from reference import reference_stop

import sweep
import sweep.protocols.stop.chunk
from sweep.integrate.lanes_adaptive import _log2_approx
from sweep.plan.plan import make_plan
from sweep.protocols.stop.engine import _adaptive_runner
from sweep.status import Status

FINITE_CASES = [c for c in STOP_CASES if c.expect_finite]
REFERENCE_REL = 1e-12
"""Relative accuracy trusted of the reference's xi_inf (tests/integrate/test_error_estimates.py)."""


@functools.cache
def reference(name):
    case = next(c for c in STOP_CASES if c.name == name)
    return reference_stop(case.chi, case.A, case.mu1, case.m2).xi_inf


def case_scene(case, rtol, **kw):
    c = case_params(case)
    params = sweep.FrictionParams(A=c["A"], m1=c["m1"], m2=c["m2"], D0=c["D0"])
    return sweep.Scene(protocol="stop", params=params, K_over_M=[c["K_over_M"]], V=[c["V"]], model="quasistatic",
                       rtol=rtol, **kw)


def case_plan(case, rtol, **kw):
    return make_plan(case_scene(case, rtol, **kw))


@pytest.mark.parametrize("rtol", [1e-3, 1e-6, 1e-9])
def test_the_fine_twin_is_at_least_twice_as_accurate(rtol):
    """The estimate 2 |fine - run| bounds the run's error if the fine twin's error is at most half of it: checked
    against the reference on every finite case of the table, at the first run's own tolerance."""
    for case in FINITE_CASES:
        plan = case_plan(case, rtol)
        assert plan.point_methods == ("dop853",), plan.point_methods
        run = _adaptive_runner(plan, "dop853", sweep.scene.scene.DEFAULT_ATOL["xi_inf"])
        x, fine, _, status, _ = run(np.array([0]), np.array([plan.ctrl_tol]), plan.step[:1])
        exact = reference(case.name)
        floor = REFERENCE_REL * exact + sweep.scene.scene.DEFAULT_ATOL["xi_inf"]
        assert status[0] == Status.OK, case.name
        assert abs(fine[0] - exact) <= max(0.5 * abs(x[0] - exact), floor), case.name


def test_results_do_not_depend_on_the_lane_or_its_neighbours():
    """Every lane keeps its own step and accept/reject decisions: the same runs in another order, and alone, give
    bitwise the same numbers."""
    s = sweep.Scene(protocol="stop", params=sweep.FrictionParams(A=0.007, m1=0.0125, m2=0.0033, D0=0.7e-6),
                    K_over_M=np.logspace(2, 7, 9), V=np.logspace(-8, -3, 7), model="quasistatic", rtol=1e-7)
    plan = make_plan(s)
    run = _adaptive_runner(plan, "dop853", s.atol["xi_inf"])
    points = np.flatnonzero(plan.finite)
    tols = np.full(points.size, plan.ctrl_tol)
    forward = run(points, tols, plan.step[points])
    order = np.random.default_rng(7).permutation(points.size)
    shuffled = run(points[order], tols[order], plan.step[points[order]])
    alone = run(points[:1], tols[:1], plan.step[points[:1]])
    for a, b, c in zip(forward, shuffled, alone):
        np.testing.assert_array_equal(a[order], b)
        np.testing.assert_array_equal(a[:1], c)


def test_a_run_past_max_steps_is_flagged_not_silent():
    """A point that needs more attempts than max_steps comes back max_steps, with no value."""
    case = next(c for c in FINITE_CASES if c.name == "s2_KM1e4_V100um_corner")
    s = case_scene(case, 1e-8, max_steps=5)
    out = sweep.protocols.stop.chunk.execute(s, make_plan(s), progress=False)
    assert out.status[0] == Status.MAX_STEPS and np.isnan(out.xi_inf[0])


def test_branch_free_log2_is_good_enough_for_a_step_factor():
    """The controller's log2 (bits and a quadratic, so that the lane loop vectorises) is within 0.006 of log2 over
    the whole positive normal range: a step factor err^(-1/6) off by 2^(0.006/6) = 0.07 %."""
    x = np.logspace(-300, 300, 20001)
    approx = np.array([_log2_approx(v) for v in x])
    assert np.max(np.abs(approx - np.log2(x))) < 0.006


def test_halving_the_mesh_shows_eighth_order():
    """dop853 in the lanes is of order 8: on the same mesh halved (the fine twin) the error falls by ~2^8 where
    the steps are accuracy-limited. Loose control tolerances keep both errors far above the reference's floor;
    the observed order log2(|run error| / |twin error|), median over the finite cases, lies within 1.5 of 8."""
    orders = []
    for case in FINITE_CASES:
        plan = case_plan(case, 1e-2)
        run = _adaptive_runner(plan, "dop853", sweep.scene.scene.DEFAULT_ATOL["xi_inf"])
        x, fine, _, status, _ = run(np.array([0]), np.array([1e-2]), plan.step[:1])
        exact = reference(case.name)
        e_run, e_fine = abs(x[0] - exact), abs(fine[0] - exact)
        if status[0] == Status.OK and e_fine > 1e3 * REFERENCE_REL * exact:
            orders.append(np.log2(e_run / e_fine))
    assert len(orders) >= 5, orders
    assert abs(np.median(orders) - 8.0) <= 1.5, sorted(orders)


def test_auto_leaves_the_quasistatic_points_bit_for_bit_as_the_quasistatic_model():
    """model="auto" carries the first-order inertial correction in the same lanes (its own stage loops after each
    stage's (x, s) loop, docs/design.md "Adaptive lanes"): the (x, s) arithmetic, and so xi_inf, its estimate and the
    steps of every point that auto leaves quasi-static, are those of model="quasistatic" bit for bit; the correction
    itself is checked against the inertial solution in tests/protocols/test_stop_inertial.py."""
    base = sweep.default_scene()
    scene = sweep.Scene(protocol="stop", params=base.params, K_over_M=np.geomspace(1e3, 1e6, 9),
                        V=np.geomspace(1e-7, 1e-4, 7), model="auto", rtol=1e-6)
    auto = sweep.run_sweep(scene, progress=False)
    quasi = sweep.run_sweep(sweep.Scene(protocol="stop", params=base.params, K_over_M=scene.K_over_M, V=scene.V,
                                        model="quasistatic", rtol=1e-6), progress=False)
    kept = auto["model"].values == 0
    assert kept.sum() >= 50  # the default parameters leave most points quasi-static
    assert np.isfinite(auto["model_error"].values[kept]).all()
    for name in ("xi_inf", "xi_inf_error", "steps", "status"):
        np.testing.assert_array_equal(auto[name].values[kept], quasi[name].values[kept], err_msg=name)


def test_a_sweep_compiles_each_adaptive_kernel_once():
    """The chunks of every backend path (one chunk at a time, side by side on 2 threads, the reruns of the tolerance
    ladder) hand the compiled kernels arrays of one type: a read-only array (the chunk layout's are) made numba
    compile the adaptive lanes a second time, ~20 s on a cold cache."""
    import numba

    from sweep.integrate.lanes_adaptive import adaptive_lane_kernels
    from sweep.integrate.tolerance_ladder import _judge
    from sweep.protocols.stop.model_choice import _route

    d = sweep.default_scene()
    scene = dataclasses.replace(d, K_over_M=d.K_over_M[::16], V=d.V[::8], rtol=1e-3)  # 13 x 13
    threads = numba.get_num_threads()
    try:
        for n in sorted({1, min(2, numba.config.NUMBA_NUM_THREADS)}):
            numba.set_num_threads(n)
            sweep.run_sweep(scene, progress=False, chunk_size=8)  # 22 chunks: side by side on 2 threads
    finally:
        numba.set_num_threads(threads)
    kernels = {"relax_runs (auto)": adaptive_lane_kernels(sweep.plan.plan.LANES_METHOD, True)[0], "_judge": _judge,
               "_route": _route}
    assert {name: len(k.signatures) for name, k in kernels.items()} == dict.fromkeys(kernels, 1)
    # the warm-up (sweep.protocols.stop.chunk.warm_up, the command line's) and the dask workers pass writable arrays
    readonly = {name: str(k.signatures[0]) for name, k in kernels.items() if "readonly" in str(k.signatures[0])}
    assert not readonly, readonly


INLINED_PROBE = """
import re
import numpy as np
from sweep.integrate.lanes import LanePoints
from sweep.integrate.lanes_adaptive import AdaptiveOutputs, AdaptiveRuns, _rates, adaptive_lane_kernels
relax_runs = adaptive_lane_kernels("dop853", True)[0]
cells = dict(zip(relax_runs.py_func.__code__.co_freevars, relax_runs.py_func.__closure__))
n = 3
points = LanePoints(*(np.full(n, v) for v in (1e3, 0.5, 0.3, 1.0, 0.01)))
runs = AdaptiveRuns(np.arange(n), np.full(n, 1e-6), np.full(n, 1e-3), 1e-12, 100_000)
relax_runs(points, runs, np.arange(n), AdaptiveOutputs.empty(n, True))
ir = "\\n".join(relax_runs.inspect_llvm().values())
calls = re.findall(r"call [^@]*@\\S*(?:rate_call|attempt_all)", ir)
print(len(calls), len(re.findall(r"@llvm\\.sqrt\\.v\\d+f64\\(", ir)))
print(*(len(f.signatures) for f in (cells["attempt_all"].cell_contents, *_rates(np.float64))))
"""


@pytest.mark.slow
def test_the_attempt_and_its_right_hand_sides_are_inlined_by_llvm(tmp_path):
    """The generated attempt and the right-hand sides it calls are compiled by numba once each and inlined by LLVM
    (``forceinline``, lanes_adaptive._rates), not copied into relax_runs in numba's IR, which took ~2/3 of a cold
    default run (benchmarks/cold_start.py): relax_runs compiled in a new process on an empty cache (its LLVM IR is
    kept only then) calls none of them, and its stage loops are vectorised (vector square roots, one per stage of
    the run and of its twin, as with numba's inlining); numba compiled each of them once, on its own."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", INLINED_PROBE], env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    inlined, compiled = out.stdout.splitlines()[-2:]
    calls, vector_sqrt = map(int, inlined.split())
    assert compiled.split() == ["1", "1", "1"]  # attempt_all, rate, correction_rate: each compiled by numba itself
    assert calls == 0
    assert vector_sqrt >= 2 * 12  # dop853: 12 evaluations a step, the run's and its twin's
