"""run_to_file / resume_file: interruption, resume bit for bit, failure, validation, memory."""
import os
import re
import signal
import socket
import subprocess
import sys
import textwrap

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.output import run_layout
from rodjit.output import h5files, hdf5, writer_id
from rodjit.stepping import layout as L

from conftest import assert_same_files, datasets, final_state, rodjit_cli

# a fixed explicit step through the floor (the energy step stays admissible)
FAILING = {"time.dt": 1e-3, "initial.velocity": -100.0, "time.integrator": "verlet"}


def _interrupt_at(call: int, signum=signal.SIGINT):
    """A progress callback that sends ``signum`` to this process at compiled call ``call``."""
    state = {"n": 0}

    def progress(run):
        state["n"] += 1
        if state["n"] == call:
            os.kill(os.getpid(), signum)
    return progress


@pytest.mark.parametrize("call", [1, 7, 15])
def test_interrupt_and_resume_bit_for_bit(tmp_path, small_config, many_calls, call):
    ref, cut = tmp_path / "ref.h5", tmp_path / "cut.h5"
    rodjit.run_to_file(small_config, ref)
    with pytest.raises(rodjit.RunInterrupted) as info:
        rodjit.run_to_file(small_config, cut, progress=_interrupt_at(call))
    assert info.value.signum == signal.SIGINT
    s = info.value.summary
    assert s.status == "interrupted" and "rodjit run --resume" in s.message
    assert 0 < s.t < 1.0
    with h5py.File(cut, "r") as f:
        assert f.attrs["status"] == "interrupted"
    summary = rodjit.resume_file(cut)
    assert summary.status == "completed" and summary.t == 1.0
    assert_same_files(cut, ref)
    with h5py.File(cut, "r") as f:
        assert "resumed at t" in f.attrs["history"][-1]


def test_interrupt_in_contact_lists_open_bounce_then_drops_it(tmp_path, small_config,
                                                              many_calls):
    """Stopped during contact, the file lists the bounce as open; the resume removes that
    provisional row and the final tables equal an uninterrupted run's."""
    ref, cut = tmp_path / "ref.h5", tmp_path / "cut.h5"
    rodjit.run_to_file(small_config, ref)
    state = {"sent": False}

    def progress(run):
        if not state["sent"] and run.arrays.ev[L.IN_CONTACT]:
            state["sent"] = True
            os.kill(os.getpid(), signal.SIGTERM)
    with pytest.raises(rodjit.RunInterrupted) as info:
        rodjit.run_to_file(small_config, cut, progress=progress)
    assert info.value.signum == signal.SIGTERM
    res = rodjit.load_file(cut)
    assert res.bounces["open"][-1] and res.n_bounces == final_state(cut)["count"][
        L.BOUNCES_TOTAL] + 1
    rodjit.resume_file(cut)
    assert_same_files(cut, ref)


def test_resume_truncates_rows_written_after_the_checkpoint(tmp_path, small_config,
                                                            many_calls):
    ref, cut = tmp_path / "ref.h5", tmp_path / "cut.h5"
    rodjit.run_to_file(small_config, ref)
    with pytest.raises(rodjit.RunInterrupted):
        rodjit.run_to_file(small_config, cut, progress=_interrupt_at(5))
    with h5py.File(cut, "r+") as f:    # as if the writer died between data and checkpoint
        for group, cols in hdf5.TABLES.items():
            for c in cols:
                ds = f[group][c]
                ds.resize(ds.shape[0] + 3, axis=0)
                ds[-3:] = 7
    rodjit.resume_file(cut)
    assert_same_files(cut, ref)


@pytest.mark.parametrize("integrator", ["energy", "auto"])
def test_extend_a_completed_run(tmp_path, small_config, integrator):
    """An extension equals a run to the new end at once, bit for bit, for an integrator
    that lands on the output times; auto's (dop853, dense output) steps toward t_end, so
    its extension continues from the 1 s run's own last step: the same to its tolerance."""
    small_config = small_config.override({"time.integrator": integrator})
    short, long_ = tmp_path / "short.h5", tmp_path / "long.h5"
    # the extension keeps what "auto" chose for the 1 s run (its tolerances): so does this
    rodjit.run_to_file(small_config.resolve().override({"time.t_end": 2.0}), long_)
    rodjit.run_to_file(small_config, short)
    with pytest.raises(ValueError, match="already complete at t = 1; give a later t_end"):
        rodjit.resume_file(short)
    rodjit.resume_file(short, t_end=2.0)
    assert rodjit.load_file(short).config.time.t_end == 2.0
    a, b = datasets(short), datasets(long_)
    if integrator == "auto":
        assert rodjit.load_file(short).config.time.integrator == "dop853"
        assert np.array_equal(a["snapshots/t"], b["snapshots/t"])
        assert np.abs(a["snapshots/u"] - b["snapshots/u"]).max() < 1e-5
        return
    # t = 1 is on both output grids, so the extension takes the same steps
    for name in b:
        assert np.array_equal(a[name], b[name], equal_nan=True), name


