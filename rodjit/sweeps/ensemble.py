"""The ensemble engine's host side: a batch of sweep points in one compiled call
(``stepping.ensemble.run_batch``), returned as a ``BatchResult``.

What runs in Python per point, before the call, and why: the point's Config
(``Grid.config``: the base configuration with the swept keys replaced, the fast path of
``Config.override``), and its set-up (``driver.setup.start``: parameter tuples, initial
state checked admissible, clock row, flight time), the one a ``Run`` makes, so the compiled
loop starts from exactly the arrays ``rodjit run`` would give it, packed into a row of
doubles.  A ``Run`` object, its buffers and its compile lookup are not made.  After the
call, the points' results are read by ``sweeps.decode``, as the GPU engine's are.

Every bounce is kept: a call returns early at a point whose rows fill the batch's bounce
rows (``stepping.trajectory``), and the next call, after the rows are taken out, goes on
with that point from where it stopped (``run_group``).

Threads: one per worker process (no ``prange`` over points): the sweep's workers are the
parallelism, as for the per-point path.  Batches on threads of one process (the compiled
call releases the GIL) were measured to scale no better than the same batches in worker
processes (``benchmarks/bench_sweep.py --engine --threads``), and a process confines a
point that crashes it to its own batch.
"""
from __future__ import annotations

import functools
import importlib
import pickle
import time
import warnings
from typing import Any, NamedTuple

import numpy as np

from ..config import ModelWarning
from ..driver.run import NODE_STEPS_PER_CALL, capacities
from ..driver.setup import Start, start
from ..records.columns import BOUNCE_COLUMNS
from ..stepping import aot
from ..stepping import ensemble as E
from ..stepping import impact_stream as S
from ..stepping import layout as L
from ..stepping import trajectory as T
from ..stepping.arrays import allocate
from ..stepping.observers import state_size
from . import decode
from .batch import BatchResult
from .point import (SUMMARY_COLUMNS, died, empty_columns, pass_on, run_point,
                    summary_columns, worker_info)

__all__ = ["BatchTask", "run_batch", "run_task", "run_tasks", "lost", "lost_batch", "task_key",
           "timed", "batches", "check_batch_size", "split_bounces", "as_batch",
           "BATCH_SECONDS", "MAX_BATCH_SIZE", "load_batch_kernel", "run_starts",
           "run_group"]

# bounce rows a batch's call holds per point (on average) before it returns for them to be
# taken out: most points have fewer, so one call runs the batch
BOUNCE_ROWS = 64


BATCH_SECONDS = 0.3    # work per batch of the ensemble engine
# points of the batches sent before any has been timed: small, since each worker takes two
# at once (one running, one waiting), and a costly region at the grid's start dealt out
# in a few large batches would keep one worker busy while the others wait
FIRST_BATCH = 2
MAX_BATCH_SIZE = 100_000


def check_batch_size(batch_size) -> None:
    """ValueError (one line) unless ``batch_size`` is None or a whole number in range."""
    if batch_size is None:
        return
    if (isinstance(batch_size, bool) or not isinstance(batch_size, int)
            or not 1 <= batch_size <= MAX_BATCH_SIZE):
        raise ValueError(f"batch_size = {batch_size!r} is out of range (a whole number from "
                         f"1 to {MAX_BATCH_SIZE})")


