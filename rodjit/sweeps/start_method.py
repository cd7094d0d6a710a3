"""How the local pool makes its worker processes: on Linux, forked from multiprocessing's
fork server, which has imported the workers' module once; elsewhere, spawned.

A spawned worker is a fresh interpreter that imports rodjit before its first point (about
0.2 s here, once per worker and again for each worker that replaces a dead one): the
largest part of a short sweep's fixed cost.  The fork server is a fresh interpreter too,
started the same way (it inherits nothing of the sweep's process: no open HDF5 file, no
thread, no lock), which imports the workers' module (``PRELOAD``) once and then forks a
worker whenever the pool asks, each with that import already done.  ``start_server``
starts it ahead of the pool: ``rodjit sweep`` does so first thing, so that the server's
import runs on another core while the command's own process imports what it needs.

A forked worker prepares itself as a spawned one does (the caller's ``sys.path`` and
working directory; a main script imported again under ``__mp_main__``, so the
``if __name__ == "__main__":`` guard is still needed: ``main_guard``).  The workers' environment is the
server's, fixed when it starts, always inside ``worker_environment`` (one thread each).  A
worker ends the moment the sweep's process dies (``pool._die_with_parent``); the server
lives while the process that started it or any of its workers does.  macOS spawns (a fork of a process that loaded the system's
frameworks is unsafe there), Windows has no fork.
"""
from __future__ import annotations

import multiprocessing as mp
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["POOL_SCHEDULERS", "PRELOAD", "WORKER_ENV", "worker_environment", "forks",
           "context", "start_server"]

# the ``--scheduler`` values that run the sweep on the local pool (``executors``)
POOL_SCHEDULERS = (None, "processes")
# the module a worker runs (``pool._worker_main``), imported by the fork server
PRELOAD = ["rodjit.sweeps.pool"]
# one thread per worker: the workers are the parallelism (no oversubscribed cores)
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}


@contextmanager
def worker_environment() -> Iterator[None]:
    """WORKER_ENV set while worker processes (or the fork server) start: they inherit it
    before Numba is imported; the caller's environment is restored afterwards."""
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


def forks() -> bool:
    """Whether the pool's workers are forked from the fork server (Linux) or spawned."""
    return sys.platform.startswith("linux") and "forkserver" in mp.get_all_start_methods()


def context():
    """The multiprocessing context the pool starts its workers with."""
    if not forks():
        return mp.get_context("spawn")
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(PRELOAD)
    return ctx


def start_server() -> None:
    """Start the fork server now, where the workers are forked (else nothing), so that its
    import of ``PRELOAD`` is done, or under way, when the pool forks its first worker.  A
    server already running (this process started one before) is kept."""
    if not forks():
        return
    from multiprocessing import forkserver

    context()          # (sets the preload the server imports)
    with worker_environment():
        forkserver.ensure_running()
