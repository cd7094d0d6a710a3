"""Observers (``rodjit.observers``, ``output.observer``): compiled code of one's own that sees
every accepted step, its values on the Result, in run files, in sweep columns of every
engine, and its events.  The observer is ``tests/step_observer.py``, registered from
outside the package as a user registers one."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rodjit
from rodjit.observers import Observer, observer_kernel, register

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import step_observer  # noqa: E402  (registers "step-count" and "step-count-40")

from conftest import simulated_sweeps  # noqa: E402


def _cfg(**over):
    flat = {"time.t_end": 0.6, "output.observer": "step-count"}
    flat.update(over)
    return rodjit.load_preset("paper-mu100").override(flat)


@pytest.fixture(scope="module")
def observed_run():
    return rodjit.simulate(_cfg())


def test_the_observer_sees_every_accepted_step(observed_run):
    r = observed_run
    assert r.observed["observed_steps"] == r.stats["steps"] > 0
    assert r.observed["t_last"] == r.t_final == 0.6
    # every snapshot row of radau5 under landing is a step's end, but its dense output
    # interpolates: the top's largest height at a step's end bounds the snapshots' from
    # below only to the interpolation error
    assert r.observed["top_max"] >= r.u[:, -1].max() - 1e-6
    assert r.observed["top_max"] >= r.u[0, -1]
    # the floor law reaches the observer: its largest stress at a step's end is at most the
    # run's, whose bounce extremes are searched inside the steps too, and close to it
    peak = float(np.max(r.bounces["max_floor_force"]))
    assert 0.9 * peak < r.observed["floor_max"] <= peak


def test_an_observer_changes_no_bit_of_the_run(observed_run):
    plain = rodjit.simulate(_cfg(**{"output.observer": "none"}))
    assert plain.observed == {}
    assert np.array_equal(plain.u, observed_run.u)
    assert np.array_equal(plain.v, observed_run.v)
    for name, col in plain.diagnostics.items():
        assert np.array_equal(col, observed_run.diagnostics[name]), name
    assert plain.stats["steps"] == observed_run.stats["steps"]


def test_an_observer_ends_the_run():
    r = rodjit.simulate(_cfg(**{"output.observer": "step-count-40"}))
    assert r.status == "completed"
    assert r.stats["steps"] == r.observed["observed_steps"] == 40
    assert r.t_final == r.observed["t_last"] < 0.6
    assert r.t[-1] == r.t_final          # its last snapshot at the end, as at t_end


def test_values_in_the_run_file_and_after_a_resume(tmp_path, observed_run):
    path = tmp_path / "r.h5"
    rodjit.run_to_file(_cfg(**{"time.t_end": 0.455}), path)
    first = rodjit.load_file(path).observed
    rodjit.resume_file(path, t_end=0.6)
    back = rodjit.load_file(path)
    # the state travels in the checkpoint: the resumed run goes on counting, every step
    # of both parts once (the first part's steps land on its end, so the count differs
    # from an uninterrupted run's)
    assert 0 < first["observed_steps"] < back.observed["observed_steps"]
    assert back.observed["observed_steps"] == back.stats["steps"]
    assert back.observed["t_last"] == 0.6
    assert back.observed["top_max"] >= first["top_max"]
    assert "observer step-count" in rodjit.load_file(path).report()


def test_a_file_names_its_observer_columns_for_readers_without_it(tmp_path):
    path = tmp_path / "s.h5"
    rodjit.sweep(_cfg(), {"rod.mu": [100.0, 150.0]}, output=path, scheduler="inline",
                 progress=False)
    # another process, which never imported the observer, reads the columns
    script = (f"import json, rodjit; t = rodjit.load_sweep({str(path)!r}); "
              f"print(json.dumps([t['observed_steps'].tolist(), t['steps'].tolist()]))")
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       timeout=300, cwd=path.parent)
    assert p.returncode == 0, p.stderr[-2000:]
    seen, steps = json.loads(p.stdout.strip().splitlines()[-1])
    assert seen == steps and min(steps) > 0


def test_sweep_columns_equal_simulate_inline_and_in_a_pool(tmp_path):
    grid = {"rod.mu": [100.0, 150.0]}
    cfg = _cfg()
    alone = [rodjit.simulate(cfg.override({"rod.mu": mu})).observed for mu in grid["rod.mu"]]
    inline = rodjit.sweep(cfg, grid, scheduler="inline", progress=False)
    pool = rodjit.sweep(cfg, grid, jobs=2, output=tmp_path / "p.h5", progress=False)
    back = rodjit.load_sweep(tmp_path / "p.h5")
    for table in (inline, pool, back):
        for name in step_observer.COLUMNS:
            assert table[name].tolist() == [a[name] for a in alone], name
    assert inline["observed_steps"].tolist() == inline["steps"].tolist()
    head = back.report().splitlines()[0].split()      # rodjit info's table shows them
    assert head[-4:] == list(step_observer.COLUMNS)


def test_a_point_with_a_run_file_gives_the_same_columns(tmp_path):
    grid = {"rod.mu": [100.0]}
    a = rodjit.sweep(_cfg(), grid, scheduler="inline", progress=False)
    b = rodjit.sweep(_cfg(), grid, scheduler="inline", save_runs=tmp_path / "runs",
                     progress=False)
    for name in step_observer.COLUMNS:
        assert a[name].tolist() == b[name].tolist(), name


def test_refusals_are_one_line():
    with pytest.raises(ValueError, match=r"output.observer = 'nope' is not a registered "
                                         r"observer; choose one of \[.*'step-count'"):
        rodjit.simulate(_cfg(**{"output.observer": "nope"}))
    with pytest.raises(ValueError, match="grid output.observer: the observer gives"):
        rodjit.sweep(_cfg(), {"output.observer": ["none", "step-count"]}, scheduler="inline")
    with pytest.raises(TypeError, match="params must be a NamedTuple class"):
        register(Observer("bad", dict, {}, 0, step_observer.start, step_observer.step,
                          step_observer.stop, step_observer.values))
    with pytest.raises(TypeError, match="step must be compiled"):
        register(Observer("bad", type("P", (tuple,), {"_fields": ()}), {}, 0,
                          step_observer.start, lambda *a: None, step_observer.stop,
                          step_observer.values))
    with pytest.raises(ValueError, match="is registered already"):
        from typing import NamedTuple
        register(Observer("step-count", NamedTuple("Other", []), {}, 0,
                          step_observer.start, step_observer.step, step_observer.stop,
                          step_observer.values))


def test_a_function_that_fails_its_dry_run_is_refused_at_register():
    from typing import NamedTuple

    @observer_kernel
    def past_the_end(p, st, out):
        out[2] = 1.0           # two columns: out has 2 entries

    @observer_kernel
    def no_system(p, st, t, u, v):      # start without ``system``
        pass

    with pytest.raises(TypeError, match=r"observer 'bad-values': values fails a dry run on "
                                        r"a rod of 4 segments: IndexError"):
        register(Observer("bad-values", NamedTuple("BadValues", [("limit", int)]),
                          {"a": "", "b": ""}, 4,
                          step_observer.start, step_observer.step, step_observer.stop,
                          past_the_end))
    with pytest.raises(TypeError, match="observer 'bad-start': start fails a dry run"):
        register(Observer("bad-start", NamedTuple("BadStart", [("limit", int)]), {}, 4,
                          no_system,
                          step_observer.step, step_observer.stop, step_observer.values))
    from rodjit.observers import observer_names
    assert "bad-values" not in observer_names() and "bad-start" not in observer_names()


def test_a_column_named_as_a_built_in_one_is_refused():
    from typing import NamedTuple

    @observer_kernel
    def values(p, st, out):
        out[0] = 1.0

    register(Observer("clashing", NamedTuple("Clash", [("limit", int)]), {"steps": "a clash"},
                      4,
                      step_observer.start, step_observer.step, step_observer.stop, values))
    with pytest.raises(ValueError, match="names a column 'steps', which is a built-in"):
        rodjit.sweep(_cfg(**{"output.observer": "clashing"}), {"rod.mu": [100.0]},
                     scheduler="inline")


def test_the_command_line_refuses_an_unknown_observer(tmp_path):
    p = subprocess.run([sys.executable, "-m", "rodjit", "run", "paper-mu0", "--set",
                        "output.observer=nope", "-o", str(tmp_path / "x.h5")],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 2
    assert "output.observer = 'nope' is not a registered observer" in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "x.h5").exists()


@pytest.mark.slow
def test_the_gpu_engine_gives_the_same_columns():
    got = simulated_sweeps(
        f"import sys; sys.path.insert(0, {str(HERE)!r}); import step_observer\n"
        "cfg = rodjit.load_preset('paper-mu100').override({'time.t_end': 0.6, "
        "'output.observer': 'step-count'})",
        {"rod.mu": [100.0, 150.0]}, (*step_observer.COLUMNS, "steps"))
    for name, (gpu, cpu) in got.items():
        assert gpu == cpu, name