def test_failure_keeps_data_and_records_status(tmp_path):
    cfg = rodjit.Config().override(FAILING)
    path = tmp_path / "fail.h5"
    with pytest.raises(rodjit.SimulationError, match="fixed step time.dt") as info:
        rodjit.run_to_file(cfg, path)
    s = info.value.summary
    assert s.status == "failed" and "bending limit" in s.message
    res = rodjit.load_file(path)
    assert res.status == "failed" and res.message == s.message
    with pytest.raises(rodjit.SimulationError) as mem:
        rodjit.simulate(cfg)
    expected = mem.value.result       # everything up to the failure, as in memory
    assert res.t.size > 0
    assert np.array_equal(res.t, expected.t) and np.array_equal(res.u, expected.u)
    assert res.t_final == expected.t_final == s.t


def test_validation_writes_nothing(tmp_path):
    out = tmp_path / "out.h5"
    with pytest.raises(ValueError, match="time.t_end = -1.0 is out of range"):
        rodjit.run_to_file(rodjit.Config(), out, t_end=-1.0)
    with pytest.raises(ValueError, match="output directory .* does not exist"):
        rodjit.run_to_file(rodjit.Config(), tmp_path / "no" / "out.h5")
    with pytest.raises(ValueError, match="is a directory"):
        rodjit.run_to_file(rodjit.Config(), tmp_path)
    with pytest.raises(ValueError, match="flush_interval = 0 is out of range"):
        rodjit.run_to_file(rodjit.Config(), out, flush_interval=0)
    assert list(tmp_path.iterdir()) == []


def test_existing_output_needs_overwrite(tmp_path, small_config):
    out = tmp_path / "out.h5"
    out.write_bytes(b"precious")
    with pytest.raises(rodjit.OutputExists, match="already exists; pass overwrite=True"):
        rodjit.run_to_file(small_config, out)
    assert out.read_bytes() == b"precious"
    # overwrite replaces rodjit run files only, never someone else's file
    with pytest.raises(ValueError, match="is not a rodjit file; overwrite=True replaces only"):
        rodjit.run_to_file(small_config, out, overwrite=True)
    assert out.read_bytes() == b"precious"
    out.unlink()
    rodjit.run_to_file(small_config.override({"time.t_end": 0.5}), out)
    rodjit.run_to_file(small_config, out, overwrite=True)
    assert rodjit.load_file(out).status == "completed"


def test_resume_maps_the_scheme_counters_by_name(tmp_path, small_config, many_calls):
    """A file whose checkpoint names other per-scheme counters, in another order (an older
    or newer rodjit), resumes: each counter is matched by name, one this version does not
    count is dropped, and the run continues bit for bit."""
    from rodjit.stepping.registry import SCHEME_STATS

    small_config = small_config.override({"time.integrator": "energy"})   # Newton counters
    ref, cut = tmp_path / "ref.h5", tmp_path / "cut.h5"
    rodjit.run_to_file(small_config, ref)
    with pytest.raises(rodjit.RunInterrupted):
        rodjit.run_to_file(small_config, cut, progress=_interrupt_at(5))
    names = ("retired_counter",) + tuple(reversed(SCHEME_STATS))
    with h5py.File(cut, "r+") as f:
        for slot in ("slot0", "slot1"):
            g = f["checkpoint"][slot]
            old = dict(zip(SCHEME_STATS, g["sstats"][()]))
            del g["sstats"]
            ds = g.create_dataset("sstats", data=np.array(
                [99] + [old[n] for n in reversed(SCHEME_STATS)], np.int64))
            ds.attrs["names"] = np.array(names, dtype=h5py.string_dtype())
            if g["digest"][()].any():      # that rodjit's digest covers its own layout
                g["digest"][...] = run_layout.digest_rows(
                    {n: g[n][()] for n in run_layout.CK_DATASETS}, f.attrs["config_toml"])
        at_cut = old
    assert at_cut["newton_iterations"] > 0
    back = rodjit.load_file(cut).stats
    assert {n: back[n] for n in SCHEME_STATS} == at_cut and "retired_counter" not in back
    assert rodjit.resume_file(cut).status == "completed"
    done, want = rodjit.load_file(cut), rodjit.load_file(ref)
    assert {n: done.stats[n] for n in SCHEME_STATS} == {n: want.stats[n] for n in SCHEME_STATS}
    np.testing.assert_array_equal(done.u, want.u)
    with h5py.File(cut) as f:        # the file keeps its own names, written by name
        g = f["checkpoint"][f"slot{int(f['checkpoint/current'][()])}"]
        assert tuple(n.decode() if isinstance(n, bytes) else n
                     for n in g["sstats"].attrs["names"]) == names
        assert list(g["sstats"][()]) == [0] + [want.stats[n] for n in reversed(SCHEME_STATS)]