def batches(todo, base, grid, laws, batch_size, timing, jobs):
    """BatchTasks over ``todo``: ``batch_size`` points each, or by default about
    BATCH_SECONDS of work at the cost per point measured so far (``timing``, updated as
    results arrive; FIRST_BATCH points before any), and at most the points left over two
    batches per worker, so the workers finish together."""
    todo = np.asarray(todo, dtype=np.int64)
    i = 0
    while i < todo.size:
        if batch_size is not None:
            k = batch_size
        else:
            k = (int(BATCH_SECONDS * timing["points"] / max(timing["wall"], 1e-9))
                 if timing["points"] else FIRST_BATCH)
            k = max(1, min(k, -(-(todo.size - i) // (2 * max(1, jobs)))))
        yield BatchTask(todo[i:i + k], base, grid, laws)
        i += k


class BatchTask(NamedTuple):
    """A batch of points for a worker: their indices in ``grid`` over ``base``."""

    index: Any                  # (n,) int64 grid indices
    base: Any                   # the sweep's base Config
    grid: Any                   # its Grid
    laws: tuple[str, ...]       # modules to import first (user_modules: laws, integrator,
                                # observer)
    retry: bool = False         # its worker died once: this is the second try


def run_task(task):
    """A PointTask's PointResult, or a BatchTask's BatchResult."""
    if isinstance(task, BatchTask):
        return run_batch(task)
    return run_point(task)


def lost(task, message: str):
    """What to do with a task whose worker died: a point fails (its result); a batch is
    tried once more, each of its points alone (the tasks to run, a list), so only a
    point that kills its worker fails, as a batch of one on its second death (its
    result)."""
    if isinstance(task, BatchTask):
        if task.retry:
            return lost_batch(task, message)
        return [task._replace(index=task.index[k:k + 1], retry=True)
                for k in range(len(task.index))]
    return died(task.index, message)


def task_key(task):
    """A task's identity for the executors' bookkeeping: a point's index, a batch's first."""
    return ("batch", int(task.index[0])) if isinstance(task, BatchTask) else task.index


def run_tasks(tasks) -> bytes:
    """Run several tasks in turn (one Dask task); their results pickled into one blob,
    which Dask moves as a single frame."""
    return pickle.dumps([run_task(t) for t in tasks], protocol=pickle.HIGHEST_PROTOCOL)


def timed(result) -> tuple[int, float]:
    """(points timed, their wall time) of a result: a point that died has no steps."""
    steps = np.atleast_1d(result.values["steps"])
    wall = np.atleast_1d(result.values["wall_time"])
    return int(np.count_nonzero(steps)), float(np.sum(wall[steps != 0]))


def lost_batch(task: BatchTask, message: str) -> BatchResult:
    """The result of a batch whose worker died twice: every point failed with ``message``."""
    idx = np.asarray(task.index, dtype=np.int64)
    values = empty_columns(idx.size, _columns(task))
    values["status"][:] = "failed"
    values["message"][:] = message
    return BatchResult(idx, values, _no_bounces(), np.zeros(idx.size, np.int64))


def _columns(task: BatchTask) -> dict:
    """The summary columns of ``task``'s points (their observer's: the points of a batch
    share it, ``summary_columns``)."""
    if len(task.index) == 0:
        return SUMMARY_COLUMNS
    return summary_columns(task.grid.config(task.base, int(task.index[0])))


def _no_bounces() -> dict:
    from ..records.bounces import empty_bounces

    return empty_bounces()


def run_batch(task: BatchTask) -> BatchResult:
    """Run the points of ``task`` (module docstring); a point that fails, also in its
    set-up, gets its row marked failed with its reason, the others go on."""
    t0 = time.perf_counter()
    idx = np.asarray(task.index, dtype=np.int64)
    n = idx.size
    rows_of: list[list] = [[] for _ in range(n)]
    caught: list = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ModelWarning)
        for mod in task.laws:
            importlib.import_module(mod)
        values = empty_columns(n, _columns(task))
        members = []
        for k, i in enumerate(idx):
            try:
                s = start(task.grid.config(task.base, int(i)))
            except Exception as exc:     # as run_point reports a point that cannot start
                values["status"][k] = "failed"
                values["message"][k] = f"{type(exc).__name__}: {exc}"
                continue
            members.append((k, s))
        compiled, loading = run_starts(members, values, rows_of)
    said = pass_on(caught)
    bounces, counts = decode.bounce_tables(values, rows_of)
    wall = time.perf_counter() - t0
    # a point's share of the batch's time, by its steps (its loop's work)
    work = (values["steps"] + values["rejected_steps"]).astype(float)
    share = np.where(work > 0, work, 1.0)
    share = share / share.sum() if share.sum() > 0 else share
    values["run_time"] = share * compiled
    values["wall_time"] = share * wall
    values["compile_time"] = share * loading
    return BatchResult(idx, values, bounces, counts, said, worker_info())


def run_starts(members, values: dict, rows_of: list) -> tuple[float, float]:
    """Run the points ``members`` (``(position, driver.setup.Start)`` pairs) in one
    compiled call per family (``run_group``): their summary columns into ``values``, their
    bounce rows into ``rows_of[position]``.  The seconds of the compiled calls and of
    loading their kernels."""
    groups: dict = {}
    for k, s in members:
        cfg = s.config
        key = (E.family(s.params()), cfg.rod.N, capacities(cfg, s.ctrl),
               cfg.output.diagnostics_interval, cfg.time.t_end, cfg.output.times)
        groups.setdefault(key, []).append((k, s))
    compiled = loading = 0.0
    for group in groups.values():
        c, ld = run_group(group, values, rows_of)
        compiled += c
        loading += ld
    return compiled, loading


_LOADED: set = set()      # the families whose batch kernel this process has loaded


def _scratch(n1, scheme, cap_s, cap_d, ev_cap, times=(), observed: int = 0) -> tuple:
    """One point's arrays of ``run_batch`` (reused by every point of the call): a Run's
    arrays and buffers (``stepping.arrays``; its listed snapshot ``times`` and the
    ``observed`` entries of its observer, the same for the call's points), and the
    first-impact state."""
    return (allocate(n1, scheme, cap_s, cap_d, ev_cap, times, observed), np.zeros(S.SIZE))


EV_CAP = 1024    # event rows of a point's scratch


def _batch_kernel(params: tuple):
    """The batch kernel for points of the family of ``params`` (a point's parameter
    tuples), as a function of its arguments after the parameter tuples: the one compiled
    ahead of time where it was built for these types (``stepping.aot``), else the JIT's."""
    ahead = aot.batch_for(params)
    if ahead is not None:
        return ahead
    return functools.partial(E.run_batch, *params)


def _load_kernel(s: Start) -> float:
    """Load (or compile) the batch kernel of the family of point ``s`` if this process has
    not: a call with no point, so that loading is timed apart, as a Run's compile_time.
    The seconds it took (0 when the kernel was loaded before)."""
    params = s.params()
    key = E.family(params)
    if key in _LOADED:
        return 0.0
    cfg = s.config
    n1 = cfg.rod.N + 1
    cap_s, cap_d = capacities(cfg, s.ctrl)
    t0 = time.perf_counter()
    _batch_kernel(params)(np.zeros((0, len(E.pack(params)))), np.zeros((0, 2, n1)),
                          np.zeros((0, L.CLOCK_SIZE)), np.zeros(0), 0,
                          *_scratch(n1, s.scheme, cap_s, cap_d, EV_CAP, (),
                                    state_size(s.obs)),
                          np.zeros((BOUNCE_ROWS, T.BOUT_SIZE)),
                          np.zeros((0, T.fout_width(s.obs))),
                          np.zeros((0, T.I_SIZE), dtype=np.int64), 1)
    _LOADED.add(key)
    return time.perf_counter() - t0


def load_batch_kernel(config) -> float:
    """Load the batch kernel a sweep's points of ``config``'s family run with (a worker's
    start, ``workers.start_worker``); the seconds it took."""
    return _load_kernel(start(config))


def run_group(members, values: dict, rows_of: list) -> tuple[float, float]:
    """Run points of one family (``(position, Start)`` pairs) in compiled calls: one, or
    more where the bounce rows filled (a call returns at the point that stopped; after its
    rows are taken out, the next goes on from it); their summary columns into ``values``
    (``decode.summarize``), their bounce rows into ``rows_of``.  The seconds of the
    compiled calls and of loading the kernel (0 after the first call of a family)."""
    _, s0 = members[0]
    cfg = s0.config
    n1 = cfg.rod.N + 1
    m = len(members)
    params = np.array([E.pack(s.params()) for _, s in members], dtype=np.float64)
    init = np.empty((m, 2, n1))
    clock0 = np.empty((m, L.CLOCK_SIZE))
    flight = np.empty(m)
    for j, (_, s) in enumerate(members):
        init[j] = s.state
        clock0[j] = s.clock
        flight[j] = s.tau
    cap_s, cap_d = capacities(cfg, s0.ctrl)
    scratch = _scratch(n1, s0.scheme, cap_s, cap_d, EV_CAP, cfg.output.times,
                       state_size(s0.obs))
    fout = np.zeros((m, T.fout_width(s0.obs)))
    iout = np.zeros((m, T.I_SIZE), dtype=np.int64)
    pos = np.array([k for k, _ in members], dtype=np.int64)
    max_steps = int(max(1, NODE_STEPS_PER_CALL // n1))
    loading = _load_kernel(s0)
    call = _batch_kernel(s0.params())
    elapsed = 0.0
    first = 0
    while first < m:
        bout = np.empty((max(1, BOUNCE_ROWS * (m - first)), T.BOUT_SIZE))
        t0 = time.perf_counter()
        stop = int(call(params, init, clock0, flight, first, *scratch, bout, fout, iout,
                        max_steps))
        elapsed += time.perf_counter() - t0
        last = min(stop + 1, m)
        decode.take_rows(rows_of, pos[first:last], bout, iout[first:last])
        first = stop
    decode.summarize(values, pos, [s for _, s in members], fout, iout)
    return elapsed, loading


def split_bounces(result: BatchResult) -> list[dict]:
    """Each point's bounce table from a BatchResult's columns (a sweep without a file
    keeps them per point)."""
    ends = np.cumsum(result.bounce_count)
    starts = ends - result.bounce_count
    return [{name: col[s:e].copy() for name, col in result.bounces.items()}
            for s, e in zip(starts, ends)]


def as_batch(results) -> BatchResult:
    """PointResults and BatchResults as one BatchResult, in increasing point order."""
    parts = [r if isinstance(r, BatchResult) else _from_point(r) for r in results]
    idx = np.concatenate([p.index for p in parts])
    counts = np.concatenate([p.bounce_count for p in parts])
    values = {name: np.concatenate([np.asarray(p.values[name]) for p in parts])
              for name in parts[0].values}
    starts = np.cumsum(counts) - counts
    order = np.argsort(idx, kind="stable")
    rows = (np.concatenate([np.arange(starts[k], starts[k] + counts[k]) for k in order])
            if counts.sum() else np.zeros(0, np.int64))
    bounces = {name: np.concatenate([np.asarray(p.bounces[name]) for p in parts])[rows]
               for name in BOUNCE_COLUMNS}
    return BatchResult(idx[order], {k: v[order] for k, v in values.items()}, bounces,
                       counts[order])


def _from_point(r) -> BatchResult:
    values = empty_columns(1, {name: SUMMARY_COLUMNS.get(name, ("float", ""))
                               for name in r.values})
    for name in values:
        values[name][0] = r.values[name]
    return BatchResult(np.array([r.index], np.int64), values,
                       {name: np.asarray(r.bounces[name]) for name in BOUNCE_COLUMNS},
                       np.array([len(r.bounces["t_impact"])], np.int64))
