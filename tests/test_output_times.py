"""Snapshots at listed times (``output.times``, SciPy's ``t_eval``): the same rows as the
interval grid where the two share a time, on every path a run takes (a single run, calls
of any size, a run file and its resume, the batch engine, the GPU engine's simulator)."""
from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rodjit
from rodjit.config import ConfigError
from rodjit.config.errors import ModelWarning
from conftest import simulated_sweeps

ROOT = Path(__file__).resolve().parent.parent
# paper-mu100 for 0.6 s: the fall, the first impact (at 0.452 s) and its release (0.464 s)
MU100 = rodjit.load_preset("paper-mu100").override({"time.t_end": 0.6})
# binary fractions: k/256 is exact, so the interval grid's times equal the listed ones;
# three of them in the contact
STEP = 1 / 256
TIMES = [0.0625, 0.125, 0.25, 0.453125, 0.45703125, 0.4609375, 0.5]
ODD = [0.0, 0.01, 0.123456789, 0.4567, 0.46, 0.6]


def _at(result, times):
    """The rows of ``result``'s snapshots at ``times`` (each present exactly)."""
    index = [result.t.tolist().index(t) for t in times]
    return result.u[index], result.v[index]


@pytest.mark.parametrize("integrator", ["radau5", "dop853"])
def test_a_dense_output_gives_the_interval_grids_rows_at_the_listed_times(integrator):
    """Under a dense output the outputs cost no steps: the listed times' rows are the
    interval grid's rows at those times, bit for bit, and nothing else changes."""
    cfg = MU100.override({"time.integrator": integrator})
    grid = rodjit.simulate(cfg.override({"output.snapshot_interval": STEP}))
    listed = rodjit.simulate(cfg.override({"output.times": TIMES}))
    assert listed.t.tolist() == TIMES            # no row at t0 or t_end unless listed
    u, v = _at(grid, TIMES)
    assert np.array_equal(listed.u, u) and np.array_equal(listed.v, v)
    assert listed.stats["steps"] == grid.stats["steps"]
    for name in ("t", "energy_total", "dissipated", "u_bottom"):
        assert np.array_equal(listed.diagnostics[name], grid.diagnostics[name]), name
    assert np.array_equal(listed.bounces["restitution"], grid.bounces["restitution"])


def test_a_landing_integrator_lands_on_each_listed_time():
    """``energy`` always lands: its steps end on the listed times (one list equal to the
    interval grid gives that grid's run to the bit), and off-grid times are met exactly,
    with the state of a tight reference there."""
    cfg = MU100.override({"time.integrator": "energy"})
    grid = rodjit.simulate(cfg.override({"output.snapshot_interval": STEP}))
    same = rodjit.simulate(cfg.override({"output.times": grid.t.tolist()}))
    assert np.array_equal(same.t, grid.t) and np.array_equal(same.u, grid.u)
    assert same.stats["steps"] == grid.stats["steps"]
    listed = rodjit.simulate(cfg.override({"output.times": ODD}))
    assert listed.t.tolist() == ODD
    ref = rodjit.simulate(MU100.override({"time.integrator": "radau5", "time.rtol": 1e-10,
                                          "time.atol": 1e-10, "output.times": ODD}))
    assert np.max(np.abs(listed.u - ref.u)) < 1e-6          # 2e-8 here
    assert np.max(np.abs(listed.v - ref.v)) < 1e-4          # 3e-6
    assert np.array_equal(listed.u[0], ref.u[0])          # t = 0: the initial state


def test_the_listed_times_are_the_same_in_calls_of_any_size():
    from rodjit.driver.run import Run
    from rodjit.records.sink import Sink
    from rodjit.stepping import layout as L

    class Keep(Sink):
        def __init__(self):
            self.t, self.u = [], []

        def snapshots(self, t, step, u, v):
            self.t.extend(t.tolist())
            self.u.extend(u.tolist())

    cfg = MU100.override({"time.integrator": "dop853", "output.times": TIMES})
    whole = rodjit.simulate(cfg)
    run, sink = Run(cfg, snapshot_capacity=1), Keep()
    run.start(sink)
    while run.advance(sink, max_steps=3) != L.DONE:
        pass
    assert sink.t == TIMES and np.array_equal(np.array(sink.u), whole.u)


