"""Compiled calls in a worker thread while the file is written (driver.pipeline): the same
file bit for bit as serial calls, through checkpoints, stops and failures; the next block
really computes while the last one is written; the compiled call releases the GIL."""
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import h5py
import numpy as np
import pytest

import rodjit
import rodjit.driver.files as files
from rodjit.driver import pipeline
from rodjit.driver.run import Run
from rodjit.output import hdf5, run_writer
from rodjit.stepping import layout as L

from conftest import assert_same_files, final_state

# a fixed explicit step through the floor (the energy step stays admissible)
FAILING = {"time.dt": 1e-3, "initial.velocity": -100.0, "time.integrator": "verlet"}
CASES = {
    "default": {"time.t_end": 1.0},
    "viscous, dense diagnostics": {"time.t_end": 0.6, "rod.N": 12, "rod.mu": 5.0,
                                   "time.integrator": "semi-implicit",
                                   "output.diagnostics_interval": 0.0007},
    "failing": FAILING,
    "lzf": {"time.t_end": 0.5, "output.compression": "lzf"},
}
JIT = os.environ.get("NUMBA_DISABLE_JIT", "0") in ("", "0")


@pytest.fixture
def every_call_overlapped(monkeypatch):
    """Every call in the worker thread, however short (the tests cut runs into tiny calls,
    which would otherwise run inline)."""
    monkeypatch.setattr(pipeline, "HANDOFF", 0.0)


def _to_file(cfg, path, overlap, monkeypatch, **kwargs):
    """run_to_file with or without the worker thread; the summary, also of a failed run."""
    monkeypatch.setattr(files, "OVERLAP", overlap)
    try:
        return rodjit.run_to_file(cfg, path, **kwargs)
    except (rodjit.SimulationError, rodjit.RunInterrupted) as exc:
        return exc.summary


def _attrs(path):
    with h5py.File(path, "r") as f:
        return {k: f.attrs[k] for k in ("status", "message", "format_version")}


@pytest.mark.parametrize("flush_interval", [1e-9, files.RUN_FLUSH_INTERVAL],
                         ids=["checkpoint-every-call", "default-checkpoints"])
@pytest.mark.parametrize("case", CASES)
def test_pipelined_file_equals_serial_bit_for_bit(tmp_path, monkeypatch, many_calls, case,
                                                  flush_interval, every_call_overlapped):
    cfg = rodjit.Config().override(CASES[case])
    serial = _to_file(cfg, tmp_path / "serial.h5", False, monkeypatch,
                      flush_interval=flush_interval)
    piped = _to_file(cfg, tmp_path / "piped.h5", True, monkeypatch,
                     flush_interval=flush_interval)
    assert_same_files(tmp_path / "piped.h5", tmp_path / "serial.h5")
    assert _attrs(tmp_path / "piped.h5") == _attrs(tmp_path / "serial.h5")
    assert piped.status == serial.status == ("failed" if case == "failing" else "completed")
    assert piped.report().split("\n")[1:-2] == serial.report().split("\n")[1:-2]  # not timings


def test_failed_drain_mid_pipeline_keeps_the_same_rows_as_serial(tmp_path, monkeypatch,
                                                                 many_calls,
                                                                 every_call_overlapped):
    """A block refused at the drain (non-finite diagnostics) stops the run with nothing
    computed beyond it and no new checkpoint, pipelined or not."""
    # rtol 1e-3: the energy step's error per unit step then takes about the steps per
    # output interval that these block counts were laid out for
    cfg = rodjit.Config().override({"time.t_end": 1.0, "time.rtol": 1e-3})
    take = Run.take

    def poisoned(self, code=L.PAUSED):
        block = take(self, code)
        self._takes = getattr(self, "_takes", 0) + 1
        if self._takes == 9 and block.diagnostics.shape[0]:
            block.diagnostics[-1, 2] = np.nan
            block.finite = False
        return block
    monkeypatch.setattr(Run, "take", poisoned)
    for overlap, name in ((False, "serial.h5"), (True, "piped.h5")):
        s = _to_file(cfg, tmp_path / name, overlap, monkeypatch, flush_interval=1e-9)
        assert s.status == "failed" and "non-finite diagnostic" in s.message
    assert_same_files(tmp_path / "piped.h5", tmp_path / "serial.h5")
    with h5py.File(tmp_path / "piped.h5", "r") as f:
        ck = hdf5.read_checkpoint(f)
        assert f["snapshots/t"].shape[0] > ck["lengths"]["snapshots"]   # the block's rows kept
        assert f["diagnostics/t"].shape[0] == ck["lengths"]["diagnostics"]  # refused ones not


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_while_a_block_computes_then_resume_bit_for_bit(tmp_path, monkeypatch,
                                                               many_calls, signum,
                                                               every_call_overlapped):
    """The signal comes from another thread at an arbitrary moment (a call computing, a
    block draining); the run stops at the next boundary with a final checkpoint."""
    cfg = rodjit.Config().override({"time.t_end": 1.0})
    ref, cut = tmp_path / "ref.h5", tmp_path / "cut.h5"
    rodjit.run_to_file(cfg, ref)
    calls = {"n": 0}

    def progress(run):
        calls["n"] += 1
        if calls["n"] == 4:
            threading.Timer(0.002, os.kill, (os.getpid(), signum)).start()
    with pytest.raises(rodjit.RunInterrupted) as info:
        rodjit.run_to_file(cfg, cut, progress=progress, flush_interval=1e-9)
    assert info.value.signum == signum and 0 < info.value.summary.t < 1.0
    with h5py.File(cut, "r") as f:
        ck = hdf5.read_checkpoint(f)
        assert f.attrs["status"] == "interrupted"
        assert ck["lengths"]["snapshots"] == f["snapshots/t"].shape[0]   # every row saved
    rodjit.resume_file(cut)
    assert_same_files(cut, ref)


