"""What every executor's worker processes share: the heartbeat of the executors' result
iterators, the one-thread environment the workers start in (the workers are the
parallelism, so no worker oversubscribes the cores with threads of its own), and what a
worker does before its first task (``start_worker``)."""
from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

from ..driver.run import Run
from ..records.sink import Sink
from .ensemble import load_batch_kernel
from .point import default_jobs, worker_info

__all__ = ["HEARTBEAT", "WORKER_ENV", "default_jobs", "worker_environment", "start_worker"]

# seconds between the ``None`` heartbeats of an executor's results while tasks run
HEARTBEAT = 0.2
# one thread per worker: the workers are the parallelism (no oversubscribed cores)
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}


@contextmanager
def worker_environment() -> Iterator[None]:
    """WORKER_ENV set while worker processes start (they inherit it before Numba is
    imported); the caller's environment is restored afterwards."""
    old = {k: os.environ.get(k) for k in WORKER_ENV}
    os.environ.update(WORKER_ENV)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


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
