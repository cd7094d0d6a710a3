"""Observables of many configurations, run in parallel on the sweep engine's executors.

Where the caller needs only observables that a sweep point's summary row holds
(``SUMMARY_OF``: the first bounce's, the extremes), the configurations run on the batch
engine as sweep points do, and the rows are the answer.  Otherwise each configuration
becomes one sweep point that writes its full run file to a private temporary directory
(the executors move only summaries; the other observables need the diagnostics and
episodes); the parent reads each file back as it arrives, computes the observables, and
deletes it.  One configuration, or ``scheduler="inline"``, then runs in this process
without any file.
"""
from __future__ import annotations

import math
import os
import tempfile
import warnings
from typing import Any, Iterator, Sequence

__all__ = ["evaluate", "check_limits", "Extractor", "SUMMARY_OF"]

# an observable beside the built-in ones: name -> function(Result) -> float
Extractor = "Callable[[rodjit.Result], float]"

# the observables a sweep point's summary row holds, by their column there: the same
# numbers (``records.impact`` streams the one implementation of the first-impact ones;
# tests/test_analysis_evaluate.py compares them), so a study that needs only these runs
# its points on the batch engine, without a run file each
SUMMARY_OF = {"restitution_first": "restitution_first",
              "restitution_apex_first": "restitution_apex",
              "contact_time_first": "contact_time_first",
              "rebound_speed_first": "rebound_speed", "min_u0_first": "min_u0_impact",
              "min_u0": "min_u0", "max_floor_force": "max_floor_force"}


class _Configs:
    """Explicit configurations in a batch task's place of a grid: ``config(base, i)`` is
    configuration ``i`` (only the task's own travel with it)."""

    def __init__(self, configs: dict) -> None:
        self.configs = configs

    def config(self, base, index: int):
        return self.configs[index]


