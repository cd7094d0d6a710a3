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

import logging
import multiprocessing as mp
import os
import pickle
import signal
import time
import uuid
from collections import deque
from contextlib import contextmanager
from itertools import count, islice
from multiprocessing.connection import wait

from ..output.h5files import abandoned, quiet_disk_errors
from .dask_logging import route_dask_logs
from .ensemble import (BatchTask, lost_batch, run_task, run_tasks, timed, task_key as _key,
                       lost as _lost)
from .point import PointTask, died, start_worker

__all__ = ["Inline", "ProcessPool", "DaskCluster", "make_executor", "check_scheduler",
           "WORKER_ENV", "SCHEDULERS", "default_jobs"]

HEARTBEAT = 0.2
TASK_SECONDS = 0.5   # Dask tasks of about this much work (its advice: well over 100 ms)
MAX_BATCH = 64
CONNECT_TIMEOUT = 10.0     # seconds to reach an existing Dask scheduler
# one thread per worker: the workers are the parallelism (no oversubscribed cores)
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}
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
SCHEDULERS = ("processes", "local", "inline", "tcp://HOST:PORT")


def default_jobs() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:   # not Linux
        return os.cpu_count() or 1


@contextmanager
def _worker_environment():
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


def _death_message(pid: int, code: int | None) -> str:
    if code is not None and code < 0:
        try:
            how = f"killed by {signal.Signals(-code).name}"
        except ValueError:
            how = f"killed by signal {-code}"
    else:
        how = f"exited with code {code}"
    return f"the worker process (pid {pid}) died while running this point ({how})"


class Inline:
    """Points run one after another in this process (debugging, NUMBA_DISABLE_JIT)."""

    name = "inline"
    jobs = 1

    def results(self, tasks, total: int | None = None):
        for task in tasks:
            yield run_task(task)

    def close(self, cancel: bool = False) -> None:
        pass


def _die_with_parent() -> None:
    """Linux: the kernel kills this worker if the sweep's process dies (even by SIGKILL)."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)       # PR_SET_PDEATHSIG
        if os.getppid() == 1:                # the parent died before prctl took effect
            os._exit(1)
    except (OSError, AttributeError):
        pass


def _worker_main(conn, warm) -> None:
    """A pool worker: load the kernels of ``warm`` (a Config), then run the tasks the parent
    sends until it sends None or goes away."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)    # Ctrl-C is the parent's to handle
    # the parent ends a worker by SIGTERM when the sweep stops: it exits without a word
    # (the parent says what stopped the sweep, once)
    signal.signal(signal.SIGTERM, lambda signum, frame: os._exit(128 + signum))
    _die_with_parent()
    quiet_disk_errors()       # a run file the disk refuses: the parent reports it
    try:
        conn.send(("ready", start_worker(warm)))
        while True:
            try:
                task = conn.recv()
            except (EOFError, OSError):
                return
            if task is None:
                return
            try:
                conn.send(run_task(task))
            except (BrokenPipeError, OSError):
                return
    finally:
        if abandoned():   # a run file the disk refused: its handles must not be closed
            os._exit(0)


class _Worker:
    """One pool process and the points sent to it, in the order it runs them."""

    def __init__(self, ctx, warm):
        self.conn, child = ctx.Pipe()
        self.process = ctx.Process(target=_worker_main, args=(child, warm), daemon=True,
                                   name="rodjit-sweep-worker")
        with _worker_environment():
            self.process.start()
        child.close()
        self.tasks: deque[PointTask] = deque()     # the first is running, the rest wait
        self.ready = False

    def _send(self, msg) -> None:
        try:
            self.conn.send(msg)
        except (BrokenPipeError, OSError):
            pass       # it died; its sentinel reports it

    def assign(self, task: PointTask) -> None:
        self.tasks.append(task)
        self._send(task)

    def release(self) -> None:
        """Tell the worker to exit after its points (it is not waited for: see ``stop``)."""
        self._send(None)

    def stop(self, cancel: bool) -> None:
        """Wait for a released worker to exit, or end it now (``cancel``); kill it if it
        hangs."""
        if cancel:
            self.process.terminate()
        self.process.join(timeout=5)
        if self.process.is_alive():
            self.process.kill()
            self.process.join()
        self.conn.close()


