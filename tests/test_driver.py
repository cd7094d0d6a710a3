"""The Python API: simulate, Result, errors, and that a run cut into pieces is the same
run bit for bit (the foundation of checkpoint/resume)."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import rodjit
from rodjit.records.result import MemorySink
from rodjit.driver.run import Run
from rodjit.stepping import layout as L

CASES = [
    {"time.t_end": 3.0},
    {"time.t_end": 2.0, "rod.mu": 5.0, "rod.gamma": 1e-3, "time.integrator": "semi-implicit",
     "rod.N": 12, "output.diagnostics_interval": 0.0007},
    {"time.t_end": 2.0, "rod.mu": 5.0, "rod.gamma": 1e-3, "rod.N": 12},
]


def one_shot(cfg):
    return rodjit.simulate(cfg)


def in_pieces(cfg, rng):
    run = Run(cfg, snapshot_capacity=3, diag_capacity=5, event_capacity=1)
    sink = MemorySink()
    run.start(sink)
    while run.advance(sink, max_steps=int(rng.integers(1, 40))) != L.DONE:
        pass
    return sink.result(run)


@pytest.mark.parametrize("over", CASES)
def test_a_run_cut_into_pieces_is_bitwise_the_same(over, rng):
    cfg = rodjit.Config().override(over)
    a, b = one_shot(cfg), in_pieces(cfg, rng)
    assert np.array_equal(a.u_final, b.u_final) and np.array_equal(a.v_final, b.v_final)
    assert np.array_equal(a.u, b.u) and np.array_equal(a.t, b.t)
    for name in a.diagnostics:
        assert np.array_equal(a.diagnostics[name], b.diagnostics[name]), name
    for name in a.bounces:
        assert np.array_equal(a.bounces[name], b.bounces[name], equal_nan=True), name
    assert a.stats["steps"] == b.stats["steps"]


def test_checkpoint_restores_bitwise(rng):
    cfg = rodjit.Config().override({"time.t_end": 2.0, "rod.mu": 1.0})
    full = one_shot(cfg)
    run = Run(cfg)
    sink = MemorySink()
    run.start(sink)
    for _ in range(3):
        run.advance(sink, max_steps=500)
    resumed = Run.from_checkpoint(cfg, run.checkpoint())
    while resumed.advance(sink) != L.DONE:
        pass
    res = sink.result(resumed)
    assert np.array_equal(res.u_final, full.u_final) and np.array_equal(res.u, full.u)
    assert np.array_equal(res.diagnostics["energy_total"], full.diagnostics["energy_total"])


def test_output_times_are_exact_grid_points():
    res = rodjit.simulate(rodjit.Config().override({"time.t_end": 1.0,
                                                    "output.snapshot_interval": 0.003,
                                                    "output.diagnostics_interval": 0.001}))
    k = np.arange(res.t.size)
    assert np.array_equal(res.t, k * 0.003)
    assert np.array_equal(res.diagnostics["t"], np.arange(1001) * 0.001)


def test_result_contents():
    res = rodjit.simulate(rodjit.Config().override({"time.t_end": 1.0}))
    assert res.x.shape == (6,) and res.u.shape == (res.t.size, 6) and res.v.shape == res.u.shape
    assert set(res.diagnostics) == set(L.DIAG_COLUMNS)
    assert set(res.bounces) == set(L.BOUNCE_ROW_COLUMNS) | {"open"}
    assert set(res.episodes) == {"t_start", "t_end"}
    for key in ("steps", "rejected_steps", "wall_time", "compile_time", "run_time",
                "node_steps_per_second"):
        assert key in res.stats
    assert res.stats["steps"] > 0 and res.stats["node_steps_per_second"] > 0
    assert res.status == "completed" and res.t_final == 1.0
    d = res.diagnostics
    parts = sum(d[k] for k in ("energy_kinetic", "energy_stretch", "energy_bend",
                               "energy_floor", "energy_gravity"))
    assert np.allclose(parts, d["energy_total"], rtol=0, atol=1e-12)


def test_initial_profiles_are_used_and_checked():
    cfg = rodjit.Config().override({"time.t_end": 0.01})
    x = np.linspace(0, 1, 6)
    res = rodjit.simulate(cfg, u0=2.0 + 1.1 * x, v0=np.full(6, -1.0))
    assert res.u[0] == pytest.approx(2.0 + 1.1 * x) and res.diagnostics["cm_velocity"][0] == pytest.approx(-1.0)
    with pytest.raises(ValueError, match=r"u0 must be a 1-D array of length rod\.N \+ 1 = 6"):
        rodjit.simulate(cfg, u0=np.ones(5))
    with pytest.raises(ValueError, match=r"v0\[2\] = nan is not finite"):
        rodjit.simulate(cfg, v0=[0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ValueError, match=r"u0 is not admissible: strain of segment 2 is -1\.0, must be > -1\.0"):
        rodjit.simulate(cfg, u0=[1, 1.2, 1.4, 1.4, 1.6, 1.8])
    with pytest.raises(ValueError, match=r"bottom height u0\[0\] = -0\.06, must be > -0\.05"):
        rodjit.simulate(cfg, u0=-0.06 + x)
    with pytest.raises(TypeError, match="rodjit.Config"):
        rodjit.simulate({"rod.N": 5})


def test_same_results_with_jit_disabled():
    """The kernels are plain Python too: a short run in a process with NUMBA_DISABLE_JIT=1
    gives the same numbers as the compiled run."""
    over = {"time.t_end": 0.6, "rod.N": 4, "rod.mu": 1.0, "rod.gamma": 1e-3,
            "time.integrator": "verlet", "time.control": "cfl",
            "output.snapshot_interval": 0.1, "output.diagnostics_interval": 0.05}
    code = ("import json, rodjit; r = rodjit.simulate(rodjit.Config().override(%r)); "
            "print(json.dumps([list(r.u_final), r.stats['steps'], list(r.bounces['t_impact'])]))"
            % over)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True, timeout=600)
    u, steps, t_impact = json.loads(out.stdout)
    res = rodjit.simulate(rodjit.Config().override(over))
    assert steps == res.stats["steps"]
    assert np.allclose(u, res.u_final, rtol=0, atol=1e-13)
    assert np.allclose(t_impact, res.bounces["t_impact"], rtol=0, atol=1e-13)


def test_a_step_loop_that_stops_advancing_time_fails_in_one_line():
    """Steps far below the resolution of t (here: t moved to 1e20, where one ulp is 16384,
    with adaptive steps of ~1e-5) leave t unchanged: the call that took them fails with a
    SimulationError naming t and the step, instead of being called again for ever."""
    from conftest import quiet
    from rodjit.driver.run import SimulationError

    run = Run(quiet(**{"time.t_end": 1.0}))
    sink = MemorySink()
    run.start(sink)
    run.arrays.clock[L.T], run.arrays.clock[L.T_END] = 1e20, 2e20
    with pytest.raises(SimulationError) as caught:
        for _ in range(3):
            run.advance(sink, max_steps=50)
    message = str(caught.value)
    assert message.startswith("time stopped advancing at t = 1e+20: 50 steps of dt = ")
    assert "resolution of t there is 1.64e+04" in message and "\n" not in message
    assert run.t == 1e20 and run.steps == 50


def test_a_later_run_of_the_same_types_reuses_the_compiled_entries(monkeypatch, jit_only):
    """The compiled entry points of ``start`` and ``advance`` (``_jit.Kernel.entry_point``)
    are looked up once per process and argument types: a later run of other values but
    the same types reuses them, a run of other types gets its own, and the results are
    the same bit for bit either way."""
    import rodjit.driver.run as run_module
    from rodjit._jit import Kernel

    cfg = rodjit.Config().override({"time.t_end": 0.05, "rod.mu": 2.0})
    rodjit.simulate(cfg)                        # compiled or loaded in this process
    looked_up = []
    original = Kernel.entry_point

    def spy(self, args):
        looked_up.append(self.__name__)
        return original(self, args)

    monkeypatch.setattr(Kernel, "entry_point", spy)
    warm = rodjit.simulate(cfg.override({"rod.mu": 3.0}))
    assert looked_up == []
    kept = dict(run_module._COMPILED)
    monkeypatch.setattr(run_module, "_COMPILED", {})     # as in a fresh process
    cold = rodjit.simulate(cfg.override({"rod.mu": 3.0}))
    assert looked_up == ["start", "advance"]
    # looked up again, the entries are the compiled functions Numba already held
    assert run_module._COMPILED and all(e is kept[k] for k, e in run_module._COMPILED.items())
    assert np.array_equal(warm.u, cold.u) and np.array_equal(warm.v, cold.v)
    assert warm.stats["steps"] == cold.stats["steps"]
    looked_up.clear()
    rodjit.simulate(cfg.override({"time.integrator": "dp54"}))     # other scheme types
    assert looked_up == ["start", "advance"]
    keys = run_module._COMPILED
    assert len(keys) == 4 and {name for name, _ in keys} == {"start", "advance"}
    assert len({k[0][0] for _, k in keys}) == 2
    # a run resumed from a checkpoint compiles ``advance`` only
    monkeypatch.setattr(run_module, "_COMPILED", {})
    looked_up.clear()
    run = Run(cfg)
    sink = MemorySink()
    run.start(sink)
    ck = run.checkpoint()
    looked_up.clear()
    run_module._COMPILED.clear()
    resumed = Run.from_checkpoint(cfg, ck)
    resumed.start(None)
    assert looked_up == ["advance"]
    while resumed.advance(sink) != L.DONE:
        pass
    assert np.array_equal(resumed.u, rodjit.simulate(cfg).u_final)


def test_a_first_run_counts_its_compile_time_once(monkeypatch, jit_only):
    """``start``'s compile was counted by ``_entry`` and again by ``start``'s own clock
    around it, so a first run reported twice its compile time."""
    import time

    import rodjit.driver.run as run_module
    from rodjit._jit import Kernel

    cfg = rodjit.Config().override({"time.t_end": 0.05, "rod.mu": 2.0})
    rodjit.simulate(cfg)                        # compiled or loaded in this process
    original = Kernel.entry_point
    slow = 0.4

    def slow_compile(self, args):               # a compile of ``slow`` seconds
        if self.__name__ == "start":
            time.sleep(slow)
        return original(self, args)

    monkeypatch.setattr(Kernel, "entry_point", slow_compile)
    monkeypatch.setattr(run_module, "_COMPILED", {})     # as in a fresh process
    run = Run(cfg)
    run.start(None)
    assert slow <= run.compile_time < 1.5 * slow, run.compile_time


def test_a_block_is_finite_exactly_when_every_value_is():
    """The drain's test of a block's diagnostics (a sum, then each value only where the
    sum is not finite): finite values whose sum overflows pass, any inf or NaN fails."""
    from rodjit.driver.run import _all_finite

    assert _all_finite(np.full((3, 4), 1e308)) and _all_finite(np.zeros((0, 9)))
    for bad in (np.inf, -np.inf, np.nan):
        rows = np.ones((3, 4))
        rows[1, 2] = bad
        assert not _all_finite(rows)
    rows = np.ones((2, 3))
    rows[0, 0], rows[1, 1] = np.inf, -np.inf        # a NaN sum
    assert not _all_finite(rows)
