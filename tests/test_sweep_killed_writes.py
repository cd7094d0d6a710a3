"""``rodjit sweep`` SIGKILLed at moments drawn (seeded) among the writes of its sweep file:
while the file is created, while a batch of points is written, while it is closed with its
status.  Each time ``rodjit info`` reads the file (exit 0) and ``rodjit sweep --resume``
completes it to the table of the uninterrupted sweep, column by column (timings apart)
with the same bounce rows; a kill before the file was whole left no file, and the same
command then runs the sweep.

The moments: the k-th call rodjit makes into h5py to write (an attribute, rows of a
dataset, a new dataset, closing the file) inside a sweep file's ``create``,
``write_batch`` or ``finish``, killed from inside the process (SIGKILL to itself) so that
it lands there and nowhere else.  Every point is its own write (batches of one point, a
flush interval of 1 ms), so a small grid of quick points makes many writes.  The default
suite kills once in each of the three phases; ``-m slow`` at 20 moments, the phases in
turn.
"""
from __future__ import annotations

import os
import signal

import numpy as np
import pytest
from click.testing import CliRunner

import rodjit
from conftest import rodjit_cli, same_table
from rodjit import cli

SEED = int(os.environ.get("RODJIT_HOSTILE_SEED", "20261207"))
ARGS = ["sweep", "--grid", "floor.beta=linspace(0.01,0.05,6)", "--set", "time.t_end=0.8",
        "--set", "rod.N=40", "--set", "time.integrator=verlet", "--set",
        "time.control=cfl", "--scheduler", "inline", "--batch-size", "1", "-q", "-o", "s.h5"]

# run first in the command's interpreter: a write for every point, and the k-th write call
# into h5py made by a sweep file's create, write_batch or finish (KILL_AT, 0: none) SIGKILLs
# the process; KILL_LOG: where each such call was made, one line each
INJECT = """
import os, signal, sys
import h5py
import rodjit.sweeps.run_sweep as run_sweep
run_sweep.sweep.__kwdefaults__["flush_interval"] = 1e-3
_at, _log, _seen = int(os.environ["KILL_AT"]), os.environ.get("KILL_LOG"), [0]

def _phase():
    f = sys._getframe(2)
    while f is not None:
        if (f.f_code.co_filename.endswith("sweep_file.py")
                and f.f_code.co_name in ("create", "write_batch", "finish")):
            return f.f_code.co_name
        f = f.f_back

def _wrap(cls, name):
    method = getattr(cls, name)
    def wrapper(*args, **kwargs):
        phase = _phase()
        if phase is not None:
            _seen[0] += 1
            if _log:
                with open(_log, "a") as fh:
                    fh.write(phase + "\\n")
            if _seen[0] == _at:
                os.kill(os.getpid(), signal.SIGKILL)
        return method(*args, **kwargs)
    setattr(cls, name, wrapper)

for _cls, _name in ((h5py.AttributeManager, "__setitem__"), (h5py.Dataset, "__setitem__"),
                    (h5py.Group, "create_dataset"), (h5py.File, "close")):
    _wrap(_cls, _name)
"""


def invoke(*args):
    return CliRunner().invoke(cli.main, [str(a) for a in args])


def _sweep(cwd, kill_at: int, log=None):
    """``rodjit sweep ARGS`` in a fresh interpreter (``INJECT`` first) killed at its
    ``kill_at``-th write call (0: not killed)."""
    env = {"KILL_AT": str(kill_at), **({"KILL_LOG": str(log)} if log else {})}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        return rodjit_cli(*ARGS, cwd=cwd, code=INJECT)
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted sweep's table, and the phase of each of its write calls."""
    d = tmp_path_factory.mktemp("ref")
    r = _sweep(d, 0, d / "calls.txt")
    assert r.returncode == 0, r.stderr
    phases = (d / "calls.txt").read_text().split()
    assert {"create", "write_batch", "finish"} <= set(phases)
    assert phases.count("write_batch") >= 6 * 3       # every point its own write
    return rodjit.load_sweep(d / "s.h5"), phases