def test_resume_errors(tmp_path, small_config, many_calls):
    cut = tmp_path / "cut.h5"
    with pytest.raises(rodjit.RunInterrupted):
        rodjit.run_to_file(small_config, cut, progress=_interrupt_at(3))
    t = final_state(cut)["clock"][L.T]
    before = cut.read_bytes()
    with pytest.raises(ValueError, match="must be > the checkpoint time"):
        rodjit.resume_file(cut, t_end=t / 2)
    assert cut.read_bytes() == before
    with pytest.raises(hdf5.NotARunFile, match="does not exist"):
        rodjit.resume_file(tmp_path / "missing.h5")


KILL_AFTER_SAVE = """
import os, signal, sys, rodjit
from rodjit.driver.run import Run
from rodjit.output import h5files, hdf5, writer_id
from rodjit.stepping import layout as L
cfg = rodjit.Config().override({"time.t_end": 1.0})
run = Run(cfg)
run.max_steps = 20
writer = hdf5.create_run_file(sys.argv[1], run.config, run, command="test")
run.start(writer)
calls = 0
while run.advance(writer) != L.DONE and calls < int(sys.argv[2]):
    calls += 1
writer.save(run)
run.advance(writer)       # rows written after the checkpoint, as between two saves
writer.tables["snapshots"].flush()
writer.file.flush()
if sys.argv[3] == "sleep":  # a writer that is still alive
    print("saved", flush=True)
    signal.pause()
os.kill(os.getpid(), signal.SIGKILL)
"""


@pytest.mark.parametrize("calls", [5, 10**6], ids=["mid-run", "after-the-end"])
def test_killed_writer_is_recovered(tmp_path, calls):
    """A writer killed at a known point (after a checkpoint, with later rows on disk):
    the file opens in SWMR-read mode, and resume_file recovers it and continues bit for
    bit, or only closes it if the checkpoint was already at the end."""
    ref, cut = tmp_path / "ref.h5", tmp_path / "cut.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 1.0}), ref)
    proc = subprocess.run([sys.executable, "-c", KILL_AFTER_SAVE, str(cut), str(calls),
                           "kill"], timeout=300)
    assert proc.returncode == -signal.SIGKILL
    with h5py.File(cut, "r", swmr=True) as f:
        assert f.attrs["status"] == "running"
        ck = hdf5.read_checkpoint(f)
        assert f["snapshots/t"].shape[0] >= ck["lengths"]["snapshots"] > 0
    summary = rodjit.resume_file(cut)
    assert summary.status == "completed"
    assert_same_files(cut, ref)
    with h5py.File(cut, "r") as f:
        assert "recovered at the checkpoint" in f.attrs["history"][1]
        assert ("closed at its end" if calls > 100 else "resumed at") in f.attrs["history"][2]


