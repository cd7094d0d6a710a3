"""Sweep tasks on Dask: a LocalCluster of single-threaded worker processes, or an existing
cluster (``executors`` describes what every executor does)."""
from __future__ import annotations

import logging
import pickle
import time
import uuid
from collections import deque
from itertools import count, islice

from .dask_logging import route_dask_logs
from .errors import DaskMissing
from .ensemble import (BatchTask, lost_batch, run_tasks, timed, task_key as _key,
                       lost as _lost)
from .point import PointTask, died
from .workers import HEARTBEAT, WORKER_ENV, start_worker

__all__ = ["DaskCluster", "TASK_SECONDS", "MAX_BATCH", "CONNECT_TIMEOUT", "DASK_WORKER_CONFIG"]

TASK_SECONDS = 0.5   # Dask tasks of about this much work (its advice: well over 100 ms)
MAX_BATCH = 64
CONNECT_TIMEOUT = 10.0     # seconds to reach an existing Dask scheduler
# The LocalCluster rodjit starts shares the cores with its workers, so its housekeeping is
# cut: no statistical profiler sampling every worker thread every 10 ms (the tasks are
# compiled code: the samples would say nothing), no work stealing (rodjit keeps at most two
# tasks per worker, nothing to steal), event-loop, system and memory monitors polled every
# second or so instead of Dask's 20-500 ms (an idle cluster otherwise keeps a good part of a
# core busy; benchmarks/bench_sweep.py measures it), no active memory manager (results
# leave the workers at once), and no retries of a point whose worker died (rodjit re-runs
# it alone: DaskCluster.results)
DASK_WORKER_CONFIG = {"distributed.worker.profile.enabled": False,
                      "distributed.scheduler.work-stealing": False,
                      "distributed.admin.tick.interval": "500ms",
                      "distributed.admin.tick.cycle": "5s",
                      "distributed.admin.system-monitor.interval": "2s",
                      "distributed.admin.system-monitor.disk": False,
                      "distributed.admin.system-monitor.gil.enabled": False,
                      "distributed.worker.memory.monitor-interval": "1s",
                      "distributed.scheduler.active-memory-manager.start": False,
                      "distributed.scheduler.allowed-failures": 0}