def _batched(configs, columns, jobs: int, scheduler) -> list[dict]:
    """``evaluate`` of observables that are summary columns (``SUMMARY_OF``): the points
    on the sweep's batch engine, a few tasks per worker."""
    import numpy as np

    from ..config import ModelWarning
    from ..sweeps.ensemble import BatchTask
    from ..sweeps.point import user_modules

    laws = tuple(dict.fromkeys(m for c in configs for m in user_modules(c)))
    n = len(configs)
    per = -(-n // (2 * jobs))                 # about two tasks per worker
    tasks = (BatchTask(np.arange(i, min(i + per, n), dtype=np.int64), None,
                       _Configs({j: configs[j] for j in range(i, min(i + per, n))}), laws)
             for i in range(0, n, per))
    out: list[dict | None] = [None] * n
    said: set = set()
    # the model's warnings of the configurations, said here once each (a worker that set
    # up an equal configuration before keeps its pieces and does not warn again)
    for text in dict.fromkeys(w for c in configs for w in c.warnings()):
        said.add(text)
        warnings.warn(text, ModelWarning, stacklevel=3)
    for res in _results(scheduler, min(jobs, -(-n // per)), configs[0] if not laws else None,
                        True, tasks, n, said):
        v = res.values
        for k, i in enumerate(res.index):
            failed = v["status"][k] == "failed"
            row: dict[str, Any] = {name: float(v[SUMMARY_OF[name]][k]) for name in columns}
            row.update(status="failed" if failed else str(v["impact_status"][k]),
                       reason=str(v["message"][k] if failed else v["impact_reason"][k]),
                       run_status=str(v["status"][k]), message=str(v["message"][k]),
                       steps=int(v["steps"][k]), rejected_steps=int(v["rejected_steps"][k]))
            out[int(i)] = row
    return [r if r is not None else _failed("no result") for r in out]


def _results(scheduler, jobs: int, warm, batched: bool, tasks, total: int,
             said: set) -> Iterator:
    """The results of ``tasks`` on an executor of ``jobs`` workers (``make_executor``),
    each with its warnings said once (``said``), the executor closed at the end."""
    from ..sweeps.executors import make_executor
    from ..sweeps.point import reissue_warnings

    executor = make_executor(scheduler, jobs, warm, batched=batched)
    try:
        for res in executor.results(tasks, total=total):
            if res is not None:
                reissue_warnings(res, said)
                yield res
    finally:
        executor.close(cancel=True)


def _values(result, extra, merge_time, histories=False) -> dict:
    from .observables import observables

    try:
        out = observables(result, merge_time)
    except ValueError as exc:         # too coarse diagnostics: say it per point
        out = _failed(str(exc))
        out.update(status="undefined", run_status=result.status)
    for name, fn in (extra or {}).items():
        out[name] = float(fn(result))
    out["run_status"] = result.status
    out["message"] = result.message
    out["steps"] = int(result.stats.get("steps", -1))
    out["rejected_steps"] = int(result.stats.get("rejected_steps", -1))
    if histories:                     # the heights at the snapshot times
        out["history"] = (result.t.copy(), result.u.copy())
    return out


def _failed(message: str, extra=None) -> dict:
    from .observables import OBSERVABLES

    out: dict[str, Any] = {name: math.nan for name in (*OBSERVABLES, *(extra or {}))}
    out.update(status="failed", reason=message, run_status="failed", message=message)
    return out


def check_limits(configs, *, max_output: float | None = None, max_steps: float | None = None,
                 max_points: float | None = None) -> None:
    """ValueError (one line) unless every configuration passes the limits a new run or
    sweep passes (``output.estimate.check_run``, the one estimate): at most
    ``max_points`` (default: a sweep's limit) of them, each finishing in at most
    ``max_steps`` fixed steps and
    holding at most ``max_output`` bytes of output (in memory, or in the temporary file
    a pool worker writes)."""
    from ..output.estimate import (ESTIMATE_KEYS, MAX_OUTPUT, MAX_STEPS, check_count_limit,
                                   check_run)
    from ..sweeps.grid import MAX_POINTS

    max_points = check_count_limit("max_points", MAX_POINTS if max_points is None
                                   else max_points)

    if len(configs) > max_points:
        raise ValueError(f"{len(configs):,} runs are more than the limit of "
                         f"{max_points:,.0f} points")
    seen = set()
    for i, cfg in enumerate(configs):
        key = tuple(cfg.get(k) for k in ESTIMATE_KEYS)
        if key in seen:
            continue
        seen.add(key)
        check_run(cfg, None, max_output=MAX_OUTPUT if max_output is None else max_output,
                  max_steps=MAX_STEPS if max_steps is None else max_steps,
                  what=f"the run at {_where(cfg, configs[0])}")


def _where(cfg, first) -> str:
    """The keys where ``cfg`` differs from the first configuration (for a message)."""
    a, b = cfg.flat(), first.flat()
    differ = [f"{k}={a[k]!r}" for k in a if a[k] != b.get(k)]
    return ", ".join(differ[:3]) if differ else "the base configuration"


def evaluate(configs, *, jobs: int | None = None, scheduler: str | None = None,
             merge_time: float | None = None, extra: dict | None = None,
             histories: bool = False, max_output: float | None = None,
             max_steps: float | None = None,
             columns: Sequence[str] | None = None) -> list[dict]:
    """The observables (``rodjit.analysis.observables``, and ``extra``: name ->
    function(Result) -> float) of every Config in ``configs``, in their order, with each
    run's accepted and rejected ``steps`` (and with ``histories``: ``history``, the
    snapshot times and heights ``(t, u)``).

    ``jobs``/``scheduler`` as for ``rodjit.sweep``; ``max_output``/``max_steps`` as for
    ``rodjit.run_to_file`` (``check_limits``, before any run).  A run that fails gives
    ``status = "failed"`` and its message as ``reason`` (observables missing).

    ``columns``: the observables the caller needs.  Where they are all summary columns of
    a sweep point (``SUMMARY_OF``) and neither ``extra``, ``histories`` nor another
    ``merge_time`` asks for a whole run, the points run on the sweep's batch engine and
    only those observables come back (with ``status``, ``reason``, ``steps``): 1.4 ms
    per run where a run file each took 31 ms (a table fit's 108 runs of paper-mu100 on
    2 workers, ``benchmarks/bench_fit.py --evaluate``)."""
    from ..driver.run import SimulationError
    from ..driver.simulate import simulate
    from ..sweeps.executors import check_scheduler, default_jobs
    from ..sweeps.point import PointTask, user_modules

    configs = list(configs)
    check_limits(configs, max_output=max_output, max_steps=max_steps)
    check_scheduler(scheduler)
    jobs = default_jobs() if jobs is None else jobs
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs = {jobs!r} is out of range (a whole number >= 1)")
    if not configs:
        return []
    if (columns is not None and set(columns) <= set(SUMMARY_OF) and not extra
            and not histories and merge_time is None):
        return _batched(configs, list(columns), jobs, scheduler)
    if scheduler == "inline" or len(configs) == 1 or jobs == 1 and scheduler is None:
        out = []
        for cfg in configs:
            try:
                out.append(_values(simulate(cfg), extra, merge_time, histories))
            except SimulationError as exc:
                out.append(_failed(str(exc), extra))
        return out

    from ..output.hdf5 import load_file

    results: list[dict | None] = [None] * len(configs)
    with tempfile.TemporaryDirectory(prefix="rodjit-evaluate-") as tmp:
        paths = [os.path.join(tmp, f"{i:06d}.h5") for i in range(len(configs))]
        tasks = (PointTask(i, cfg, paths[i], user_modules(cfg)) for i, cfg in enumerate(configs))
        warm = configs[0] if not user_modules(configs[0]) else None
        for res in _results(scheduler, min(jobs, len(configs)), warm, False, tasks,
                            len(configs), set()):
            i = res.index
            if os.path.exists(paths[i]):
                try:
                    results[i] = _values(load_file(paths[i]), extra, merge_time, histories)
                except Exception as exc:
                    results[i] = _failed(f"{type(exc).__name__}: {exc}", extra)
                os.remove(paths[i])
            else:
                results[i] = _failed(res.values.get("message") or "the point did not run",
                                     extra)
            if res.status == "failed":
                results[i].update(status="failed", run_status="failed",
                                  reason=res.values["message"], message=res.values["message"])
    return [r if r is not None else _failed("no result", extra) for r in results]

