"""A streamed run's compiled calls and the writing of their blocks (``driver.files``), in
the calling thread: a block refused at its drain, a signal at any moment or before the
first call, each leaving a file that holds its last checkpoint (and resumes to the
uninterrupted run); the compiled call releases the GIL."""
import os
import signal
import threading
import time

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.driver.run import Run
from rodjit.output import hdf5
from rodjit.stepping import layout as L

from conftest import assert_same_files, final_state

JIT = os.environ.get("NUMBA_DISABLE_JIT", "0") in ("", "0")


def test_a_streamed_run_keeps_to_the_calling_thread(tmp_path, monkeypatch, many_calls):
    """Every compiled call runs in the caller's thread, and no thread is started."""
    compute, where = Run.compute, []

    def recorded(self, max_steps=None):
        where.append((threading.current_thread() is threading.main_thread(),
                      threading.active_count()))
        return compute(self, max_steps)
    monkeypatch.setattr(Run, "compute", recorded)
    before = threading.active_count()
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 1.0}), tmp_path / "r.h5")
    assert len(where) > 5 and set(where) == {(True, before)}


def test_a_block_refused_at_its_drain_keeps_its_rows_and_no_new_checkpoint(tmp_path,
                                                                          monkeypatch,
                                                                          many_calls):
    """A block refused at the drain (non-finite diagnostics) stops the run with nothing
    computed beyond it and no new checkpoint."""
    # rtol 1e-3: the energy step's error per unit step then takes about the steps per
    # output interval that these block counts were laid out for
    cfg = rodjit.Config().override({"time.t_end": 1.0, "time.rtol": 1e-3,
                                    "time.integrator": "energy"})
    take = Run.take

    def poisoned(self, code=L.PAUSED):
        block = take(self, code)
        self._takes = getattr(self, "_takes", 0) + 1
        if self._takes == 9 and block.diagnostics.shape[0]:
            block.diagnostics[-1, 2] = np.nan
            block.finite = False
        return block
    monkeypatch.setattr(Run, "take", poisoned)
    with pytest.raises(rodjit.SimulationError) as info:
        rodjit.run_to_file(cfg, tmp_path / "r.h5", flush_interval=1e-9)
    s = info.value.summary
    assert s.status == "failed" and "non-finite diagnostic" in s.message
    with h5py.File(tmp_path / "r.h5", "r") as f:
        ck = hdf5.read_checkpoint(f)
        assert f["snapshots/t"].shape[0] > ck["lengths"]["snapshots"]   # the block's rows kept
        assert f["diagnostics/t"].shape[0] == ck["lengths"]["diagnostics"]  # refused ones not


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_while_a_block_computes_then_resume_bit_for_bit(tmp_path, many_calls,
                                                               signum):
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
    # energy: 200 000 steps of it fill no buffer (dop853's events would)
    run = Run(rodjit.Config().override({"rod.N": 200, "time.t_end": 100.0,
                                        "time.integrator": "energy",
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
