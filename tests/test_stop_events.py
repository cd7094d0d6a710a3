"""Runs that end before ``time.t_end``: after k bounces (``time.stop_after_bounces``) or at
rest (``time.stop_at_rest``), at the same step whatever the engine and however the run is
cut into calls, with their last rows at the stop."""
from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import rodjit
from rodjit.analysis import lift_energy
from rodjit.config import ConfigError
from rodjit.records.sink import Sink
from conftest import simulated_sweeps

MU0 = rodjit.load_preset("paper-mu0").override({"output.snapshot_interval": 0.01})
STICKY = rodjit.load_preset("paper-mu100").override({"rod.mu": 20.0, "time.t_end": 4.0})


def _prefix_equal(short, long) -> None:
    """The stopped run's rows before its last are the uninterrupted run's, bit for bit."""
    n = short.diagnostics["t"].size - 1
    for name in ("t", "energy_total", "dissipated", "u_bottom", "cm_velocity"):
        assert np.array_equal(short.diagnostics[name][:n], long.diagnostics[name][:n]), name
    m = short.t.size - 1
    assert np.array_equal(short.u[:m], long.u[:m])


def test_a_run_ends_once_its_kth_bounce_is_over():
    r = rodjit.simulate(MU0.override({"time.stop_after_bounces": 2}))
    full = rodjit.simulate(MU0)
    b = r.bounces
    assert r.status == "completed" and r.t_final < MU0.time.t_end
    assert b["t_impact"].size == 2 and not np.asarray(b["open"]).any()
    # over at the apex of the flight after the second: the rod rises no more
    assert full.bounces["t_release"][1] < r.t_final < full.bounces["t_impact"][2]
    assert np.array_equal(b["restitution"], full.bounces["restitution"][:2])
    _prefix_equal(r, full)
    # its last rows are the state at the stop
    assert r.diagnostics["t"][-1] == r.t_final == r.t[-1]
    assert "ended after 2 bounces (time.stop_after_bounces = 2)" in r.report()


def test_a_run_ends_at_rest_once_its_energy_is_below_the_lift_off_energy():
    """μ = 20: the first contact never ends; the run stops at the first step whose energy
    is below the lift-off energy, and the uninterrupted run confirms that the bottom
    stays on the floor from then on."""
    r = rodjit.simulate(STICKY.override({"time.stop_at_rest": True}))
    full = rodjit.simulate(STICKY)
    e_lift = lift_energy(STICKY)
    d = r.diagnostics
    assert r.t_final < 1.0 and d["t"][-1] == r.t_final
    assert d["energy_total"][-1] < e_lift
    after = full.diagnostics["t"] >= r.t_final
    assert np.all(full.diagnostics["u_bottom"][after] < 0)
    assert np.all(full.diagnostics["energy_total"][after] < e_lift)
    _prefix_equal(r, full)
    assert "ended at rest" in r.report()
    # off by default, and without a fall nothing can come to rest
    assert full.t_final == STICKY.time.t_end
    with pytest.raises(ConfigError, match="time.stop_at_rest needs gravity.g < 0"):
        STICKY.override({"time.stop_at_rest": True, "gravity.g": 0.0})
    with pytest.raises(ConfigError, match=r"time.stop_after_bounces = -1 is out of range"):
        MU0.override({"time.stop_after_bounces": -1})


class _Keep(Sink):
    def __init__(self):
        self.t = []

    def diagnostics(self, rows):
        self.t.extend(rows[:, 0].tolist())


@pytest.mark.parametrize("changes", [{"time.stop_after_bounces": 3},
                                     {"time.stop_at_rest": True}])
def test_the_stop_is_the_same_in_calls_of_any_size_and_on_the_batch_engine(changes):
    from rodjit.driver.run import Run
    from rodjit.stepping import layout as L

    cfg = (MU0 if "time.stop_after_bounces" in changes else STICKY).override(changes)
    whole = rodjit.simulate(cfg)
    run, sink = Run(cfg), _Keep()
    while run.advance(sink, max_steps=3) != L.DONE:
        pass
    assert run.arrays.clock[L.T] == whole.t_final
    assert sink.t == whole.diagnostics["t"].tolist()
    table = rodjit.sweep(cfg, {"rod.N": [cfg.rod.N]}, scheduler="inline")
    assert table["t_final"][0] == whole.t_final
    assert table["steps"][0] == whole.stats["steps"]


def test_a_stopped_run_file_is_complete(tmp_path):
    path = tmp_path / "run.h5"
    s = rodjit.run_to_file(MU0.override({"time.stop_after_bounces": 1}), path)
    assert s.status == "completed" and s.t < MU0.time.t_end
    back = rodjit.load_file(path)
    assert back.t_final == s.t and back.bounces["t_impact"].size == 1
    assert "ended after 1 bounce " in back.report()
    with pytest.raises(ValueError, match="complete"):
        rodjit.resume_file(path)


GPU_SETUP = """
cfg = rodjit.load_preset("paper-mu100").override({"time.t_end": 3.0, "time.stop_at_rest": True,
                                                  "time.integrator": "energy"})
"""


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("numba_cuda") is None,
                    reason="the GPU engine's extra is not installed")
def test_the_gpu_engine_stops_where_the_cpu_does():
    got = simulated_sweeps(GPU_SETUP, {"rod.mu": [20.0, 100.0]},
                           ("t_final", "steps", "n_bounces"))
    gpu, cpu = got["t_final"]
    assert gpu == pytest.approx(cpu, rel=1e-9) and gpu[0] < gpu[1] < 3.0
    assert got["steps"][0] == got["steps"][1]
