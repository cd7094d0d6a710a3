"""A reader holding the sweep file open (``h5py.File(path, "r")`` in another process, as a
notebook would) while ``rodjit sweep`` runs: HDF5's lock keeps the sweep from writing, and
the sweep goes on computing, says once on stderr why its writes wait, writes every point
once the reader lets go, and exits 0 with the table of a sweep nobody held.  The default
suite holds the file a few seconds past the sweep's last point; ``-m slow`` for a minute
(longer than any wait the sweep could give up after)."""
from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest

import rodjit
from conftest import rodjit_cli, same_table

ARGS = ["sweep", "--grid", "floor.beta=linspace(0.01,0.05,12)", "--set", "time.t_end=3",
        "--set", "rod.N=40", "--set", "time.integrator=verlet", "--set",
        "time.control=cfl", "--scheduler", "inline", "--batch-size", "1", "-q"]
# the reader: opens the file as soon as it can, says so, holds it open for argv[2] seconds
HOLD = """
import os, sys, time
import h5py
while True:
    try:
        f = h5py.File(sys.argv[1], "r")
        break
    except OSError:
        time.sleep(0.005)
print("open", flush=True)
time.sleep(float(sys.argv[2]))
f.close()
"""


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("ref")
    r = rodjit_cli(*ARGS, "-o", "s.h5", cwd=d)
    assert r.returncode == 0, r.stderr
    return rodjit.load_sweep(d / "s.h5")


def _start(out, seconds: float):
    """The reader holding ``out`` for ``seconds`` once it exists, and the sweep writing it
    (in ``out``'s folder; its stderr piped)."""
    reader = subprocess.Popen([sys.executable, "-c", HOLD, str(out), str(seconds)],
                              stdout=subprocess.PIPE, text=True)
    sweep = subprocess.Popen([sys.executable, "-m", "rodjit", *ARGS, "-o", out.name],
                             cwd=out.parent, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, text=True)
    return reader, sweep


def _held(tmp_path, reference, seconds: float) -> None:
    out = tmp_path / "s.h5"
    reader, sweep = _start(out, seconds)
    try:
        assert reader.stdout.readline().strip() == "open"
        held = time.monotonic()
        assert sweep.poll() is None, "the sweep ended before the reader opened the file"
        _, err = sweep.communicate(timeout=seconds + 300)
        waited = time.monotonic() - held
        reader.wait(timeout=30)
    finally:
        sweep.kill()
        reader.kill()
    assert sweep.returncode == 0, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "is held open by another process" in lines[0], err
    assert lines[0].startswith("warning:"), err
    assert waited >= seconds - 0.5            # it waited for the reader, and wrote after
    table = rodjit.load_sweep(out)
    assert table.status == "completed" and table.counts["completed"] == len(reference)
    same_table(table, reference)


def test_a_reader_holding_the_file_costs_the_sweep_no_point(tmp_path, reference):
    _held(tmp_path, reference, 5.0)


@pytest.mark.slow
def test_a_reader_holding_the_file_for_a_minute_costs_the_sweep_no_point(tmp_path,
                                                                         reference):
    _held(tmp_path, reference, 60.0)


def test_a_signal_while_the_sweep_waits_for_a_reader_ends_the_wait(tmp_path, reference):
    """SIGINT while the sweep, its points done, waits for the reader: exit 130 and one more
    line naming the points not written and how to continue; ``--resume`` (the reader gone)
    then completes the table."""
    out = tmp_path / "s.h5"
    reader, sweep = _start(out, 600)
    try:
        assert reader.stdout.readline().strip() == "open"
        err = ""
        while "is held open by another process" not in err:   # the points done, waiting
            line = sweep.stderr.readline()
            assert line, "the sweep ended without waiting"
            err += line
        time.sleep(0.5)
        sweep.send_signal(signal.SIGINT)
        err += sweep.communicate(timeout=60)[1]
    finally:
        sweep.kill()
        reader.kill()
        reader.wait()
    assert sweep.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 2 and "Traceback" not in err, err
    assert "interrupted by SIGINT while waiting for another process to let go of" in lines[1]
    assert (f"finished points were not written; continue with: rodjit sweep --resume -o "
            f"{out.name}") in lines[1], err
    r = rodjit_cli("sweep", "--resume", "-o", out, "-q", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    same_table(rodjit.load_sweep(out), reference)