def _counter():
    """A count that threads can wait on."""
    cond = threading.Condition()
    state = {"n": 0}

    def bump():
        with cond:
            state["n"] += 1
            cond.notify_all()

    def wait_for(n, timeout=30.0):
        with cond:
            return cond.wait_for(lambda: state["n"] >= n, timeout)
    return bump, wait_for


def test_the_next_block_computes_while_the_last_is_written(tmp_path, monkeypatch, many_calls,
                                                          every_call_overlapped):
    """Each drain waits until the call after it has finished: serially that never happens
    (it would time out), pipelined it does for every block but the last."""
    monkeypatch.setattr(files, "OVERLAP", True)
    bump, wait_for = _counter()
    compute, snapshots = Run.compute, hdf5.RunWriter.snapshots
    threads, overlapped = set(), []

    def counted(self, max_steps=None):
        threads.add(threading.current_thread() is threading.main_thread())
        code = compute(self, max_steps)
        bump()
        return code

    def waiting(self, *cols):
        overlapped.append(wait_for(len(overlapped) + 2, timeout=2.0))
        return snapshots(self, *cols)
    monkeypatch.setattr(Run, "compute", counted)
    monkeypatch.setattr(hdf5.RunWriter, "snapshots", waiting)
    cfg = rodjit.Config().override({"time.t_end": 0.5, "output.snapshot_interval": 0.001,
                                    "time.rtol": 1e-4})
    rodjit.run_to_file(cfg, tmp_path / "r.h5")
    assert threads == {False}                      # every call ran in the worker thread
    assert len(overlapped) > 5 and all(overlapped[:-1]) and not overlapped[-1]
    assert np.array_equal(rodjit.load_file(tmp_path / "r.h5").t,
                          rodjit.simulate(cfg).t)


def test_tiny_calls_run_inline_and_give_the_same_file(tmp_path, monkeypatch, many_calls):
    """Calls far shorter than a thread handoff run in the caller's thread after the first
    one (which overlaps the file's creation); the file is the same bit for bit."""
    cfg = rodjit.Config().override({"time.t_end": 1.0})
    _to_file(cfg, tmp_path / "serial.h5", False, monkeypatch)
    compute, where = Run.compute, []

    def recorded(self, max_steps=None):
        where.append(threading.current_thread() is threading.main_thread())
        return compute(self, max_steps)
    monkeypatch.setattr(Run, "compute", recorded)
    _to_file(cfg, tmp_path / "piped.h5", True, monkeypatch)
    assert where[0] is False and len(where) > 10 and all(where[1:])
    assert_same_files(tmp_path / "piped.h5", tmp_path / "serial.h5")


def test_the_layout_is_created_while_the_first_block_computes(tmp_path, monkeypatch):
    monkeypatch.setattr(files, "OVERLAP", True)
    bump, wait_for = _counter()
    compute, create = Run.compute, run_writer.create_run_file
    seen = []

    def counted(self, max_steps=None):
        code = compute(self, max_steps)
        bump()
        return code

    def creating(*args, **kwargs):
        seen.append(wait_for(1, timeout=5.0))      # the first call ends before the file exists
        return create(*args, **kwargs)
    monkeypatch.setattr(Run, "compute", counted)
    monkeypatch.setattr(run_writer, "create_run_file", creating)
    summary = rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.5}),
                                 tmp_path / "r.h5")
    assert seen == [True] and summary.status == "completed"
    assert final_state(tmp_path / "r.h5")["lengths"][0] == 101   # t0's snapshot included