def _killed_then_resumed(tmp_path, reference, k: int) -> None:
    ref, phases = reference
    r = _sweep(tmp_path, k)
    assert r.returncode == -signal.SIGKILL and r.stderr == "", (k, phases[k - 1], r.stderr)
    out = tmp_path / "s.h5"
    if not out.exists():         # killed before the file was whole: nothing was written
        assert phases[k - 1] == "create", k
        again = _sweep(tmp_path, 0)
        assert again.returncode == 0, again.stderr
    else:
        shown = invoke("info", out)
        assert shown.exit_code == 0, (k, phases[k - 1], shown.output)
        for _ in range(2):
            if rodjit.load_sweep(out).status == "completed":
                break
            resumed = invoke("sweep", "--resume", "-o", out, "-q")
            assert resumed.exit_code == 0, (k, phases[k - 1], resumed.output)
    table = rodjit.load_sweep(out)
    assert table.status == "completed" and table.counts["completed"] == len(ref)
    same_table(table, ref)


PHASES = ("create", "write_batch", "finish")


def _draw(phases, n: int) -> list[int]:
    """``n`` distinct write calls to kill at (1-based), drawn from the phases in turn (a
    phase's calls may be few: ``finish`` makes three), skipping a phase drawn out."""
    rng = np.random.default_rng(SEED)
    calls = {p: rng.permutation([k + 1 for k, q in enumerate(phases) if q == p]).tolist()
             for p in PHASES}
    out: list[int] = []
    while len(out) < n:
        for p in PHASES:
            if calls[p] and len(out) < n:
                out.append(int(calls[p].pop(0)))
    return out


@pytest.mark.parametrize("phase", range(3), ids=PHASES)
def test_sigkill_in_each_phase_of_the_sweep_file(tmp_path, reference, phase):
    _killed_then_resumed(tmp_path, reference, _draw(reference[1], 3)[phase])


@pytest.mark.slow
@pytest.mark.parametrize("draw", range(20))
def test_sigkill_at_20_moments_of_the_sweep_file(tmp_path, reference, draw):
    _killed_then_resumed(tmp_path, reference, _draw(reference[1], 20)[draw])

def test_a_file_an_earlier_rodjit_left_open_is_named_so_and_overwritten(tmp_path):
    """What an earlier rodjit left when killed while it wrote a sweep file (HDF5's "open
    for writing" flag set, nothing to undo, its writer lock file naming it): ``info`` and
    ``--resume`` say so in one line (exit 2), ``--overwrite`` replaces it; the same file
    without a dead rodjit writer's lock file is not replaced."""
    import h5py
    from rodjit.output.lock import WriterLock

    out = tmp_path / "s.h5"
    with h5py.File(out, "w", libver=("v110", "v110")) as f:
        f.attrs["rodjit_kind"] = "sweep"
    pid = os.fork()
    if pid == 0:                   # the writer of before: its lock, the file open, killed
        try:
            WriterLock(out).acquire()
            f = h5py.File(out, "r+", libver=("v110", "v110"))
            f.attrs["status"] = "running"
            f.flush()
            os.kill(os.getpid(), signal.SIGKILL)
        finally:
            os._exit(3)
    assert os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]) == -signal.SIGKILL
    for args in (["info", out], ["sweep", "--resume", "-o", out]):
        r = invoke(*args)
        assert r.exit_code == 2, r.output
        assert "was left open for writing by a process that stopped" in r.output, r.output
        assert len(r.output.strip().splitlines()) == 1, r.output
    keep = out.read_bytes()
    lock = tmp_path / ".s.h5.lock"
    held = lock.read_bytes()
    lock.unlink()                  # no rodjit writer died on it: someone else's file
    r = invoke(*ARGS[:-2], "-o", out, "--overwrite")
    assert r.exit_code == 2 and "replaces only rodjit sweep files" in r.output, r.output
    assert out.read_bytes() == keep
    lock.write_bytes(held)
    r = invoke(*ARGS[:-2], "-o", out, "--overwrite")
    assert r.exit_code == 0, r.output
    assert rodjit.load_sweep(out).status == "completed"
