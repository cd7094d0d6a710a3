"""``rodjit sweep``, and ``info``/``plot`` of sweep files: output, exit codes, usage errors,
and a real Ctrl-C of a real sweep followed by --resume."""
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import psutil
import pytest
from click.testing import CliRunner

import rodjit
from rodjit.cli import main
from rodjit.sweeps import sweep_file

from test_sweep_driver import same_values

GRID_ARGS = ["--grid", "rod.mu=0,10", "--grid", "floor.beta=0.01,0.05", "--set",
             "time.t_end=0.8"]


def invoke(*args):
    return CliRunner().invoke(main, list(map(str, args)), catch_exceptions=False)


def test_sweep_writes_the_file_and_prints_the_table(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = invoke("sweep", *GRID_ARGS, "--scheduler", "inline")
    assert r.exit_code == 0, r.output
    assert r.stderr == ""                       # no progress bar off a terminal
    lines = r.stdout.splitlines()
    assert lines[0].startswith("sweep.h5: sweep completed, 4 points (4 completed, 0 failed")
    assert lines[1].split()[:4] == ["#", "rod.mu", "floor.beta", "status"]
    assert len(lines) == 6 and lines[5].split()[:4] == ["3", "10", "0.05", "completed"]
    table = rodjit.load_sweep(tmp_path / "sweep.h5")
    expected = rodjit.sweep(rodjit.Config().override({"time.t_end": 0.8}),
                            {"rod.mu": [0.0, 10.0], "floor.beta": [0.01, 0.05]},
                            scheduler="inline")
    same_values(table, expected)
    with h5py.File(tmp_path / "sweep.h5") as f:
        assert f.attrs["command"] == ("rodjit sweep --grid rod.mu=0,10 --grid "
                                      "floor.beta=0.01,0.05 --set time.t_end=0.8 --scheduler "
                                      "inline")
    # a preset names the file after it; an existing file needs --overwrite
    r = invoke("sweep", "paper-mu100", "--grid", "floor.beta=0.05", "--set", "time.t_end=0.3",
               "--scheduler", "inline", "-q")
    assert r.exit_code == 0 and r.stdout == ""
    assert rodjit.load_sweep(tmp_path / "paper-mu100_sweep.h5").base.rod.mu == 100.0
    r = invoke("sweep", *GRID_ARGS)
    assert r.exit_code == 2 and "already exists; use --overwrite (or --resume)" in r.stderr


def test_info_and_plot_of_a_sweep_file(tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    assert invoke("sweep", *GRID_ARGS, "--scheduler", "inline", "-q").exit_code == 0
    r = invoke("info", "sweep.h5")
    assert r.exit_code == 0
    out = r.stdout
    assert out.startswith(f"rodjit sweep file sweep.h5 (format {sweep_file.FORMAT_VERSION}")
    assert "status    completed" in out and "points    4 (4 completed, 0 failed, 0 not run)" in out
    assert "  rod.mu = 0, 10\n  floor.beta = 0.01, 0.05\n" in out
    assert "t_end = 0.8" in out and "restitution_first" in out
    r = invoke("plot", "sweep.h5")
    assert r.exit_code == 0 and r.stdout.strip() == "wrote sweep_restitution.png"
    assert (tmp_path / "sweep_restitution.png").stat().st_size > 10_000
    r = invoke("plot", "sweep.h5", "--kind", "heatmap", "-o", "h.png")
    assert r.exit_code == 0 and (tmp_path / "h.png").exists()
    for args, message in ((["--kind", "heights"], "--kind heights is for run files"),
                          (["--at", "floor.beta=0.3"], "--at floor.beta=0.3 is not on the grid"),
                          (["--at", "rod.mu=10"], "--at rod.mu fixes the key the figure runs along"),
                          (["--quantity", "status"], "is not a numeric summary column"),
                          (["--x", "rod.N"], "'rod.N' is not a swept key"),
                          (["--kind", "heatmap", "--at", "rod.mu=10"],
                           "a heatmap needs two swept keys with several values")):
        r = invoke("plot", "sweep.h5", "--overwrite", *args)
        assert r.exit_code == 2 and message in r.stderr, r.stderr


def test_failed_points_exit_1_and_resume_reruns_them(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = invoke("sweep", "--grid", "initial.velocity=0,-100", "--set", "time.dt=1e-3",
               "--set", "time.t_end=0.5", "--set", "time.integrator=verlet",
               "--scheduler", "inline")
    assert r.exit_code == 1
    assert "1 completed, 1 failed" in r.stdout and "failed points (1):" in r.stdout
    assert "1: initial.velocity=-100: fixed step time.dt = 0.001 failed" in r.stdout
    r = invoke("sweep", "--resume", "-o", "sweep.h5", "--scheduler", "inline")
    assert r.exit_code == 1 and "1 run here" in r.stdout        # only the failed point ran
    r = invoke("sweep", "--resume", "sweep.h5", "--grid", "initial.velocity=0,-50")
    assert r.exit_code == 2 and "the grid differs from the one in 'sweep.h5'" in r.stderr


@pytest.mark.parametrize("args, message", [
    (["--grid", "rod.muu=1"], "unknown configuration key 'rod.muu'; did you mean 'rod.mu'?"),
    (["--grid", "rod.mu=-1"], "rod.mu = -1.0 is out of range (float >= 0)"),
    ([], "a sweep needs at least one --grid KEY=VALUES"),
    (["--grid", "rod.mu=1", "--jobs", "0"], "jobs = 0 is out of range"),
    (["--grid", "rod.mu=1", "--scheduler", "mpi"], "scheduler = 'mpi' is not allowed"),
    (["--grid", "rod.mu=1", "--batch-size", "0"], "batch_size = 0 is out of range"),
    (["--grid", "rod.mu=1", "--set", "rod.mu=2"], None),
    (["--grid", "rod.mu=1", "-o", "missing/s.h5"], "output directory 'missing' does not exist"),
    (["nosuch.toml", "--grid", "rod.mu=1"], "configuration file 'nosuch.toml' does not exist"),
    (["--resume"], "--resume needs the sweep file"),
    (["--resume", "-o", "none.h5"], "'none.h5' does not exist"),
])
def test_usage_errors_exit_2_and_write_nothing(tmp_path, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    r = invoke("sweep", *args, "--save-runs", "runs")
    if message is None:        # a key both set and swept: the grid wins, no error
        assert r.exit_code == 0
        return
    assert r.exit_code == 2, r.output
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert list(tmp_path.iterdir()) == []


def _wait_for(predicate, timeout=120):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.05)
    return False


def _completed(path) -> int:
    try:
        return int(np.sum(rodjit.load_sweep(path)["status"] == "completed"))
    except (ValueError, OSError):
        return 0


@pytest.mark.slow
def test_ctrl_c_stops_a_real_sweep_and_resume_finishes_it(tmp_path):
    """A sweep in a subprocess with two workers: SIGINT once some points are on disk; the
    workers go away, the file keeps every finished point, --resume runs the rest and the
    table equals a sweep run in one go."""
    args = ["--grid", "floor.beta=linspace(0.01,0.05,16)", "--set", "time.t_end=6", "--set",
            "rod.N=200", "--set", "time.integrator=verlet", "--set", "time.control=cfl",
            "--jobs", "2", "-o", "s.h5"]          # ~0.4 s a point
    proc = subprocess.Popen([sys.executable, "-m", "rodjit", "sweep", *args], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert _wait_for(lambda: _completed(tmp_path / "s.h5") >= 2 or proc.poll() is not None)
        workers = psutil.Process(proc.pid).children(recursive=True)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert _wait_for(lambda: not any(w.is_running() and w.status() != psutil.STATUS_ZOMBIE
                                     for w in workers), timeout=60)
    cut = rodjit.load_sweep(tmp_path / "s.h5")
    assert cut.counts["failed"] == 0
    if cut.counts["completed"] == 16:   # a loaded machine: the signal came after the last point
        assert cut.status == "completed" and "SIGINT after the last point" in err
        return
    assert "interrupted by SIGINT after" in err and "rodjit sweep --resume -o s.h5" in err
    assert cut.status == "interrupted" and 2 <= cut.counts["completed"] < 16
    r = subprocess.run([sys.executable, "-m", "rodjit", "sweep", "--resume", "-o", "s.h5", "-q"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    final = rodjit.load_sweep(tmp_path / "s.h5")
    assert final.status == "completed" and final.counts["completed"] == 16
    ref = rodjit.sweep(rodjit.Config().override({"time.t_end": 6.0, "rod.N": 200,
                                                 "time.integrator": "verlet",
                                                 "time.control": "cfl"}),
                       {"floor.beta": "linspace(0.01,0.05,16)"}, jobs=2)
    same_values(final, ref)


def test_sweep_progress_bar_writes_to_stderr(capsys):
    from rodjit.cli.options import sweep_bar as _SweepProgress
    from rodjit.sweeps import SweepProgress

    bar = _SweepProgress()
    bar(SweepProgress(done=13, total=52, failed=2, run=10, todo=49, elapsed=75.0))
    bar.close()
    err = capsys.readouterr().err
    assert "13/52 points" in err and " 25%" in err and "2 failed" in err
    assert "1:15 elapsed" in err and "4:52 left" in err       # 75 s / 10 × 39 points left
    assert capsys.readouterr().out == ""


def test_plot_takes_a_swept_key_by_its_dimension_name_too(tmp_path, monkeypatch):
    """``to_xarray`` names the dimensions ``mu``, ``beta`` (``ds.sel(mu=10)``: old scripts
    keep working); ``rodjit plot --x/--y/--at/--panels`` take those names as well as the
    keys, for the same figure."""
    pytest.importorskip("matplotlib")
    from rodjit.plotting.sweep import sweep_figure

    monkeypatch.chdir(tmp_path)
    assert invoke("sweep", *GRID_ARGS, "--scheduler", "inline", "-q").exit_code == 0
    ds = rodjit.load_sweep("sweep.h5").to_xarray()
    assert set(ds.dims) == {"mu", "beta"}
    assert (ds["mu"].attrs["key"], ds["beta"].attrs["key"]) == ("rod.mu", "floor.beta")
    for x, at, x_key, at_key in (("mu", {"beta": "0.05"}, "rod.mu", {"floor.beta": "0.05"}),
                                 ("beta", {"mu": "10"}, "floor.beta", {"rod.mu": "10"})):
        a = sweep_figure("sweep.h5", quantity="min_u0", x=x, at=at).axes[0]
        b = sweep_figure("sweep.h5", quantity="min_u0", x=x_key, at=at_key).axes[0]
        assert a.get_xlabel() == b.get_xlabel() and a.get_title() == b.get_title()
        assert [list(ln.get_xdata()) for ln in a.get_lines()] == \
            [list(ln.get_xdata()) for ln in b.get_lines()]
    r = invoke("plot", "sweep.h5", "--quantity", "min_u0", "--x", "beta", "--at", "mu=10",
               "-o", "b.png")
    assert r.exit_code == 0, r.stderr
    r = invoke("plot", "sweep.h5", "--kind", "heatmap", "--quantity", "min_u0", "--x", "mu",
               "--y", "beta", "-o", "h.png")
    assert r.exit_code == 0, r.stderr
    r = invoke("plot", "sweep.h5", "--x", "kappa")
    assert r.exit_code == 2 and "swept: rod.mu or mu, floor.beta or beta" in r.stderr


def test_sweep_coordinates_carry_units_and_meaning(tmp_path):
    """Every dataset has ``units`` (docs/output.md): the swept keys' coordinates too."""
    pytest.importorskip("xarray")
    table = rodjit.sweep(rodjit.Config().override({"time.t_end": 0.2}),
                         {"rod.mu": [0.0, 1.0], "floor.kappa_b": [1e3],
                          "time.integrator": ["energy"]}, scheduler="inline")
    ds = table.to_xarray()
    assert ds["mu"].attrs["units"] == rodjit.config.field_spec("rod.mu").unit
    assert ds["kappa_b"].attrs["units"] == "N"
    assert ds["mu"].attrs["description"] == rodjit.config.field_spec("rod.mu").meaning
    assert "units" not in ds["integrator"].attrs          # a name, not a quantity
    for name, var in ds.data_vars.items():
        if var.dtype.kind in "fi":
            assert "units" in var.attrs, name


@pytest.mark.parametrize("value, shown", [("0:100:11", "'0:100:11'"),
                                          ("[0,10,100]", "rod.mu = '[0,10,100]': '[0'")])
def test_a_bad_grid_value_lists_the_accepted_forms(tmp_path, monkeypatch, value, shown):
    monkeypatch.chdir(tmp_path)
    r = invoke("sweep", "--grid", f"rod.mu={value}")
    assert r.exit_code == 2 and list(tmp_path.iterdir()) == []
    line = r.stderr.strip()
    assert line.startswith("Error: grid rod.mu") and f"{shown} is not a number" in line, line
    for form in ("comma-separated list (rod.mu=0,1,10,100)", "linspace(a,b,n)",
                 "logspace(a,b,n)"):
        assert form in line, line
    r = invoke("sweep", "--grid", "rod.mu=1,2s")     # a unit: the key's own hint
    assert r.exit_code == 2 and "plain SI numbers without units" in r.stderr


def test_set_with_a_unit_says_values_are_si_numbers(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["run", "--set", "time.t_end=2s"])
    assert r.exit_code == 2 and list(tmp_path.iterdir()) == []
    assert "values are plain SI numbers without units; write it in s" in r.stderr
    assert "docs/units.md" in r.stderr


@pytest.mark.parametrize("scheduler,capped", [("local", True), ("processes", True),
                                              ("tcp://127.0.0.1:1", False)])
def test_jobs_on_this_machine_are_capped_at_its_cores(monkeypatch, tmp_path, scheduler,
                                                      capped):
    """Dask's local cluster starts --jobs worker processes on this machine, as the pool
    does: both are capped at the cores (a note says so); a remote cluster is not."""
    import rodjit.sweeps
    import rodjit.sweeps.executors
    import rodjit.sweeps.start_method

    asked = {}

    def recorder(*args, jobs=None, **kwargs):
        asked["jobs"] = jobs
        raise ValueError("stopped before any worker starts")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(rodjit.sweeps.executors, "default_jobs", lambda: 2)
    monkeypatch.setattr(rodjit.sweeps.start_method, "start_server", lambda: None)
    monkeypatch.setattr(rodjit.sweeps, "sweep", recorder)
    r = CliRunner().invoke(main, ["sweep", "--grid", "rod.mu=0,1,2,3,4,5,6,7", "-j", "6",
                                  "--scheduler", scheduler])
    assert r.exit_code == 2 and "stopped before any worker starts" in r.stderr, r.output
    assert asked["jobs"] == (2 if capped else 6)
    assert ("--jobs 6 is more than the 2 cores; using 2" in r.stderr) == capped


@pytest.mark.parametrize("verb,target", [
    ("fit", ("rod.mu", "--target", "restitution_first=0.5", "--bracket", "1,100")),
    ("fit", ("rod.mu", "--table", "t.csv")),
    ("converge", ("--ladder", "rod.N=5,10,20"))])
@pytest.mark.parametrize("force", [False, True])
def test_fit_and_converge_cap_their_jobs_as_sweep_does(monkeypatch, tmp_path, verb, target,
                                                       force):
    """fit and converge run their points on the same pool: --jobs beyond the cores is cut
    to the cores with the sweep's note, unless --force-jobs."""
    import importlib

    import rodjit.sweeps.executors

    asked = {}

    def recorder(*args, jobs=None, **kwargs):
        asked["jobs"] = jobs
        raise ValueError("stopped before any worker starts")

    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text("initial.height,restitution_first\n1,0.5\n2,0.4\n")
    monkeypatch.setattr(rodjit.sweeps.executors, "default_jobs", lambda: 2)
    for name in ("fit", "fit_table", "converge"):
        monkeypatch.setattr(importlib.import_module(f"rodjit.analysis.{name}"), name, recorder)
    r = CliRunner().invoke(main, [verb, *target, "-j", "6",
                                  *(["--force-jobs"] if force else [])])
    assert "stopped before any worker starts" in r.stderr, r.output
    assert asked["jobs"] == (6 if force else 2)
    assert ("--jobs 6 is more than the 2 cores; using 2" in r.stderr) == (not force)
