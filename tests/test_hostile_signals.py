"""Hostile catalogue, signals at random moments: SIGINT, SIGTERM and SIGKILL sent to a real
``rodjit`` process (a run, a resume, a sweep on the process pool, a sweep on a Dask
LocalCluster) at moments drawn by a seeded generator (``RODJIT_HOSTILE_SEED`` picks
another draw) over the uninterrupted command's own wall time from the moment its file
appears, measured here, so the draws span the file's whole life on a fast or a loaded
machine.

The contract, case by case:

- the command ends within a timeout (never a hang), with no Traceback on stderr;
- SIGINT/SIGTERM: exit 130/143 and one line naming the signal, or exit 0 and nothing on
  stderr (it had finished); SIGKILL: nothing of rodjit's, whatever it was doing;
- the file then calls itself complete only if it is: a completed file holds exactly the
  uninterrupted command's data; any other file is continued with ``--resume`` (a killed
  writer's file recovered first) until complete, and then holds exactly that data
  (compared dataset by dataset for a run, column by column, timings apart, for a sweep);
- a run file a kill left while it was being created, before its first checkpoint, is not
  taken for a rodjit file: ``--resume`` refuses it in one line (exit 2); a sweep file
  appears only whole, and whatever the moment, ``info`` reads it.

CI runs one moment per command and signal (the Dask sweep: SIGINT once); ``-m slow`` runs
more moments of each.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from click.testing import CliRunner

import rodjit
from rodjit.output.summary import summarize
from conftest import assert_same_files, same_table
from rodjit import cli

SEED = int(os.environ.get("RODJIT_HOSTILE_SEED", "20261205"))
TIMEOUT = 180          # seconds: any command still running then has hung
RUN = ["--set", "rod.N=200", "--set", "time.t_end=30", "--set", "rod.mu=1", "--set",
       "output.snapshot_interval=0.05", "-q", "--flush-interval", "0.05"]
GRID = ["--grid", "rod.mu=1,2,3,4,5,6", "--set", "time.t_end=4", "-q"]
POOL = ["-j", "2"]
DASK = ["--scheduler", "local", "-j", "2"]
SIGNALS = {"SIGINT": signal.SIGINT, "SIGTERM": signal.SIGTERM, "SIGKILL": signal.SIGKILL}


def invoke(*args):
    return CliRunner().invoke(cli.main, [str(a) for a in args])


def _start(args, cwd) -> subprocess.Popen:
    """``python -m rodjit ARGS`` in its own process group (so that whatever it leaves
    behind, e.g. the workers of a killed sweep, can be ended with it)."""
    return subprocess.Popen([sys.executable, "-m", "rodjit", *map(str, args)], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)


def _end(p: subprocess.Popen) -> tuple[str, str]:
    """Wait for ``p`` (a hang fails the test), then end its process group."""
    try:
        out, err = p.communicate(timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        pytest.fail(f"the command hung ({TIMEOUT} s after the signal)")
    try:
        os.killpg(p.pid, signal.SIGKILL)      # leftovers of a killed main process
    except ProcessLookupError:
        pass
    return out, err


def _timed(args, cwd, out) -> float:
    """Run ``args`` to its end; its wall time from the moment its file ``out`` appears
    to its exit (the span the signals are sent in)."""
    p = _start(args, cwd)
    while not out.exists() and p.poll() is None:
        time.sleep(0.002)
    start = time.monotonic()
    _, err = _end(p)
    assert p.returncode == 0, err
    return time.monotonic() - start


def _interrupt(args, cwd, out, sig: int, delay: float) -> subprocess.Popen:
    """Start ``args`` and send ``sig`` ``delay`` seconds after its file ``out`` appears
    (or after it has ended); checks the exit code and stderr against the contract.  An
    ``out`` that exists already (a resume) counts from the moment the command takes its
    writer lock (``.NAME.lock`` beside it), when it starts to work on the file."""
    ready = out.with_name(f".{out.name}.lock") if out.exists() else out
    p = _start(args, cwd)
    deadline = time.monotonic() + TIMEOUT
    while not ready.exists() and p.poll() is None:
        assert time.monotonic() < deadline, "the output file never appeared"
        time.sleep(0.002)
    time.sleep(delay)
    if p.poll() is None:
        p.send_signal(sig)
    _, err = _end(p)
    print(f"[{' '.join(map(str, args[:2]))} {signal.Signals(sig).name} +{delay:.2f}s: exit "
          f"{p.returncode}]")
    assert "Traceback" not in err and "Exception ignored" not in err, err
    lines = err.strip().splitlines()
    name = signal.Signals(sig).name
    if p.returncode == 0:                 # it had finished
        assert lines == [], err
    elif sig == signal.SIGKILL:
        assert p.returncode == -signal.SIGKILL and lines == [], err
    else:
        assert p.returncode == 128 + sig, err
        assert len(lines) == 1 and f"interrupted by {name}" in lines[0], err
    return p


def _moments(kind: str, n: int, signals) -> list[tuple[str, float]]:
    """(signal name, fraction of the uninterrupted wall time) draws for ``kind``."""
    rng = np.random.default_rng([SEED, sum(map(ord, kind))])
    return [(s, float(rng.uniform(0.0, 1.1))) for _ in range(n) for s in signals]


def _ids(cases):
    return [f"{s}-at-{f:.2f}" for s, f in cases]


# ---- runs ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def run_ref(tmp_path_factory):
    """The uninterrupted run, and its wall time (the span the moments are drawn over)."""
    d = tmp_path_factory.mktemp("signals_run")
    wall = _timed(["run", *RUN, "-o", "ref.h5"], d, d / "ref.h5")
    return d / "ref.h5", wall


def _complete_run(path, ref) -> None:
    """The run file after a signal: complete and the same run, or continued to be."""
    try:
        status = summarize(path).status
    except ValueError:
        # killed while the file was being created: not a rodjit file, nothing to continue
        r = invoke("run", "--resume", path, "-q")
        assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1, r.output
        return
    for _ in range(3):
        if status == "completed":
            break
        r = invoke("run", "--resume", path, "-q")
        assert r.exit_code == 0, r.output
        status = summarize(path).status
    assert status == "completed"
    assert_same_files(path, ref)


RUN_CASES = _moments("run", 1, SIGNALS)
RUN_MORE = _moments("run more", 4, SIGNALS)


def _run_case(run_ref, tmp_path, name, frac):
    ref, wall = run_ref
    out = tmp_path / "x.h5"
    _interrupt(["run", *RUN, "-o", out.name], tmp_path, out, SIGNALS[name], frac * wall)
    _complete_run(out, ref)


@pytest.mark.parametrize("name,frac", RUN_CASES, ids=_ids(RUN_CASES))
def test_signal_during_a_run(run_ref, tmp_path, name, frac):
    _run_case(run_ref, tmp_path, name, frac)


@pytest.mark.slow
@pytest.mark.parametrize("name,frac", RUN_MORE, ids=_ids(RUN_MORE))
def test_signal_during_a_run_more(run_ref, tmp_path, name, frac):
    _run_case(run_ref, tmp_path, name, frac)


@pytest.fixture(scope="module")
def interrupted_run(run_ref, tmp_path_factory):
    """A run stopped early by SIGINT (its file interrupted, with a checkpoint)."""
    d = tmp_path_factory.mktemp("signals_resume")
    out = d / "cut.h5"
    for delay in (0.3, 0.1, 0.0):
        out.unlink(missing_ok=True)
        p = _interrupt(["run", *RUN, "-o", out.name], d, out, signal.SIGINT, delay)
        if p.returncode == 130:
            return out
    pytest.skip("the run ended before SIGINT reached it three times")


RESUME_CASES = _moments("resume", 1, SIGNALS)
RESUME_MORE = _moments("resume more", 3, SIGNALS)


def _resume_case(run_ref, interrupted_run, tmp_path, name, frac):
    """A resume signalled at a random moment, then resumed again: the uninterrupted run."""
    ref, wall = run_ref
    out = tmp_path / "x.h5"
    out.write_bytes(interrupted_run.read_bytes())
    _interrupt(["run", "--resume", out.name, "-q", "--flush-interval", "0.05"], tmp_path,
               out, SIGNALS[name], frac * wall)
    _complete_run(out, ref)


@pytest.mark.parametrize("name,frac", RESUME_CASES, ids=_ids(RESUME_CASES))
def test_signal_during_a_resume(run_ref, interrupted_run, tmp_path, name, frac):
    _resume_case(run_ref, interrupted_run, tmp_path, name, frac)


@pytest.mark.slow
@pytest.mark.parametrize("name,frac", RESUME_MORE, ids=_ids(RESUME_MORE))
def test_signal_during_a_resume_more(run_ref, interrupted_run, tmp_path, name, frac):
    _resume_case(run_ref, interrupted_run, tmp_path, name, frac)


# ---- sweeps -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def sweep_ref(tmp_path_factory):
    """The uninterrupted sweep on the process pool, and its wall time."""
    d = tmp_path_factory.mktemp("signals_sweep")
    wall = _timed(["sweep", *GRID, *POOL, "-o", "ref.h5"], d, d / "ref.h5")
    return rodjit.load_sweep(d / "ref.h5"), wall




def _complete_sweep(path, ref) -> None:
    table = rodjit.load_sweep(path)      # whatever the moment, the file there reads
    assert invoke("info", path).exit_code == 0
    for _ in range(3):
        if table.status == "completed":
            break
        r = invoke("sweep", "--resume", "-o", path, "-q", "--scheduler", "inline")
        assert r.exit_code == 0, r.output
        table = rodjit.load_sweep(path)
    assert table.status == "completed" and table.counts["completed"] == len(ref)
    same_table(table, ref)


def _sweep_case(sweep_ref, tmp_path, name, frac, executor):
    ref, wall = sweep_ref
    out = tmp_path / "s.h5"
    _interrupt(["sweep", *GRID, *executor, "-o", out.name], tmp_path, out, SIGNALS[name],
               frac * wall)
    if not out.exists():            # its creation was cut: nothing is left
        return
    _complete_sweep(out, ref)


SWEEP_CASES = _moments("sweep", 1, SIGNALS)
SWEEP_MORE = _moments("sweep more", 3, SIGNALS)


@pytest.mark.parametrize("name,frac", SWEEP_CASES, ids=_ids(SWEEP_CASES))
def test_signal_during_a_sweep(sweep_ref, tmp_path, name, frac):
    _sweep_case(sweep_ref, tmp_path, name, frac, POOL)


@pytest.mark.slow
@pytest.mark.parametrize("name,frac", SWEEP_MORE, ids=_ids(SWEEP_MORE))
def test_signal_during_a_sweep_more(sweep_ref, tmp_path, name, frac):
    _sweep_case(sweep_ref, tmp_path, name, frac, POOL)


DASK_CASES = _moments("dask", 1, ["SIGINT"])
DASK_MORE = _moments("dask more", 1, ["SIGINT", "SIGTERM", "SIGKILL"])


@pytest.mark.parametrize("name,frac", DASK_CASES, ids=_ids(DASK_CASES))
def test_signal_during_a_dask_sweep(sweep_ref, tmp_path, name, frac):
    pytest.importorskip("distributed")
    _sweep_case(sweep_ref, tmp_path, name, frac, DASK)


@pytest.mark.slow
@pytest.mark.parametrize("name,frac", DASK_MORE, ids=_ids(DASK_MORE))
def test_signal_during_a_dask_sweep_more(sweep_ref, tmp_path, name, frac):
    pytest.importorskip("distributed")
    _sweep_case(sweep_ref, tmp_path, name, frac, DASK)


def test_sigkill_of_a_dask_sweep_leaves_nothing_on_stderr(sweep_ref, tmp_path):
    """A Dask sweep's main process killed while its cluster holds semaphores: the
    resource tracker of multiprocessing (which outlives it) cleans them up without its
    two-line warning, and the file is continued to the uninterrupted table."""
    pytest.importorskip("distributed")
    out = tmp_path / "s.h5"
    p = _interrupt(["sweep", *GRID, *DASK, "-o", out.name], tmp_path, out, signal.SIGKILL,
                   0.3)
    assert p.returncode in (0, -signal.SIGKILL)
    _complete_sweep(out, sweep_ref[0])


def test_the_resource_trackers_note_is_ignored_beside_the_users_filters(monkeypatch):
    """The filter joins the user's own PYTHONWARNINGS (once), never replaces it."""
    from rodjit import entry

    monkeypatch.setenv("PYTHONWARNINGS", "error::DeprecationWarning")
    entry._quiet_resource_tracker()
    entry._quiet_resource_tracker()
    assert os.environ["PYTHONWARNINGS"] == f"error::DeprecationWarning,{entry._QUIET_TRACKER}"
