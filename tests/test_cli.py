"""The ``rodjit`` command: runs, usage errors, info, plot, and real signals in subprocesses."""
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

import rodjit
from rodjit.cli import main
from rodjit.cli.options import run_bar as _Progress
from rodjit.output import hdf5
from rodjit.stepping import layout as L

from conftest import assert_same_files, final_state, rodjit_cli

# heavy enough that a run is still going when the test signals it (it would take minutes);
# energy lands on the output times, so a resume to an earlier end equals a run made to it
# at once (dop853, auto's here, steps toward t_end: driver.files.resume_file)
LONG_RUN = """
[rod]
N = 300
[time]
t_end = 1000.0
integrator = "energy"
[output]
snapshot_interval = 0.01
"""


def invoke(*args, cwd=None):
    runner = CliRunner()
    if cwd is None:
        return runner.invoke(main, list(map(str, args)), catch_exceptions=False)
    with runner.isolated_filesystem(temp_dir=cwd):
        return runner.invoke(main, list(map(str, args)), catch_exceptions=False)


def test_readme_command_runs_the_default(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = invoke("run", "-o", "default.h5", "--overwrite")
    assert r.exit_code == 0, r.output
    assert "completed at t = 5 of 5" in r.stdout and "energy drift" in r.stdout
    assert "node-steps/s" in r.stdout and "restitution" in r.stdout
    # no progress bar off a terminal; the default (μ = γ = 0) says its first bounce has no
    # continuum limit, one line
    assert r.stderr == f"warning: {rodjit.config.SHOCK_WARNING}\n"
    assert "warning" not in r.stdout            # said once: on stderr, not in the summary too
    res = rodjit.load_file(tmp_path / "default.h5")
    # the default as it ran: "auto" resolved (dop853), and why
    assert res.config == rodjit.Config().resolve() and res.status == "completed"
    assert res.config.choice.startswith("chosen by 'auto'")
    with h5py.File(tmp_path / "default.h5") as f:
        assert f.attrs["command"] == "rodjit run -o default.h5 --overwrite"
    assert invoke("run", "-o", "default.h5", "--overwrite").exit_code == 0


def test_presets_and_preset_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = invoke("presets")
    assert r.exit_code == 0
    assert r.stdout.splitlines()[0].startswith("paper-mu0") and "paper-mu100" in r.stdout
    r = invoke("run", "paper-mu100", "--t-end", "0.5", "-q")
    assert r.exit_code == 0 and r.stdout == ""
    res = rodjit.load_file(tmp_path / "paper-mu100.h5")
    assert res.config.rod.mu == 100.0 and res.t_final == 0.5


def test_config_file_and_set(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my.toml").write_text("[rod]\nN = 8\n[time]\nt_end = 0.4\n")
    r = invoke("run", "my.toml", "--set", "rod.mu=2.5", "--set", "time.integrator=semi-implicit")
    assert r.exit_code == 0, r.output
    cfg = rodjit.load_file(tmp_path / "my.h5").config
    assert (cfg.rod.N, cfg.rod.mu, cfg.time.integrator) == (8, 2.5, "semi-implicit")
    assert "energy balance error" in r.stdout


@pytest.mark.parametrize("args, message", [
    (["--set", "rod.mu2=3"], "unknown configuration key 'rod.mu2'; did you mean 'rod.mu'? "
                             "valid keys: rod.N"),
    (["--set", "rod.mu=-1"], "rod.mu = -1.0 is out of range (float >= 0)"),
    (["--set", "rod.mu"], "--set expects KEY=VALUE"),
    (["--t-end", "-2"], "time.t_end = -2.0 is out of range (float > 0)"),
    (["-o", "missing/out.h5"], "output directory 'missing' does not exist"),
    (["nope.toml"], "configuration file 'nope.toml' does not exist"),
    (["bad.toml"], "configuration file 'bad.toml' is not valid TOML"),
    (["nopreset"], "'nopreset' is neither a configuration file nor a preset; presets: "
                   "paper-mu0, paper-mu100"),
    (["--resume"], "--resume needs the file to continue"),
    (["old.h5"], "'old.h5' is not a configuration; to continue a run file use: rodjit run "
                 "--resume old.h5"),
    (["--resume", "x.h5", "--set", "rod.mu=1"], "--set cannot be used with --resume"),
    (["--resume", "absent.h5"], "'absent.h5' does not exist"),
])
def test_usage_errors_exit_2_with_one_line_and_write_nothing(tmp_path, monkeypatch, args,
                                                             message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.toml").write_text("[rod\n")
    r = invoke("run", *args)
    assert r.exit_code == 2
    assert r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: ") and message in lines[0], lines
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_existing_output_is_not_overwritten(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "default.h5").write_bytes(b"keep me")
    r = invoke("run")
    assert r.exit_code == 2
    assert r.stderr.strip() == ("Error: output file 'default.h5' already exists; use "
                                "--overwrite to replace it")
    assert (tmp_path / "default.h5").read_bytes() == b"keep me"


def test_resume_a_completed_run_needs_a_later_end(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert invoke("run", "--t-end", "0.5", "-q").exit_code == 0
    r = invoke("run", "--resume", "default.h5")
    assert r.exit_code == 2 and r.stderr.strip() == (
        "Error: 'default.h5' is already complete at t = 0.5; give a later t_end to extend it")
    r = invoke("run", "--resume", "-o", "default.h5", "--t-end", "0.8")
    assert r.exit_code == 0 and "completed at t = 0.8 of 0.8" in r.stdout
    assert rodjit.load_file(tmp_path / "default.h5").config.time.t_end == 0.8


def test_failed_run_exits_1_and_keeps_data(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = invoke("run", "--set", "time.dt=1e-3", "--set", "initial.velocity=-100",
               "--set", "time.integrator=verlet", "-o", "f.h5")
    assert r.exit_code == 1
    assert "failed at t = " in r.stderr and "bending limit" in r.stderr
    assert "failed at t = 0.01" in r.stdout            # the summary still shows
    res = rodjit.load_file(tmp_path / "f.h5")
    assert res.status == "failed" and res.t.size > 0 and "bending limit" in res.message


def test_info(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert invoke("run", "--t-end", "2", "-q").exit_code == 0
    r = invoke("info", "default.h5")
    assert r.exit_code == 0
    out = r.stdout
    assert "status    completed" in out and "command   rodjit run --t-end 2.0 --quiet" in out
    assert "[rod]" in out and "t_end = 2.0" in out
    assert "401 snapshots, 2001 diagnostics" in out
    res = rodjit.load_file(tmp_path / "default.h5")
    assert f"{res.n_bounces} bounces" in out
    for e in res.bounces["restitution"]:
        assert f"{e:.4f}" in out


def test_info_and_plot_reject_other_files(tmp_path):
    (tmp_path / "a.txt").write_text("x")
    with h5py.File(tmp_path / "p.h5", "w") as f:
        f["x"] = 1
    for cmd in ("info", "plot"):
        r = invoke(cmd, tmp_path / "a.txt")
        assert r.exit_code == 2 and r.stderr.strip().endswith("is not a rodjit file (not an "
                                                              "HDF5 file)")
        r = invoke(cmd, tmp_path / "p.h5")
        assert r.exit_code == 2 and "no 'rodjit_kind' attribute" in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("kind", ["heights", "energy", "bounces"])
def test_plot(tmp_path, monkeypatch, kind):
    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    assert invoke("run", "--t-end", "1.5", "-q").exit_code == 0
    r = invoke("plot", "default.h5", "--kind", kind)
    assert r.exit_code == 0, r.output
    png = tmp_path / f"default_{kind}.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


def test_plot_without_matplotlib(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert invoke("run", "--t-end", "0.2", "-q").exit_code == 0
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)
    r = invoke("plot", "default.h5")
    assert r.exit_code == 2          # a usage error (install the extra), not a failed run
    assert r.stderr.strip() == ("Error: plotting needs matplotlib; install it with: "
                                "pip install 'rodjit[plot]'")
    r = invoke("animate", "default.h5")
    assert r.exit_code == 2 and "pip install 'rodjit[plot]'" in r.stderr
    assert not (tmp_path / "default.gif").exists()


def test_any_missing_extra_is_a_usage_error(tmp_path, monkeypatch):
    """A verb that needs an extra that is not installed exits 2 with the install line."""
    import rodjit.cli.options as cli
    from rodjit._extras import need

    monkeypatch.setattr(cli, "load_config", lambda source: need("nosuchmodule", "analysis",
                                                                 "rodjit run"))
    r = CliRunner().invoke(main, ["run", "--dry-run"])
    assert r.exit_code == 2, r.output
    assert "install it with: pip install 'rodjit[analysis]'" in r.output


def test_progress_bar_writes_to_stderr(capsys):
    class FakeRun:
        t, t_end, steps, bounces_total, run_time = 2.5, 5.0, 1000, 3, 0.5
    bar = _Progress()
    bar(FakeRun())
    bar.close()
    err = capsys.readouterr().err
    assert "t = 2.5 / 5" in err and "50%" in err and "3 bounces" in err
    assert "2e+03 steps/s" in err
    assert capsys.readouterr().out == ""


# ---- real processes, real signals -------------------------------------------------------
def _start_long_run(tmp_path, name):
    (tmp_path / "long.toml").write_text(LONG_RUN)
    proc = subprocess.Popen(
        [sys.executable, "-m", "rodjit", "run", "long.toml", "-o", name, "-q",
         "--flush-interval", "0.1"],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    path = tmp_path / name
    deadline = time.monotonic() + 240           # a cold numba cache compiles first
    seen_running = False
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        try:
            res = rodjit.load_file(path)        # read while another process writes it
        except (ValueError, OSError, KeyError):
            time.sleep(0.05)
            continue
        seen_running |= res.status == "running"
        if res.t.size > 20 and res.t_final > 0.2:
            assert seen_running and np.all(np.diff(res.t) > 0)
            return proc, path
        time.sleep(0.05)
    proc.kill()
    pytest.fail("the run did not make progress in time")


def _reference_and_resume(tmp_path, path):
    """Resume ``path`` to a little after its checkpoint, and run the same span in one go."""
    t_end = float(final_state(path)["clock"][L.T]) + 0.25
    r = rodjit_cli("run", "--resume", path.name, "--t-end", repr(t_end), "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    cfg = rodjit.Config.from_toml(tmp_path / "long.toml").override({"time.t_end": t_end})
    rodjit.run_to_file(cfg, tmp_path / "ref.h5")
    assert_same_files(path, tmp_path / "ref.h5")


@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)],
                         ids=["SIGINT", "SIGTERM"])
@pytest.mark.slow
def test_signal_then_resume_bit_for_bit(tmp_path, signum, code):
    proc, path = _start_long_run(tmp_path, "run.h5")
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err
    name = signal.Signals(signum).name
    assert f"interrupted by {name} at t = " in err and "rodjit run --resume run.h5" in err
    with h5py.File(path, "r") as f:           # closed cleanly: no SWMR flags left
        assert f.attrs["status"] == "interrupted"
        ck = hdf5.read_checkpoint(f)
        assert ck["lengths"]["snapshots"] == f["snapshots/t"].shape[0]
    _reference_and_resume(tmp_path, path)


@pytest.mark.slow
def test_sigkill_leaves_a_readable_file_that_resumes_bit_for_bit(tmp_path):
    proc, path = _start_long_run(tmp_path, "run.h5")
    time.sleep(0.3)
    proc.kill()
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    with pytest.raises(OSError, match="already open for write"):
        h5py.File(path, "r")                   # the SWMR flags are still set ...
    with h5py.File(path, "r", swmr=True) as f:  # ... and SWMR-read mode opens it as is
        ck = hdf5.read_checkpoint(f)
        t = f["snapshots/t"][()]
        assert f.attrs["status"] == "running"
        assert t.size >= ck["lengths"]["snapshots"] > 20   # every row up to the last flush
        assert np.array_equal(t, np.arange(t.size) * 0.01)
    r = rodjit_cli("info", "run.h5", cwd=tmp_path)
    assert r.returncode == 0 and "the writing process is gone" in r.stdout
    _reference_and_resume(tmp_path, path)
    with h5py.File(path, "r") as f:            # recovered into a clean file
        assert "recovered at the checkpoint" in f.attrs["history"][1]
        assert f.attrs["status"] == "completed"


def test_the_cli_knows_every_kind_of_figure():
    """rodjit.cli keeps its own copies of the figure kinds (fast start-up): they agree with
    the plotting modules."""
    import rodjit.cli as cli
    from rodjit import plotting
    from rodjit.plotting import sweep as sweep_plots

    assert cli.RUN_KINDS == plotting.KINDS and cli.SWEEP_KINDS == sweep_plots.KINDS


def test_run_dry_run_prints_the_estimate_and_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "old.h5").write_bytes(b"")
    r = invoke("run", "--dry-run", "--set", "time.t_end=1", "--set", "time.dt=1e-3",
               "-o", "out.h5")
    assert r.exit_code == 0, r.output
    for text in ("dry run: checked, nothing written", f"output       {tmp_path / 'out.h5'} "
                 "(a new file)", "snapshots    201 rows (every 0.005 s to t = 1)",
                 "diagnostics  1001 rows", "file         about", "memory       about",
                 "steps        1000 fixed steps of time.dt = 0.001"):
        assert text in r.output, r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.h5"]
    r = invoke("run", "--dry-run", "-o", "old.h5", "--overwrite")
    assert r.exit_code == 0 and "replaces the existing run file" in r.output
    assert "steps        adaptive (dop853, chosen by 'auto' for rod.mu = 0" in r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.h5"]


def test_sweep_dry_run_prints_points_files_and_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = invoke("sweep", "--dry-run", "--grid", "rod.mu=0,1,10", "--grid",
               "rod.N=5,50", "--save-runs", "runs", "-o", "s.h5")
    assert r.exit_code == 0, r.output
    for text in ("points       6: rod.mu (3 values) x rod.N (2 values)",
                 f"output       {tmp_path / 's.h5'} (a new file)", "sweep file   about",
                 f"run files    6 in {tmp_path / 'runs'}, about",
                 "worst point  1 (rod.mu=0 rod.N=50): 1001 snapshot rows"):
        assert text in r.output, r.output
    assert list(tmp_path.iterdir()) == []


def _warning_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if "warning" in line.lower()]


@pytest.mark.parametrize("args", [
    ("run", "-o", "w.h5", "--t-end", "0.3"),
    ("fit", "rod.mu", "--target", "restitution_first=0.5", "--bracket", "0,100",
     "--points", "2", "--set", "time.t_end=0.8", "--jobs", "2"),
    ("fit", "rod.mu", "--target", "restitution_first=0.5", "--bracket", "0,100",
     "--points", "2", "--set", "time.t_end=0.8", "--jobs", "1"),
], ids=["run", "fit-workers", "fit-inline"])
def test_a_warning_is_one_line_once_without_a_path(tmp_path, args):
    """μ = γ = 0 (the default) warns: one ``warning:`` line on stderr, once, never the
    file and line that issued it nor its source line (a worker's passed on to the
    parent); before, ``rodjit fit`` showed ``.../point.py:186: ModelWarning:`` and the
    call, and ``rodjit run`` said it on stderr and again in its summary."""
    r = rodjit_cli(*args, cwd=tmp_path)
    lines = _warning_lines(r.stderr) + _warning_lines(r.stdout)
    assert lines == [f"warning: {rodjit.config.SHOCK_WARNING}"], r.stderr + r.stdout
    assert ".py:" not in r.stderr and "ModelWarning" not in r.stderr, r.stderr


def test_any_warning_a_command_issues_is_said_as_one_line(tmp_path, monkeypatch):
    """Not only the model's: a library's warning while a command runs is one line too."""
    import warnings

    import rodjit.cli.options as cli

    def noisy(*a, **k):
        warnings.warn("something odd", RuntimeWarning)
        warnings.warn("something odd", RuntimeWarning)
        return rodjit.Config().override({"rod.mu": 1.0}), "default.h5"

    monkeypatch.setattr(cli, "load_config", lambda source: noisy())
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["run", "--dry-run"])
    assert r.exit_code == 0, r.output
    assert _warning_lines(r.stderr)[:1] == ["warning: something odd"]
    assert _warning_lines(r.stderr).count("warning: something odd") == 1


def test_a_run_asked_for_a_device_says_devices_are_for_sweeps(tmp_path, monkeypatch):
    """click said only "No such option: --device"."""
    monkeypatch.chdir(tmp_path)
    for args in (["--device", "cuda"], ["--device=auto"]):
        r = invoke("run", *args)
        assert r.exit_code == 2, r.output
        assert ("--device is not an option of rodjit run: devices are for sweeps: "
                "'rodjit sweep --device cuda'") in r.output
    assert "No such option" in invoke("run", "--nosuch").output
    assert list(tmp_path.iterdir()) == []


def test_quiet_says_no_warning(tmp_path, monkeypatch):
    """``-q`` ("print nothing but errors") still printed the model's warnings."""
    monkeypatch.chdir(tmp_path)
    args = ("run", "-o", "w.h5", "--t-end", "0.02", "--set", "rod.N=3")
    loud = CliRunner().invoke(main, list(args))
    assert loud.exit_code == 0, loud.output
    assert _warning_lines(loud.stderr) == [f"warning: {rodjit.config.SHOCK_WARNING}"]
    for p in tmp_path.iterdir():
        p.unlink()
    quiet = CliRunner().invoke(main, [*args, "-q"])
    assert quiet.exit_code == 0, quiet.output
    assert quiet.stderr == "" and quiet.stdout == ""
    # the next command (in this process) says its warnings again
    again = CliRunner().invoke(main, ["run", "--dry-run", "--set", "gravity.g=9.81"])
    assert any("gravity.g = 9.81 > 0" in line for line in _warning_lines(again.stderr))


def test_plot_and_animate_replace_a_picture_only_with_overwrite(tmp_path, monkeypatch):
    """``rodjit plot`` replaced its default picture without a word: like every writer, it
    refuses an existing file (one line, exit 2, the file as it was) unless --overwrite."""
    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    assert invoke("run", "--t-end", "0.2", "--set", "rod.N=3", "-q").exit_code == 0
    for verb, picture in (("plot", "default_heights.png"), ("animate", "default.gif")):
        (tmp_path / picture).write_bytes(b"an older picture")
        r = CliRunner().invoke(main, [verb, "default.h5", "--fps", "2", "--duration", "1"]
                               if verb == "animate" else [verb, "default.h5"])
        assert r.exit_code == 2, r.output
        assert r.stderr.strip() == (f"Error: output file {picture!r} already exists; use "
                                    f"--overwrite to replace it")
        assert (tmp_path / picture).read_bytes() == b"an older picture"
        r = CliRunner().invoke(main, [verb, "default.h5", "--overwrite"]
                               + (["--fps", "2", "--duration", "1"] if verb == "animate"
                                  else []))
        assert r.exit_code == 0 and r.stdout.strip() == f"wrote {picture}", r.output
        assert (tmp_path / picture).read_bytes() != b"an older picture"
