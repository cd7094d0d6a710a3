"""One writer per file: two real processes started together on one output, new or
existing, ``--overwrite`` or ``--resume``: exactly one writes, the other is refused with one
line (exit 2) and the file stays intact."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

import rodjit
from rodjit.output import lock

LONG = ["--set", "rod.N=200", "--set", "time.t_end=1000", "--set", "output.snapshot_interval=0",
        "--set", "output.diagnostics_interval=0.5", "-q"]


def _start(*args, cwd):
    return subprocess.Popen([sys.executable, "-m", "rodjit", *map(str, args)], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _race(cwd, args):
    """Start two identical commands together; when one has ended, stop the other with
    SIGTERM; return (loser, winner) as (returncode, stderr) pairs."""
    procs = [_start(*args, cwd=cwd), _start(*args, cwd=cwd)]
    try:
        deadline = time.monotonic() + 120
        while all(p.poll() is None for p in procs) and time.monotonic() < deadline:
            time.sleep(0.05)
        first = next(p for p in procs if p.poll() is not None)
        other = procs[1 - procs.index(first)]
        other.send_signal(signal.SIGTERM)
        out = [(p.wait(timeout=120), p.communicate()[1]) for p in (first, other)]
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    return out


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.slow
@pytest.mark.parametrize("existing", [False, True])
def test_two_runs_started_together_one_writes(tmp_path, existing):
    out = tmp_path / "same.h5"
    args = ["run", "-o", out, *LONG]
    if existing:
        rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.05}), out)
        args.append("--overwrite")
    (rc_lost, err_lost), (rc_won, err_won) = _race(tmp_path, args)
    assert rc_lost == 2        # refused by the lock, or (new path) by the file it created
    # the lock refuses it, or, if it gets there once the winner holds the lock (a start
    # that compiles nothing is that fast), the check of the output path before it
    assert ("is being written by process" in _one_line(err_lost)
            or (existing and "is being written by a running rodjit process" in err_lost)
            or (not existing and "already exists" in err_lost))
    assert rc_won == 128 + signal.SIGTERM
    assert "interrupted by SIGTERM" in _one_line(err_won)
    s = rodjit.load_file(out)               # the winner's file, whole and resumable
    assert s.status == "interrupted"
    with rodjit.output.hdf5.open_file(out) as f:
        ck = rodjit.output.hdf5.read_checkpoint(f)
        n = ck["lengths"]["diagnostics"]
        t = f["diagnostics"]["t"][:n]
    assert n > 0 and (t[1:] > t[:-1]).all()   # one writer's rows, in order


def test_a_resume_and_an_overwrite_of_a_file_being_written_are_refused(tmp_path):
    out = tmp_path / "r.h5"
    writer = _start("run", "-o", out, *LONG, cwd=tmp_path)
    try:
        deadline = time.monotonic() + 120
        while not (out.exists() and lock.is_locked(out)) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert lock.is_locked(out)
        for args in (["run", "--resume", out], ["run", "-o", out, "--overwrite", "-q"],
                     ["sweep", "--grid", "rod.mu=0,1", "-o", out, "--overwrite", "-q"]):
            r = subprocess.run([sys.executable, "-m", "rodjit", *map(str, args)],
                               capture_output=True, text=True, timeout=120)
            assert r.returncode == 2, (args, r.stderr)
            assert "being written by" in _one_line(r.stderr)
    finally:
        writer.send_signal(signal.SIGTERM)
        rc = writer.wait(timeout=120)
    assert rc == 128 + signal.SIGTERM
    assert not lock.is_locked(out)            # the kernel dropped it with the process
    assert rodjit.load_file(out).status == "interrupted"


def test_two_sweeps_started_together_on_one_file_one_writes(tmp_path):
    out = tmp_path / "s.h5"
    args = ["sweep", "--grid", "time.t_end=1000,1001,1002", "--set", "rod.N=200", "--set",
            "output.snapshot_interval=0", "--set", "output.diagnostics_interval=0",
            "-o", out, "-j", "1", "-q"]
    (rc_lost, err_lost), (rc_won, err_won) = _race(tmp_path, args)
    assert rc_lost == 2
    line = _one_line(err_lost)
    assert "is being written by process" in line or "already exists" in line
    assert rc_won == 128 + signal.SIGTERM
    assert rodjit.load_sweep(out).status == "interrupted"


def test_the_lock_file_names_its_holder_and_is_dropped_on_release(tmp_path):
    out = tmp_path / "x.h5"
    with lock.WriterLock(out):
        assert lock.is_locked(out)
        with pytest.raises(lock.FileBusy, match="being written by process"):
            lock.WriterLock(out).acquire()
    assert not lock.is_locked(out)
    assert lock.lock_path(out).name == ".x.h5.lock"
    assert not lock.lock_path(out).exists()      # removed on release


def test_a_second_writer_names_a_holder_that_has_just_taken_the_lock(tmp_path):
    """The holder writes its id just after it takes the lock; a writer refused in between
    still names it (it was told "another process" by chance)."""
    import fcntl
    import threading

    out = tmp_path / "x.h5"
    fd = os.open(lock.lock_path(out), os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)   # taken, no id written yet
        late = threading.Timer(0.2, lambda: os.pwrite(fd, b"4242\n", 0))
        late.start()
        with pytest.raises(lock.FileBusy, match="being written by process 4242 "):
            lock.WriterLock(out).acquire()
        late.join()
    finally:
        os.close(fd)
