"""Dask's own log lines go through rodjit's reporting: each record one ``warning:`` line
naming its logger and level (no Dask timestamps, no traceback), nothing under ``-q``."""
from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("distributed")

from rodjit.sweeps import dask_logging  # noqa: E402

TESTS = Path(__file__).parent


@pytest.fixture
def routed(monkeypatch):
    """Distributed imported (its handlers installed), then routed; put back afterwards."""
    import distributed  # noqa: F401

    saved = {name: (logging.getLogger(name).handlers[:], logging.getLogger(name).propagate)
             for name in [*logging.root.manager.loggerDict, "distributed", "tornado"]}
    monkeypatch.delenv("DASK_DISTRIBUTED__ADMIN__LOG_FORMAT", raising=False)
    for name in ("distributed", "distributed.client", "tornado"):
        # the handlers distributed installs when imported (not under pytest, whose own
        # handlers on the root logger it leaves alone)
        lg = logging.getLogger(name)
        if not lg.handlers:
            lg.addHandler(logging.StreamHandler(sys.stderr))
            lg.propagate = False
    dask_logging.route_dask_logs()
    yield
    for name, (handlers, propagate) in saved.items():
        lg = logging.getLogger(name)
        lg.handlers[:] = handlers
        lg.propagate = propagate


def test_a_record_becomes_one_warning_line(routed, capfd):
    log = logging.getLogger("distributed.scheduler")
    old = log.level
    log.setLevel(logging.INFO)
    try:
        try:
            raise ValueError("a worker\nwent away")
        except ValueError:
            with pytest.warns(dask_logging.DaskLogWarning) as got:
                log.error("Task x marked as failed\n  because 1 workers died", exc_info=True)
                log.info("Receive client connection")         # below WARNING: dropped
    finally:
        log.setLevel(old)
    assert [str(w.message) for w in got] == [
        "distributed.scheduler (ERROR): Task x marked as failed because 1 workers died "
        "(ValueError: a worker went away)"]
    out, err = capfd.readouterr()
    assert out == err == ""          # distributed's own handler no longer writes
    assert not [h for name in ("distributed", "tornado", "bokeh")
                for h in logging.getLogger(name).handlers if type(h) is logging.StreamHandler]
    assert os.environ["DASK_DISTRIBUTED__ADMIN__LOG_FORMAT"] == dask_logging.WORKER_LOG_FORMAT


def test_routing_twice_adds_one_handler(routed):
    dask_logging.route_dask_logs()
    assert logging.getLogger("distributed").handlers.count(dask_logging._HANDLER) == 1


def test_a_local_clusters_silence_logs_still_sets_the_level(routed):
    from distributed.utils import silence_logging_cmgr

    with silence_logging_cmgr(logging.ERROR):
        assert dask_logging._HANDLER.level == logging.ERROR
    assert dask_logging._HANDLER.level == logging.WARNING


@pytest.mark.slow
@pytest.mark.parametrize("quiet", [False, True], ids=["verbose", "quiet"])
def test_a_dask_sweep_with_a_dead_worker_speaks_in_rodjit_lines(tmp_path, quiet):
    """A LocalCluster sweep whose point kills its worker: the scheduler's log records are
    ``warning:`` lines (none in Dask's own format), the failure one ``Error:`` line; under
    ``-q`` that line alone.  (The records themselves are checked in this process
    above: the scheduler logs them or not depending on when it notices the death.)"""
    code = ("import sys\nsys.path.insert(0, %r)\nimport killer_law\nsys.argv[0] = 'rodjit'\n"
            "from rodjit.entry import main\nmain()" % str(TESTS))
    args = ["sweep", "--grid", "rod.kappa=10,13", "--set", "rod.law=kill-test", "--set",
            "time.t_end=0.02", "--set", "rod.N=3", "--scheduler", "local", "-j", "2", "-o",
            "k.h5"] + (["-q"] if quiet else [])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(TESTS.parent), str(TESTS), os.environ.get("PYTHONPATH", "")]))
    r = subprocess.run([sys.executable, "-c", code, *args], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 1, r.stderr
    lines = r.stderr.strip().splitlines()
    assert "Traceback" not in r.stderr and " - ERROR - " not in r.stderr, r.stderr
    assert lines[-1].startswith("Error: 1 of 2 points failed"), r.stderr
    if quiet:
        assert len(lines) == 1, r.stderr
    else:
        # the scheduler's records of the death (whether it logs them depends on when it
        # notices), each one warning line
        assert all(line.startswith("warning: distributed.") for line in lines[:-1]), r.stderr