class DaskCluster:
    """Points as Dask tasks (short points several to a task): on a LocalCluster of ``jobs``
    single-threaded worker processes (``scheduler="local"``) or on an existing cluster
    (``tcp://HOST:PORT``)."""

    name = "dask"
    depth = 2            # tasks in flight per worker thread

    def __init__(self, scheduler: str, jobs: int, warm=None, batched: bool = False):
        try:
            import distributed
        except ImportError:
            raise DaskMissing(scheduler) from None
        self.distributed = distributed
        route_dask_logs()        # its log lines as rodjit's warnings (sweeps/dask_logging.py)
        self.cluster = None
        self.started = time.perf_counter()
        if scheduler == "local":
            import dask

            with dask.config.set(DASK_WORKER_CONFIG):     # nannies pass it to the workers
                self.cluster = distributed.LocalCluster(
                    n_workers=jobs, threads_per_worker=1, processes=True,
                    dashboard_address=None, env=dict(WORKER_ENV), silence_logs=logging.ERROR,
                    # no dashboard; the scheduler's health endpoint on any free port, not
                    # on 8787 (which another cluster may hold: Dask then warns)
                    scheduler_kwargs={"dashboard_address": ":0"})
            self.client = distributed.Client(self.cluster, direct_to_workers=True)
            self.name = f"dask LocalCluster ({jobs} workers)"
        else:
            try:
                self.client = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT)
            except (OSError, TimeoutError) as exc:
                raise ValueError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
            self.name = f"dask {scheduler}"
        self.jobs = max(1, sum(self.client.nthreads().values()))
        try:     # every worker imports rodjit now (and says so if it cannot)
            self.client.run(start_worker, warm, batched)
        except ImportError as exc:
            self.close()
            raise ValueError(f"the Dask workers cannot import rodjit ({exc}); install rodjit "
                             f"where they run") from None
        self.startup_time = time.perf_counter() - self.started
        self._futures: dict = {}
        self.tasks = 0             # Dask tasks submitted (a task runs one point or several)
        self.deaths = 0            # worker processes that died running points

    def results(self, tasks, total: int | None = None):
        d = self.distributed
        tasks = iter(tasks)
        token = uuid.uuid4().hex[:8]
        suspects: deque[PointTask] = deque()   # their worker died: each is re-run alone
        retried: set[int] = set()
        lost: set[str] = set()                 # addresses of the workers that died
        seq = count()
        timing = {"sent": 0, "done": 0, "wall": 0.0}

        def batch() -> tuple[PointTask | BatchTask, ...]:
            # a task costs Dask milliseconds of CPU (scheduler, client, worker): short points
            # go several to a task, of about TASK_SECONDS; none before a point has been
            # timed, and (guided scheduling) at most the remaining points over the tasks in
            # flight, so the tasks shrink toward the end and the workers finish together
            k = 1
            first = next(tasks, None)
            if first is None:
                return ()
            if isinstance(first, BatchTask):     # already sized: one Dask task
                return (first,)
            if timing["done"]:
                k = int(TASK_SECONDS * timing["done"] / max(timing["wall"], 1e-9))
                if total is not None:
                    k = min(k, -(-(total - timing["sent"]) // (self.depth * self.jobs)))
                k = max(1, min(k, MAX_BATCH))
            return (first,) + tuple(islice(tasks, k - 1))

        def submit(points: tuple[PointTask | BatchTask, ...]) -> None:
            fut = self.client.submit(run_tasks, points, pure=False,
                                     key=f"rodjit-points-{next(seq)}-{token}")
            self._futures[fut] = points
            timing["sent"] += len(points)
            self.tasks += 1

        def fill() -> None:
            # Two tasks per worker thread: the next one waits on the worker while one runs,
            # so no scheduler round trip stands between them.  While a point
            # whose worker died is pending or re-running, at most one task per live worker
            # process: then that point has a process to itself, and if it dies again it was
            # the one that killed it.
            while True:
                # (a re-run point is always alone in its task)
                isolating = bool(suspects) or any(_key(p[0]) in retried
                                                  for p in self._futures.values())
                limit = self._live_workers() if isolating else self.depth * self.jobs
                if len(self._futures) >= limit:
                    return
                points = (suspects.popleft(),) if suspects else batch()
                if not points:
                    return
                submit(points)

        fill()
        timeouts = (TimeoutError, getattr(d, "TimeoutError", TimeoutError))
        try:
            while self._futures or suspects:
                if not self._futures:          # every worker is restarting
                    time.sleep(HEARTBEAT)
                    fill()
                    yield None
                    continue
                try:       # blocks until a task finishes (no polling), or the heartbeat
                    done = d.wait(list(self._futures), timeout=HEARTBEAT,
                                  return_when="FIRST_COMPLETED").done
                except timeouts:
                    fill()
                    yield None
                    continue
                for fut in done:
                    points = self._futures.pop(fut)
                    try:
                        results = pickle.loads(fut.result())
                    except d.KilledWorker as exc:
                        # the tasks a worker held all fail: count the worker once (a
                        # restarted worker has a new address)
                        lost.add(getattr(getattr(exc, "last_worker", None), "address", fut.key))
                        self.deaths = len(lost)
                        again = [p for p in points if _key(p) in retried]
                        # it, or a point beside it, killed the worker: each point again,
                        # alone (a batch as batches of one)
                        fresh = [q for p in points if _key(p) not in retried for q in (
                            _lost(p, "") if isinstance(p, BatchTask) else [p])]
                        retried.update(_key(p) for p in fresh)
                        suspects.extend(fresh)
                        why = ("the Dask worker process running this point died, also when "
                               "it ran alone (KilledWorker)")
                        results = [lost_batch(p, why) if isinstance(p, BatchTask)
                                   else died(p.index, why)
                                   for p in again]
                    except Exception as exc:   # cancelled, lost, or an error outside run_point
                        why = f"the Dask task failed: {type(exc).__name__}: {exc}"
                        results = [lost_batch(p, why) if isinstance(p, BatchTask)
                                   else died(p.index, why) for p in points]
                    fut.release()
                    for r in results:
                        done, wall = timed(r)
                        timing["done"] += done
                        timing["wall"] += wall
                    fill()                     # before the parent writes the results
                    yield from results
        finally:
            self.close(cancel=True)

    def _live_workers(self) -> int:
        """Worker processes the scheduler knows now (fewer while a dead one restarts)."""
        try:
            return len(self.client.nthreads())
        except Exception:
            return 1

    def close(self, cancel: bool = False) -> None:
        if self._futures and cancel:
            try:
                self.client.cancel(list(self._futures))
            except Exception:
                pass
        self._futures = {}
        try:
            self.client.close()
        finally:
            if self.cluster is not None:
                self.cluster.close()
