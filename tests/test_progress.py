"""One progress facility (tqdm) for runs, run files, sweeps and the command line; user
callables keep working; the first compile is announced."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest
from click.testing import CliRunner

import rodjit
from rodjit.cli import main
from rodjit.driver import progress as P

CFG = rodjit.Config().override({"time.t_end": 0.3})


def test_simulate_with_a_bar(capsys):
    r = rodjit.simulate(CFG, progress=True)
    err = capsys.readouterr().err
    assert r.status == "completed"
    assert "run: 100%" in err and "t = 0.3 / 0.3 s" in err


@pytest.mark.slow
def test_callables_still_get_the_run(tmp_path):
    long = CFG.override({"time.t_end": 5.0, "rod.N": 40})   # many compiled chunks
    seen = []
    rodjit.simulate(long, progress=lambda run: seen.append(run.t))
    assert seen and seen == sorted(seen) and 0 < seen[-1] < 5.0
    seen.clear()
    rodjit.run_to_file(CFG, tmp_path / "r.h5", progress=lambda run: seen.append(run.t))
    assert seen


def test_run_to_file_resume_and_sweep_with_bars(tmp_path, capsys):
    rodjit.run_to_file(CFG, tmp_path / "r.h5", progress=True)
    assert "run: 100%" in capsys.readouterr().err
    rodjit.resume_file(tmp_path / "r.h5", t_end=0.5, progress=True)
    assert "t = 0.5 / 0.5 s" in capsys.readouterr().err
    rodjit.sweep(CFG, {"rod.mu": [0, 1]}, scheduler="inline", progress=True)
    err = capsys.readouterr().err
    assert "sweep: 2/2 points" in err and "100%" in err and "0 failed" in err


def test_a_cold_cache_is_announced(monkeypatch, capsys):
    monkeypatch.setattr(P, "kernels_cold", lambda config=None: True)
    bar = P.RunBar()
    bar.bar.refresh()
    assert P.COMPILING in capsys.readouterr().err
    bar.close()


@pytest.mark.slow
def test_kernels_cold_reads_the_numba_cache(tmp_path):
    """Cold where Numba's cache is empty, not once a run has compiled into it: fresh
    interpreters with a cache of their own, which no other test can fill or refuse to
    write (this process's kernels may have been compiled while a test refused the cache
    writes)."""
    probe = ("import sys, rodjit\n"
             "from rodjit.driver import progress as P\n"
             "print(P.kernels_cold())\n"
             "if sys.argv[1] == 'run':\n"
             "    rodjit.simulate(rodjit.Config().override({'time.t_end': 0.05,\n"
             "                    'time.integrator': 'verlet', 'time.control': 'cfl'}))\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "RODJIT_AOT": "0"}
    env.pop("NUMBA_DISABLE_JIT", None)
    said = []
    for what in ("run", "ask"):
        done = subprocess.run([sys.executable, "-c", probe, what], env=env,
                              capture_output=True, text=True, timeout=900)
        assert done.returncode == 0, done.stderr[-3000:]
        said.append(done.stdout.split()[-1])
    assert said == ["True", "False"]


def test_cli_progress_flags(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    r = runner.invoke(main, ["run", "--set", "time.t_end=0.3", "-o", "a.h5", "--progress"])
    assert r.exit_code == 0, r.output
    assert "run: 100%" in r.stderr
    r = runner.invoke(main, ["run", "--set", "time.t_end=0.3", "-o", "b.h5", "--no-progress"])
    assert r.exit_code == 0 and "100%" not in r.stderr
    asked = []
    monkeypatch.setattr(P, "kernels_cold", lambda config=None: asked.append(config) or True)
    r = runner.invoke(main, ["run", "--set", "time.t_end=0.3", "-o", "c.h5", "--progress"])
    assert r.stderr.startswith(P.COMPILING + "\n")
    # asked about the run's own configuration (a run on the loop compiled ahead of time
    # has nothing to compile: tests/test_stepping_aot.py)
    assert asked[0].time.t_end == 0.3
    r = runner.invoke(main, ["sweep", "--set", "time.t_end=0.3", "--grid", "rod.mu=0,1",
                             "--scheduler", "inline", "-o", "s.h5", "--progress"])
    assert r.exit_code == 0, r.output
    assert "2/2 points" in r.stderr


def test_cli_sweep_whose_points_all_failed_exits_1(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["sweep", "--set", "time.dt=1e-3", "--set",
                                  "initial.velocity=-100", "--set", "time.t_end=0.5",
                                  "--set", "time.integrator=verlet",
                                  "--grid", "rod.mu=0,1", "--scheduler", "inline",
                                  "-o", "s.h5"])
    assert r.exit_code == 1
    assert "every point of the sweep failed (2)" in r.stderr