def test_a_signal_before_the_first_call_still_leaves_a_checkpointed_file(tmp_path,
                                                                         monkeypatch):
    """SIGINT during compilation: no call is launched, the file is created and closed
    interrupted at t0, and resumes to the uninterrupted run."""
    cfg = rodjit.Config().override({"time.t_end": 0.5})
    ref, cut = tmp_path / "ref.h5", tmp_path / "cut.h5"
    rodjit.run_to_file(cfg, ref)
    start = Run.start

    def interrupted_start(self, sink):
        start(self, sink)
        os.kill(os.getpid(), signal.SIGINT)
    monkeypatch.setattr(Run, "start", interrupted_start)
    with pytest.raises(rodjit.RunInterrupted):
        rodjit.run_to_file(cfg, cut)
    monkeypatch.undo()
    state = final_state(cut)
    assert state["clock"][L.T] == 0.0 and state["count"][L.STARTED] == 1
    assert state["lengths"][0] == 1                   # the snapshot at t0
    rodjit.resume_file(cut)
    assert_same_files(cut, ref)


@pytest.mark.skipif(not JIT, reason="plain-Python kernels hold the GIL")
def test_the_compiled_call_releases_the_gil():
    """While a long compiled call runs in another thread, this thread keeps running Python
    (it could not if the call held the GIL: Python cannot take it back from native code)."""
    run = Run(rodjit.Config().override({"rod.N": 200, "time.t_end": 100.0,
                                        "output.snapshot_interval": 0.0,
                                        "output.diagnostics_interval": 0.0}))
    run.start(None)
    span = {}

    def call():
        t0 = time.perf_counter()
        run.compute(200_000)
        span["call"] = (t0, time.perf_counter())
    worker = threading.Thread(target=call)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    t0, t1 = span["call"]
    inside = [t for t in ticks if t0 + 0.25 * (t1 - t0) < t < t1 - 0.25 * (t1 - t0)]
    assert run.steps == 200_000 and len(inside) > 100


NO_JIT_SCRIPT = textwrap.dedent("""
    import sys, h5py, numpy as np, rodjit
    import rodjit.driver.files as files
    cfg = rodjit.Config().override({"time.t_end": 0.05, "rod.N": 4})
    for overlap, name in ((False, "serial.h5"), (True, "piped.h5")):
        files.OVERLAP = overlap
        rodjit.run_to_file(cfg, sys.argv[1] + "/" + name, flush_interval=1e-9)
    a = {}
    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and not name.startswith("checkpoint/slot"):
            a.setdefault(name, []).append(obj[()])
    for name in ("serial.h5", "piped.h5"):
        with h5py.File(sys.argv[1] + "/" + name, "r") as f:
            f.visititems(visit)
    same = all(len(v) == 2 and np.array_equal(v[0], v[1]) for v in a.values())
    print("same" if same and len(a) > 30 else "different")
""")


def test_pipeline_with_jit_disabled(tmp_path):
    """The kernels as plain Python (NUMBA_DISABLE_JIT=1) run in the worker thread too."""
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", NO_JIT_SCRIPT, str(tmp_path)], env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.strip() == "same"


def test_overlap_false_keeps_the_run_on_the_calling_thread(tmp_path, monkeypatch, many_calls,
                                                           every_call_overlapped):
    """run_to_file(overlap=False), as a sweep's workers call it, starts no thread whatever
    the module default; overlap=True does, and both files are the same."""
    import threading

    monkeypatch.setattr(files, "OVERLAP", True)
    cfg = rodjit.Config().override({"time.t_end": 0.3})
    seen = {}

    def progress(tag):
        def call(run):
            seen[tag] = max(seen.get(tag, 0), threading.active_count())
        return call
    base = threading.active_count()
    rodjit.run_to_file(cfg, tmp_path / "one.h5", overlap=False, progress=progress("one"))
    rodjit.run_to_file(cfg, tmp_path / "two.h5", overlap=True, progress=progress("two"))
    assert seen["one"] == base and seen["two"] > base
    assert_same_files(tmp_path / "one.h5", tmp_path / "two.h5")
