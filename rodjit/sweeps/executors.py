"""Where sweep points run: this process, a pool of local worker processes, or Dask.

Every executor turns an iterator of tasks (PointTasks, or the ensemble engine's
BatchTasks) into an iterator of their results (PointResults, BatchResults;
``ensemble.run_task``), in the order they finish, with ``None`` as a heartbeat (at least
every HEARTBEAT seconds) so the caller can check for signals and flush while points run
(``total``, when given, is how many tasks there are).  A worker process that dies yields a
failed result for the point it held; a batch it held runs again, each point alone
(``ensemble.lost``); the other tasks go on.
"""
from __future__ import annotations

from .dask_cluster import DaskCluster
from .ensemble import run_task
from .pool import ProcessPool
from .start_method import POOL_SCHEDULERS
from .workers import HEARTBEAT, WORKER_ENV, default_jobs

__all__ = ["InlineExecutor", "Inline", "ProcessPool", "DaskCluster", "make_executor",
           "check_scheduler", "WORKER_ENV", "SCHEDULERS", "default_jobs", "HEARTBEAT"]

SCHEDULERS = ("processes", "local", "inline", "tcp://HOST:PORT")


class InlineExecutor:
    """Points run one after another in this process (debugging, NUMBA_DISABLE_JIT)."""

    name = "inline"
    jobs = 1

    def results(self, tasks, total: int | None = None):
        for task in tasks:
            yield run_task(task)

    def close(self, cancel: bool = False) -> None:
        pass


Inline = InlineExecutor     # its former name, still importable


def check_scheduler(scheduler) -> None:
    """ValueError (one line) unless ``scheduler`` is one ``make_executor`` knows."""
    if scheduler is None or (isinstance(scheduler, str) and (
            scheduler in ("processes", "inline", "local") or "://" in scheduler)):
        return
    raise ValueError(f"scheduler = {scheduler!r} is not allowed (one of: processes "
                     f"(default), local (a Dask LocalCluster), inline (this process), "
                     f"tcp://HOST:PORT (an existing Dask scheduler))")


def make_executor(scheduler: str | None, jobs: int, warm=None, batched: bool = False):
    """The executor for ``--scheduler`` (see ``check_scheduler``): None/"processes" (the
    local pool), "inline", "local" (Dask LocalCluster) or "tcp://HOST:PORT" (an existing
    Dask cluster); workers load the kernels of the Config ``warm`` before their first
    point (``batched``: the ensemble engine's batch kernel, not a run's loop)."""
    check_scheduler(scheduler)
    if scheduler in POOL_SCHEDULERS:
        return ProcessPool(jobs, warm, batched)
    if scheduler == "inline":
        return InlineExecutor()
    return DaskCluster(scheduler, jobs, warm, batched)
