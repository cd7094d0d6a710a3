"""What every executor's worker processes share: the heartbeat of the executors' result
iterators, the one-thread environment the workers start in (``start_method``: the workers
are the parallelism, so no worker oversubscribes the cores with threads of its own), and
what a worker does before its first task (``start_worker``)."""
from __future__ import annotations

from ..driver.run import Run
from ..records.sink import Sink
from .ensemble import load_batch_kernel
from .point import default_jobs, worker_info
from .start_method import WORKER_ENV, worker_environment

__all__ = ["HEARTBEAT", "WORKER_ENV", "default_jobs", "worker_environment", "start_worker"]

# seconds between the ``None`` heartbeats of an executor's results while tasks run
HEARTBEAT = 0.2


def start_worker(warm=None, batched: bool = False) -> dict:
    """A worker's start: load (or compile) the kernels the Config ``warm`` runs with, if
    given, so its first task does not pay for it (a configuration that cannot start is
    left to its point to report); then who the worker is (``worker_info``).  ``batched``:
    the sweep runs on the ensemble engine, whose batch kernel is the one to load (a
    ``Run``'s loop would be loaded for nothing)."""
    if warm is not None:
        try:
            if batched:
                load_batch_kernel(warm)
            else:
                Run(warm).start(Sink())
        except Exception:
            pass
    return worker_info()
