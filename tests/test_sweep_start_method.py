"""How the pool's workers start (``sweeps.start_method``): forked from the fork server on
Linux, spawned elsewhere; the same table either way, one thread per worker even when the
server was started ahead of the pool, and nothing left running once the sweep's process
is gone."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import psutil
import pytest

import rodjit
from rodjit.presets import load_preset
from rodjit.sweeps import start_method
from conftest import same_table

LINUX = sys.platform.startswith("linux")


def test_linux_forks_from_the_server_and_other_systems_spawn(monkeypatch):
    if LINUX:
        ctx = start_method.context()
        assert ctx.get_start_method() == "forkserver" and start_method.forks()
    monkeypatch.setattr(start_method.sys, "platform", "darwin")
    assert not start_method.forks()
    assert start_method.context().get_start_method() == "spawn"


@pytest.mark.slow
def test_forked_and_spawned_workers_give_the_same_table(tmp_path, monkeypatch):
    base = load_preset("paper-mu100").override({"time.t_end": 1.0})
    grid = {"rod.mu": [0.0, 50.0, 100.0], "floor.beta": [0.03, 0.1]}
    forked = rodjit.sweep(base, grid, jobs=2, batch_size=2, output=tmp_path / "f.h5")
    monkeypatch.setattr(start_method, "forks", lambda: False)
    spawned = rodjit.sweep(base, grid, jobs=2, batch_size=2, output=tmp_path / "s.h5")
    same_table(forked, spawned)


@pytest.mark.skipif(not LINUX, reason="the fork server is Linux's")
def test_a_server_started_ahead_gives_one_thread_workers_and_leaves_the_env_alone():
    code = """
        import os
        from rodjit.sweeps.start_method import WORKER_ENV, start_server
        for k in WORKER_ENV:
            os.environ.pop(k, None)
        start_server()
        start_server()                       # once is enough; a second call keeps it
        assert not any(k in os.environ for k in WORKER_ENV)
        from rodjit.config import Config
        from rodjit.sweeps.point import PointTask
        from rodjit.sweeps.pool import ProcessPool
        base = Config().override({"time.t_end": 0.05})
        pool = ProcessPool(2, warm=base)
        tasks = [PointTask(i, base, None, ()) for i in range(2)]
        done = [r for r in pool.results(tasks) if r is not None]
        assert [r.status for r in done] == ["completed", "completed"]
        assert {r.worker["numba_threads"] for r in done} == {1}
        assert os.getpid() not in {r.worker["pid"] for r in done}
        print("ok")
        """
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr


@pytest.mark.skipif(not LINUX, reason="the fork server is Linux's")
def test_sigkill_of_the_sweep_ends_its_server_and_workers(tmp_path):
    """The sweep's process killed outright while its workers compute batches of several
    seconds: the workers end at once (not when their batch is done), and with them the
    fork server and the resource tracker; nothing keeps computing."""
    args = ["--grid", "floor.beta=linspace(0.01,0.05,16)", "--set", "time.t_end=6", "--set",
            "rod.N=200", "--set", "time.integrator=verlet", "--set", "time.control=cfl",
            "--jobs", "2", "--batch-size", "8", "-o", "s.h5", "-q"]   # ~0.4 s a point
    proc = subprocess.Popen([sys.executable, "-m", "rodjit", "sweep", *args], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        children: list = []
        while time.monotonic() < deadline and proc.poll() is None:
            children = psutil.Process(proc.pid).children(recursive=True)
            # the resource tracker, the server and two workers forked from it, both well
            # into their first batch (ready long before: a third of a second of stepping)
            workers = [c for c in children if c.ppid() != proc.pid]
            try:
                if len(workers) >= 2 and all(w.cpu_times().user > 0.3 for w in workers):
                    break
            except psutil.NoSuchProcess:
                pass
            time.sleep(0.05)
        assert proc.poll() is None, "the sweep ended before its workers were seen"
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)

        def running():
            return [c for c in children
                    if c.is_running() and c.status() != psutil.STATUS_ZOMBIE]

        deadline = time.monotonic() + 3      # a batch takes 3 s or more
        while running() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not running(), [c.cmdline()[:3] for c in running()]
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
