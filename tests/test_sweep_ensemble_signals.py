"""A sweep run by the ensemble engine (batches of points), killed by SIGKILL in the middle:
the file keeps every batch written, and ``--resume`` finishes it with the same table as a
sweep run in one go."""
import signal
import subprocess
import sys

import numpy as np
import pytest

import rodjit

from test_cli_sweep import _completed, _wait_for
from test_sweep_driver import same_values

ARGS = ["--grid", "floor.beta=linspace(0.01,0.05,16)", "--set", "time.t_end=6", "--set",
        "rod.N=200", "--set", "time.integrator=verlet", "--set", "time.control=cfl",
        "--jobs", "2", "--batch-size", "2", "-o", "s.h5"]       # ~0.4 s a point


@pytest.mark.slow
def test_sigkill_of_a_batched_sweep_then_resume_gives_the_uninterrupted_table(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "rodjit", "sweep", *ARGS], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        assert _wait_for(lambda: _completed(tmp_path / "s.h5") >= 2 or proc.poll() is not None)
        proc.send_signal(signal.SIGKILL)
        proc.communicate(timeout=60)
    finally:
        proc.kill()
    cut = rodjit.load_sweep(tmp_path / "s.h5")
    done = cut["status"] == "completed"
    assert cut.counts["failed"] == 0 and done.sum() >= 2
    assert np.all(cut["status"][~done] == "pending")
    r = subprocess.run([sys.executable, "-m", "rodjit", "sweep", "--resume", "-o", "s.h5", "-q"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=300)
    if cut.status == "completed":     # a loaded machine: the kill came after the end
        assert r.returncode == 2 and "nothing to resume" in r.stderr
    else:
        assert r.returncode == 0, r.stderr
        assert rodjit.load_sweep(tmp_path / "s.h5").status == "completed"
    final = rodjit.load_sweep(tmp_path / "s.h5")
    assert final.counts["completed"] == 16
    ref = rodjit.sweep(rodjit.Config().override({"time.t_end": 6.0, "rod.N": 200,
                                                 "time.integrator": "verlet",
                                                 "time.control": "cfl"}),
                       {"floor.beta": "linspace(0.01,0.05,16)"}, scheduler="inline")
    same_values(final, ref)
    for i in range(16):
        a, b = final.bounces(i), ref.bounces(i)
        for name in a:
            assert np.array_equal(np.asarray(a[name]), np.asarray(b[name]),
                                  equal_nan=np.asarray(a[name]).dtype.kind == "f"), name