class ProcessPool:
    """``jobs`` worker processes (spawned: no state inherited).

    Each worker holds ``DEPTH`` points, one running and the next already in its pipe, so
    it never waits for the parent (which may be writing the sweep file).  A worker that
    dies fails the point it was running; the points waiting behind it go to another
    worker.  Each worker imports rodjit once and loads the kernels of ``warm`` (a
    Config) from the disk cache before it reports ready.
    """

    name = "processes"
    DEPTH = 2

    def __init__(self, jobs: int, warm=None):
        self.jobs = jobs
        self.warm = warm
        self.ctx = mp.get_context("spawn")
        self.workers: list[_Worker] = []
        self.started = time.perf_counter()
        self.startup_time: float | None = None     # until every first worker was ready
        self.deaths = 0

    def _spawn(self) -> _Worker:
        w = _Worker(self.ctx, self.warm)
        self.workers.append(w)
        return w

    def _retire(self, w: _Worker, cancel: bool = False) -> None:
        if w in self.workers:
            self.workers.remove(w)
            w.stop(cancel)

    def results(self, tasks, total: int | None = None):
        tasks = iter(tasks)
        requeued: deque[PointTask] = deque()      # waiting behind a point that killed its worker

        def take():
            return requeued.popleft() if requeued else next(tasks, None)

        def fill(w: _Worker) -> None:
            while len(w.tasks) < self.DEPTH:
                task = take()
                if task is None:
                    break
                w.assign(task)

        busy = []
        for _ in range(self.jobs):
            task = take()
            if task is None:
                break
            w = self._spawn()
            w.assign(task)
            busy.append(w)
        for w in busy:          # a second point each only once every worker has a first
            fill(w)
        try:
            while busy:
                by_conn = {w.conn: w for w in busy}
                by_sentinel = {w.process.sentinel: w for w in busy}
                ready = wait(list(by_conn) + list(by_sentinel), timeout=HEARTBEAT)
                if not ready:
                    yield None
                    continue
                seen = set()
                for obj in ready:
                    w = by_conn.get(obj) or by_sentinel.get(obj)
                    if id(w) in seen:
                        continue
                    seen.add(id(w))
                    kind, result = self._receive(w)
                    if kind == "idle":
                        continue
                    if kind == "dead":
                        self.deaths += 1
                        lost = _lost(w.tasks.popleft(), _death_message(w.process.pid, result))
                        requeued.extendleft(reversed(w.tasks))
                        if isinstance(lost, list):   # a batch's first death: its points
                            requeued.extendleft(reversed(lost))   # again, each alone
                            lost = None
                        w.tasks.clear()
                        busy.remove(w)
                        self._retire(w, cancel=True)
                        task = take()
                        if task is not None:           # a fresh worker takes over
                            nw = self._spawn()
                            nw.assign(task)
                            fill(nw)
                            busy.append(nw)
                        if lost is not None:
                            yield lost
                        continue
                    w.tasks.popleft()
                    fill(w)                    # keep the worker busy first
                    if not w.tasks:            # let it go; joined at close, so that its
                        busy.remove(w)         # exit delays no other result
                        w.release()
                    yield result
        finally:
            self.close(cancel=True)

    def _receive(self, w: _Worker):
        """``("result", PointResult)``, ``("dead", exit code)`` or ``("idle", None)`` (a
        ready message, or nothing yet)."""
        try:
            if w.conn.poll():
                msg = w.conn.recv()
            elif w.process.is_alive():
                return "idle", None
            else:
                msg = None
        except (EOFError, OSError):
            msg = None
        if msg is None:
            w.process.join(timeout=5)
            return "dead", w.process.exitcode
        if isinstance(msg, tuple) and msg and msg[0] == "ready":
            w.ready = True
            if self.startup_time is None and all(x.ready for x in self.workers):
                self.startup_time = time.perf_counter() - self.started
            return "idle", None
        return "result", msg

    def close(self, cancel: bool = False) -> None:
        """Stop every worker: idle ones are released (all of them, then waited for), busy
        ones terminated if ``cancel``, else released after their points."""
        for w in list(self.workers):
            if not (cancel and w.tasks):
                w.release()
        for w in list(self.workers):
            self._retire(w, cancel=bool(w.tasks))


class DaskCluster:
    """Points as Dask tasks (short points several to a task): on a LocalCluster of ``jobs``
    single-threaded worker processes (``scheduler="local"``) or on an existing cluster
    (``tcp://HOST:PORT``)."""

    name = "dask"
    depth = 2            # tasks in flight per worker thread

    def __init__(self, scheduler: str, jobs: int, warm=None):
        try:
            import distributed
        except ImportError:
            raise ValueError(f"--scheduler {scheduler} needs Dask distributed; install it with: "
                             f"pip install 'rodjit[dask]'") from None
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
            self.client.run(start_worker, warm)
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

        def batch() -> tuple[PointTask, ...]:
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

        def submit(points: tuple[PointTask, ...]) -> None:
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


def check_scheduler(scheduler) -> None:
    """ValueError (one line) unless ``scheduler`` is one ``make_executor`` knows."""
    if scheduler is None or (isinstance(scheduler, str) and (
            scheduler in ("processes", "inline", "local") or "://" in scheduler)):
        return
    raise ValueError(f"scheduler = {scheduler!r} is not allowed (one of: processes "
                     f"(default), local (a Dask LocalCluster), inline (this process), "
                     f"tcp://HOST:PORT (an existing Dask scheduler))")


def make_executor(scheduler: str | None, jobs: int, warm=None):
    """The executor for ``--scheduler`` (see ``check_scheduler``): None/"processes" (the
    local pool), "inline", "local" (Dask LocalCluster) or "tcp://HOST:PORT" (an existing
    Dask cluster); workers load the kernels of the Config ``warm`` before their first
    point."""
    check_scheduler(scheduler)
    if scheduler in (None, "processes"):
        return ProcessPool(jobs, warm)
    if scheduler == "inline":
        return Inline()
    return DaskCluster(scheduler, jobs, warm)