def test_resume_refuses_a_file_whose_writer_is_alive(tmp_path):
    cut = tmp_path / "cut.h5"
    proc = subprocess.Popen([sys.executable, "-c", KILL_AFTER_SAVE, str(cut), "3", "sleep"],
                            stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "saved"
        with hdf5.open_file(cut) as f:
            assert hdf5.writer_alive(f) is True and h5files.writer_pid(f) == proc.pid
            assert not {"writer_pid", "writer_host", "writer_tag"} & set(f.attrs)
        before = cut.read_bytes()
        with pytest.raises(hdf5.FileBusy, match=rf"live rodjit process on this machine \(process {proc.pid}\)"):
            rodjit.resume_file(cut)
        with pytest.raises(hdf5.FileBusy, match="being written by a running rodjit process"):
            rodjit.run_to_file(rodjit.Config(), cut, overwrite=True)
        assert cut.read_bytes() == before
        r = rodjit_cli("info", cut)
        assert r.returncode == 0 and "running (the writing process is alive)" in r.stdout
    finally:
        proc.kill()
        proc.wait()
    with hdf5.open_file(cut) as f:
        assert hdf5.writer_alive(f) is False
    assert rodjit.resume_file(cut).status == "completed"


def test_writer_alive_is_not_fooled_by_a_reused_pid(tmp_path, small_config):
    if not h5files.process_tag(os.getpid()):
        pytest.skip("no /proc here to tell two processes with one pid apart")
    path = tmp_path / "r.h5"
    rodjit.run_to_file(small_config, path)
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])

    def alive(**attrs):
        with h5py.File(path, "r+") as f:
            for key, value in attrs.items():
                f.attrs[key] = value
        with h5py.File(path, "r") as f:
            return hdf5.writer_alive(f)
    try:
        record = h5files.writer_attrs(other.pid)
        assert alive(**record) is True
        with h5py.File(path, "r") as f:
            assert h5files.writer_pid(f) == other.pid
        salt, key = record["writer_salt"], writer_id._machine_key()
        reused = writer_id._process_hash(salt, key, other.pid, "another-boot:12345")
        assert alive(writer_process=reused) is False              # same pid, not the writer
        assert alive(**{**record, "writer_machine": "0" * 64}) is None   # another machine
    finally:
        other.kill()
        other.wait()
    assert alive(**record) is False


def test_the_liveness_record_names_neither_host_nor_pid(tmp_path, small_config):
    """A file tells a stranger neither the writer's host name nor its process id: its
    record is salted hashes, different in every session."""
    path = tmp_path / "r.h5"
    rodjit.run_to_file(small_config, path)
    with h5py.File(path, "r") as f:
        first = {k: str(f.attrs[k]) for k in writer_id.WRITER_ATTRS}
        every = " ".join(str(v) for v in f.attrs.values())
    assert not {"writer_pid", "writer_host", "writer_tag"} & set(first)
    assert socket.gethostname() not in every
    assert not re.search(rf"\b{os.getpid()}\b", " ".join(first.values()))
    rodjit.resume_file(path, t_end=small_config.time.t_end * 2)
    with h5py.File(path, "r") as f:
        second = {k: str(f.attrs[k]) for k in writer_id.WRITER_ATTRS}
    assert all(first[k] != second[k] for k in first)    # new salt: sessions do not link


def test_files_of_older_versions_are_judged_by_host_and_pid(tmp_path, small_config):
    """A file that records the writer in the clear (rodjit before the hashed record) is
    still judged by it; a new session replaces it with the hashed record."""
    path = tmp_path / "r.h5"
    rodjit.run_to_file(small_config, path)
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    with h5py.File(path, "r+") as f:
        for k in writer_id.WRITER_ATTRS:
            del f.attrs[k]
        f.attrs.update(writer_host=socket.gethostname(), writer_pid=other.pid,
                       writer_tag=h5files.process_tag(other.pid))
    try:
        with h5py.File(path, "r") as f:
            assert hdf5.writer_alive(f) is True and h5files.writer_pid(f) == other.pid
    finally:
        other.kill()
        other.wait()
    with h5py.File(path, "r") as f:
        assert hdf5.writer_alive(f) is False
    rodjit.resume_file(path, t_end=small_config.time.t_end * 2)
    with h5py.File(path, "r") as f:
        assert not {"writer_pid", "writer_host", "writer_tag"} & set(f.attrs)
        assert set(writer_id.WRITER_ATTRS) <= set(f.attrs)


@pytest.mark.slow
def test_memory_stays_bounded_for_a_10x_longer_run(tmp_path):
    """Peak RSS of a run streaming ~80 MB of snapshots vs one 10x shorter (same process
    setup): growth under 20 MB, so nothing accumulates in memory."""
    script = textwrap.dedent("""
        import resource, sys, rodjit
        cfg = rodjit.Config().override({"rod.N": 50, "output.snapshot_interval": 2e-4,
                                        "time.rtol": 1e-4,
                                        "time.t_end": float(sys.argv[1])})
        rodjit.run_to_file(cfg, sys.argv[2])
        print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    """)
    peak = {}
    for t_end in (2.0, 20.0):
        path = tmp_path / f"m{t_end}.h5"
        out = subprocess.run([sys.executable, "-c", script, str(t_end), str(path)],
                             capture_output=True, text=True, check=True, timeout=300)
        peak[t_end] = int(out.stdout.split()[-1]) / 1024   # KiB -> MiB on Linux
        size = path.stat().st_size / 2**20
        path.unlink()
    assert size > 70                   # the long run really streamed that much data
    assert peak[20.0] - peak[2.0] < 20, peak