def test_a_run_file_keeps_its_listed_times_and_resumes_on_them(tmp_path):
    cfg = MU100.override({"time.integrator": "energy", "output.times": TIMES})
    whole = rodjit.simulate(cfg)
    path = tmp_path / "run.h5"
    with pytest.warns(ModelWarning, match=r"output.times lists 5 times after "
                                                 r"time.t_end = 0.2 \(from 0.25\)"):
        rodjit.run_to_file(cfg, path, t_end=0.2)
    rodjit.resume_file(path, t_end=0.6)
    back = rodjit.load_file(path)
    assert back.config.output.times == tuple(TIMES)
    assert back.t.tolist() == TIMES and np.array_equal(back.u, whole.u)


def test_the_batch_engine_steps_as_the_run_does():
    """``energy`` lands on the listed times, so they change its steps: a sweep point takes
    the single run's steps with them, not those of the interval grid."""
    cfg = MU100.override({"time.integrator": "energy", "output.times": ODD})
    whole = rodjit.simulate(cfg)
    plain = rodjit.simulate(cfg.override({"output.times": []}))
    assert whole.stats["steps"] != plain.stats["steps"]
    table = rodjit.sweep(cfg, {"rod.mu": [cfg.rod.mu]}, scheduler="inline", progress=False)
    assert table["steps"][0] == whole.stats["steps"]
    assert table["restitution_first"][0] == whole.impact()["restitution_first"] > 0


@pytest.mark.parametrize("value, message", [
    ([0.2, 0.1], r"output.times\[1\] = 0.1 is out of range: not after output.times\[0\]"),
    ([-0.1], r"output.times\[0\] = -0.1 is out of range"),
    ([0.1, float("nan")], r"output.times\[1\] = nan is out of range"),
    ("0.1,x", r"output.times = '0.1,x' is not a list of numbers"),
])
def test_bad_times_are_refused_naming_the_entry(value, message):
    with pytest.raises(ConfigError, match=message):
        MU100.override({"output.times": value})


def test_a_sweep_takes_one_list_for_all_its_points():
    """The list is one value of the base configuration: a grid over it is refused, in one
    line that says where to set it."""
    with pytest.raises(ValueError, match=r"grid output.times: a list of times is one value "
                                         r"for the whole sweep, not a swept key; set it "
                                         r"in the base configuration"):
        rodjit.sweep(MU100, {"output.times": [[0.1], [0.2]]}, scheduler="inline")


def test_times_from_toml_and_the_command_line(tmp_path):
    cfg = rodjit.Config.from_toml_string(MU100.override({"output.times": TIMES}).to_toml())
    assert cfg.output.times == tuple(TIMES)
    assert MU100.override({"output.times": "0.1, 0.2"}).output.times == (0.1, 0.2)
    assert MU100.override({"output.times": np.array([0.1, 0.2])}).output.times == (0.1, 0.2)
    with pytest.raises(ValueError, match=r"output.times\[0\] = 0.0125 is not a whole number "
                                         r"of steps of time.dt = 0.01"):
        rodjit.simulate(MU100.override({"time.dt": 0.01, "time.integrator": "energy",
                                        "output.times": [0.0125]}))
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = tmp_path / "r.h5"
    p = subprocess.run([sys.executable, "-m", "rodjit", "run", "paper-mu100", "-o", str(out),
                        "--set", "time.t_end=0.4", "--set", "output.times=[0.1,0.2]"],
                       capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0, p.stderr
    assert rodjit.load_file(out).t.tolist() == [0.1, 0.2]
    p = subprocess.run([sys.executable, "-m", "rodjit", "run", "paper-mu100", "--dry-run",
                        "--set", "time.t_end=0.4", "--set", "output.times=0.3,0.2"],
                       capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 2
    assert p.stderr.strip().splitlines()[-1].startswith("Error: output.times[1] = 0.2 is out")


GPU_SETUP = """
cfg = rodjit.load_preset("paper-mu100").override({
    "time.t_end": 0.6, "time.integrator": "energy",
    "output.times": [0.0, 0.01, 0.123456789, 0.4567, 0.46, 0.6]})
"""


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("numba_cuda") is None,
                    reason="the GPU engine's extra is not installed")
def test_the_gpu_engine_lands_on_the_listed_times_as_the_cpu_does():
    got = simulated_sweeps(GPU_SETUP, {"rod.mu": [100.0, 150.0]},
                           ("steps", "restitution_first"))
    gpu, cpu = got["steps"]
    assert gpu == cpu
    gpu, cpu = got["restitution_first"]
    assert gpu == pytest.approx(cpu, rel=1e-9) and min(gpu) > 0
