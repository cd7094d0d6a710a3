"""Hostile catalogue, resources: the output-size and step limits of a new run guard every
path that runs (a resume, a --t-end extension, converge, fit), refused up front in one
line, exit code 2, the file untouched."""
from __future__ import annotations

import hashlib
import shutil

import pytest
from click.testing import CliRunner

from rodjit import cli

TINY = ["--set", "time.t_end=0.3", "--set", "rod.N=3", "--set", "rod.mu=1", "-q"]


def invoke(*args):
    return CliRunner().invoke(cli.main, [str(a) for a in args])


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("hostile_resources")
    assert invoke("run", *TINY, "-o", d / "r.h5").exit_code == 0
    return d / "r.h5"


CASES = [
    ("resume to t_end 1e7", ["--t-end", "1e7"], "limit of 10 GiB"),
    ("resume to 1e5 under 1 MiB", ["--t-end", "1e5", "--max-output", "1M"], "limit of"),
    ("resume under 1 KiB", ["--t-end", "0.5", "--max-output", "1K"], "limit of"),
]


@pytest.mark.parametrize("name,extra,text", CASES, ids=[c[0] for c in CASES])
def test_limits_guard_resume(run_file, tmp_path, name, extra, text):
    p = tmp_path / "x.h5"
    shutil.copy(run_file, p)
    before = hashlib.sha256(p.read_bytes()).hexdigest()
    r = invoke("run", "--resume", p, *extra)
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.output
    assert text in lines[0] and "continued run" in lines[0], lines[0]
    assert hashlib.sha256(p.read_bytes()).hexdigest() == before


def test_fixed_step_limit_guards_resume(tmp_path):
    p = tmp_path / "x.h5"
    assert invoke("run", *TINY, "--set", "time.dt=1e-4", "-o", p).exit_code == 0
    r = invoke("run", "--resume", p, "--t-end", "1e4", "--max-steps", "1e6",
               "--max-output", "inf")
    assert r.exit_code == 2 and "--max-steps" in r.stderr, r.output


@pytest.mark.parametrize("args", [
    ["converge", "--ladder", "rod.N=5,10", "--set", "time.t_end=1e7"],
    ["fit", "rod.mu", "--target", "restitution_first=0.5", "--set", "time.t_end=1e7"],
    ["converge", "--ladder", "rod.N=5,10", "--set", "time.dt=1e-9", "--set",
     "time.t_end=100", "--set", "output.snapshot_interval=0", "--set",
     "output.diagnostics_interval=0"],
], ids=["converge too large", "fit too large", "converge too many steps"])
def test_limits_guard_converge_and_fit(tmp_path, monkeypatch, args):
    monkeypatch.chdir(tmp_path)
    r = invoke(*args)
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.output
    assert "limit" in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_one_estimate_for_every_path():
    """The check of a resume, a study and a new run is the same function."""
    import inspect

    from rodjit.analysis import evaluate
    from rodjit.driver import files, simulate

    assert "check_run(" in inspect.getsource(files._resume_locked)
    assert "check_run(" in inspect.getsource(evaluate.check_limits)
    assert "check_run(" in inspect.getsource(simulate.simulate)


@pytest.mark.parametrize("duration", ["inf", "1e9", "nan", "501"])
def test_a_movie_s_length_is_bounded(run_file, tmp_path, duration):
    """``animate`` lays out fps x duration frame times before drawing any (a duration of
    1e9 s asked for 149 GiB, inf raised a Traceback): at most ``MAX_FRAMES`` frames, one
    line naming the duration and its range, nothing written."""
    from rodjit.plotting.animation import MAX_FRAMES

    r = invoke("animate", run_file, "-o", tmp_path / "m.gif", "--duration", duration)
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.output
    assert "duration" in lines[0], lines[0]
    assert f"at most {MAX_FRAMES / 20:g} at fps = 20" in lines[0], lines[0]
    assert f"at most {MAX_FRAMES:,}" in invoke("animate", "--help").output.replace("\n", " ")
    assert list(tmp_path.iterdir()) == []


STUDIES = [["converge", "--ladder", "rod.N=5,10", "--also", "none"],
           ["fit", "rod.mu", "--target", "restitution_first=0.5"]]


@pytest.mark.parametrize("args", STUDIES, ids=["converge", "fit"])
def test_converge_and_fit_take_the_limit_options_their_refusals_name(tmp_path, monkeypatch,
                                                                      args):
    """A refusal says "raise it with --max-output" (or --max-steps): the verb has that
    option, and a lower limit given there refuses a study the default allows."""
    monkeypatch.chdir(tmp_path)
    big = invoke(*args, "--set", "time.t_end=1e7")
    line = big.stderr.strip().splitlines()[0]
    assert big.exit_code == 2 and "raise it with --max-output" in line, big.output
    help_text = invoke(args[0], "--help").output
    assert "--max-output" in help_text and "--max-steps" in help_text
    r = invoke(*args, "--set", "time.t_end=0.3", "--max-output", "1K")
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.output
    assert "more than the limit of 1 KiB" in lines[0]
    r = invoke(*args, "--set", "time.dt=1e-4", "--set", "time.t_end=1", "--set",
               "output.snapshot_interval=0", "--set", "output.diagnostics_interval=0",
               "--max-steps", "1000")
    assert r.exit_code == 2 and "more than the limit of 1e+03" in r.stderr, r.output
    r = invoke(*args, "--max-output", "lots")
    assert r.exit_code == 2 and "'lots' is not understood" in r.stderr, r.output
    assert list(tmp_path.iterdir()) == []


def test_the_study_functions_take_the_limits():
    """``converge``, ``fit`` and ``fit_table`` pass ``max_output`` to every run's check."""
    import rodjit
    from rodjit.analysis import converge, fit, fit_table

    cfg = rodjit.Config().override({"time.t_end": 0.3, "rod.N": 3})
    for call in (lambda: converge(cfg, {"rod.N": [5, 10]}, also=False,
                                           max_output=1024),
                 lambda: fit("rod.mu", {"restitution_first": 0.5}, cfg, max_output=1024),
                 lambda: fit_table(["rod.mu"], [{"initial.height": 0.1,
                                                 "restitution_first": 0.5}], cfg,
                                   max_output=1024)):
        with pytest.raises(ValueError, match="more than the limit of 1 KiB"):
            call()
