"""The local process pool: ``jobs`` worker processes (forked from the fork server on Linux,
else spawned: ``start_method``), each fed through a pipe (``executors`` describes what
every executor does)."""
from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
import time
from collections import deque
from multiprocessing.connection import wait

from ..output.abandoned import abandoned, quiet_disk_errors
from .ensemble import lost as _lost
from .ensemble import run_task
from .point import PointTask
from .start_method import context
from .workers import HEARTBEAT, start_worker, worker_environment

__all__ = ["ProcessPool"]


def _death_message(pid: int, code: int | None) -> str:
    if code is not None and code < 0:
        try:
            how = f"killed by {signal.Signals(-code).name}"
        except ValueError:
            how = f"killed by signal {-code}"
    else:
        how = f"exited with code {code}"
    return f"the worker process (pid {pid}) died while running this point ({how})"


def _die_with_parent() -> None:
    """End this worker the moment the sweep's process dies, even by SIGKILL, whatever the
    worker is doing: a thread waits on the parent's sentinel (closed by its death) and
    exits the process then.  It ends a worker forked from the fork server, whose parent
    is the sweep's process for ``multiprocessing`` (the sentinel) though the server is
    its parent for the kernel, and a spawned one alike; the batch kernel releases the GIL,
    so the thread runs while the worker computes.  The kernel's parent-death signal
    (``PR_SET_PDEATHSIG``) is not used: for a forked worker it fires at the server's
    death, not the sweep's, and the thread serves both kinds of worker
    (tests/test_sweep_start_method.py kills a sweep outright)."""
    parent = mp.parent_process()
    if parent is None:
        return

    def watch() -> None:
        wait([parent.sentinel])
        os._exit(1)

    threading.Thread(target=watch, name="rodjit-parent-watch", daemon=True).start()


def _worker_main(conn, warm, batched: bool = False) -> None:
    """A pool worker: load the kernels of ``warm`` (a Config; ``batched``: the ensemble
    engine's, ``workers.start_worker``), then run the tasks the parent
    sends until it sends None or goes away."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)    # Ctrl-C is the parent's to handle
    # the parent ends a worker by SIGTERM when the sweep stops: it exits without a word
    # (the parent says what stopped the sweep, once)
    signal.signal(signal.SIGTERM, lambda signum, frame: os._exit(128 + signum))
    _die_with_parent()
    quiet_disk_errors()       # a run file the disk refuses: the parent reports it
    try:
        try:
            conn.send(("ready", start_worker(warm, batched)))
        except (BrokenPipeError, OSError):
            return       # the sweep's process is gone (killed): nothing to say to anyone
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

    def __init__(self, ctx, warm, batched: bool = False):
        self.conn, child = ctx.Pipe()
        self.process = ctx.Process(target=_worker_main, args=(child, warm, batched),
                                   daemon=True, name="rodjit-sweep-worker")
        with worker_environment():
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
    """``jobs`` worker processes (forked from the fork server or spawned, ``start_method``:
    no state of this process inherited).

    Each worker holds ``DEPTH`` points, one running and the next already in its pipe, so
    it never waits for the parent (which may be writing the sweep file).  A worker that
    dies fails the point it was running; the points waiting behind it go to another
    worker.  Each worker imports rodjit once and loads the kernels of ``warm`` (a
    Config) from the disk cache before it reports ready.
    """

    name = "processes"
    DEPTH = 2

    def __init__(self, jobs: int, warm=None, batched: bool = False):
        self.jobs = jobs
        self.warm = warm
        self.batched = batched
        self.ctx = context()
        self.workers: list[_Worker] = []
        self.started = time.perf_counter()
        self.startup_time: float | None = None     # until every first worker was ready
        self.deaths = 0

    def _spawn(self) -> _Worker:
        w = _Worker(self.ctx, self.warm, self.batched)
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
                    w = by_conn.get(obj) or by_sentinel[obj]    # one of the two
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
