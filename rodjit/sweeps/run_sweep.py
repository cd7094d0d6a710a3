"""``rodjit.sweep``: run every point of a grid, write each result as it arrives.

Everything is validated before anything is written or started.  Results stream back from
the executor in the order points finish; the parent is the only writer of the sweep file,
which it updates in batches (at least every ``flush_interval`` seconds, and every
BATCH_ROWS results).  SIGINT/SIGTERM stop the workers, and the file keeps every finished
point; ``resume=True`` runs only the points that are still pending or failed.  Another
process holding the file open (a reader) delays the writes, never the points: they are
held until the file is let go, and the sweep waits for that at its end (``_when_free``).
"""
from __future__ import annotations

import os
import signal
import time
import warnings
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from ..config import Config
from ..driver.progress import close as close_progress
from ..driver.progress import sweep_progress
from ..driver.signals import StopFlag, deferred_signals
from ..output.estimate import MAX_OUTPUT, MAX_STEPS
from ..output.h5files import (FileBusy, WriteFailed, check_output, open_file, writer_alive,
                              writer_pid)
from ..output.lock import WriterLock, lock_path, note_failure
from . import sweep_file
from .executors import check_scheduler, default_jobs, make_executor
from .grid import MAX_POINTS, Grid
from .main_guard import check_main
from .plan import check_memory, check_runs_dir, plan_sweep
from .sweep_check import read_sweep
from .batch import BatchResult
from .ensemble import batches, check_batch_size, split_bounces, timed
from .point import PointTask, empty_columns, reissue_warnings, summary_columns, user_modules
from .errors import FileHeldOpen, ResumeMismatch, SweepWriteFailed, resume_note
from .outcome import SweepFailed, SweepInterrupted, SweepProgress, sweep_stats
from .sweep_table import SweepTable

__all__ = ["sweep", "SweepInterrupted", "SweepFailed", "SweepProgress"]

SWEEP_FLUSH_INTERVAL = 1.0   # seconds of wall time between writes of finished points
BUSY_WAIT = 1.0        # a write waits this long for a reader to let go, then tries again later
BATCH_ROWS = 256       # results held before a write at most (unless a reader holds the file)
ENGINE = True          # False: every point alone through ``point.run_point`` (benchmarks)


def check_jobs(jobs) -> int:
    if jobs is None:
        return default_jobs()
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs = {jobs!r} is out of range (a whole number >= 1)")
    return jobs


def _new_columns(grid: Grid, base) -> dict[str, np.ndarray]:
    return {**sweep_file.key_columns(grid),
            **empty_columns(len(grid), summary_columns(base))}


def _open_resume(output, config, grid, max_points):
    """Base config, grid, columns and attributes of the sweep file to continue."""
    with sweep_file.open_sweep(output) as f:
        sweep_file.check_continuable(f, output)
        header, columns = read_sweep(f)
        alive = (writer_alive(f, lock=False) if header["attrs"].get("status") == "running"
                 else False)
        pid = writer_pid(f) if alive else None
    if alive:
        raise FileBusy(f"{str(output)!r} is being written by a running sweep on this machine "
                       f"(process {pid}); stop it before resuming")
    base, file_grid = header["base"], header["grid"]
    # the configurations as they run ("auto" resolved): the file's base is resolved already
    # unless an older version or a caller of sweep_file.create wrote it unresolved
    if config is not None and (want := config.resolve()) != (have := base.resolve()):
        was = have.flat()
        differ = sorted(k for k, v in want.flat().items() if was[k] != v)
        raise ResumeMismatch(output, "configuration", ", ".join(differ))
    if grid is not None and Grid.from_spec(grid, max_points=max_points) != file_grid:
        raise ResumeMismatch(output, "grid", file_grid.to_json())
    return base, file_grid, columns, header["attrs"]


def sweep(config: Config | None = None, grid: Mapping[str, Any] | Grid | None = None, *,
          output: str | os.PathLike[str] | None = None, jobs: int | None = None,
          scheduler: str | None = None, save_runs: str | os.PathLike[str] | None = None,
          resume: bool = False, overwrite: bool = False,
          progress: bool | Callable[[SweepProgress], object] | None = None,
          command: str | None = None, handle_signals: bool = True,
          flush_interval: float = SWEEP_FLUSH_INTERVAL,
          max_output: float = MAX_OUTPUT, max_steps: float = MAX_STEPS,
          max_points: float = MAX_POINTS, device: str | None = None,
          batch_size: int | None = None) -> SweepTable:
    """Run ``config`` (None: the built-in run) at every point of ``grid`` and return the
    summary table; with ``output``, stream it to that sweep file as points finish.

    Parameters
    ----------
    config : Config or None
        The base configuration every point starts from; ``None`` is ``Config()``.
    grid : mapping
        Configuration key -> values: a list, or ``"linspace(a, b, n)"`` /
        ``"logspace(a, b, n)"``, e.g. ``{"rod.mu": [0, 1, 10], "floor.kappa_b":
        "logspace(3, 5, 3)"}``; the points are the Cartesian product, the last key varying
        fastest.
    output : str or os.PathLike, optional
        The sweep file to write.
    jobs : int, optional
        Worker processes (default: every core).
    scheduler : str, optional
        None or ``"processes"`` (a local pool), ``"local"`` (a Dask LocalCluster of
        ``jobs`` workers), ``"tcp://HOST:PORT"`` (an existing Dask cluster) or
        ``"inline"`` (this process).
    save_runs : str or os.PathLike, optional
        A directory for one full run file per point.
    resume : bool
        Continue ``output``, running only its pending and failed points.
    overwrite : bool
        Replace an existing ``output``.
    progress : bool or callable, optional
        True for a progress bar (tqdm), or a callable: ``progress(p)`` gets a SweepProgress
        as points finish.
    command : str, optional
        The command line recorded in the file.
    handle_signals : bool
        Catch SIGINT/SIGTERM and close the file with every finished point.
    flush_interval : float
        Wall-clock seconds between writes of finished points.
    max_output : float, optional
        Refuse (ValueError) a sweep whose sweep file, or with ``save_runs`` whose largest
        run file, is estimated above this many bytes, or whose files would not fit the
        free space of their disks (``plan_sweep``).
    max_steps : float, optional
        Refuse a point whose fixed step needs more steps than this.
    max_points : float, optional
        Refuse a grid of more points than this, before it is made.
    device : str, optional
        ``"cpu"`` (default), ``"cuda"`` (the GPU engine, ``rodjit.gpu``: every point in
        this process, in batches; no ``save_runs``) or ``"auto"`` (the GPU if there is one).
    batch_size : int, optional
        Points per batch of the ensemble engine (one compiled call each); by default
        from the measured cost per point, about ``ensemble.BATCH_SECONDS`` of work a
        batch; not used with ``save_runs`` (each point writes its run file).

    Returns
    -------
    SweepTable
        One summary row per point, and each point's bounce table.

    Raises
    ------
    ValueError
        Bad input (any point), a sweep that could not finish or fit, before anything is
        written or started.
    SweepInterrupted
        SIGINT or SIGTERM, after the file is closed with every finished point.
    """
    if config is not None and not isinstance(config, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(config).__name__}")
    jobs = check_jobs(jobs)
    check_batch_size(batch_size)
    check_scheduler(scheduler)
    if device not in (None, "cpu"):
        from ..gpu.executor import sweep_device
        device = sweep_device(device, save_runs, scheduler)
    if not (isinstance(flush_interval, (int, float)) and flush_interval > 0):
        raise ValueError(f"flush_interval = {flush_interval!r} is out of range (seconds > 0)")
    if resume and output is None:
        raise ValueError("resume needs the sweep file to continue (output=PATH)")
    # a new sweep: every check (grid, points, paths, sizes) before the lock is taken
    plan = None if resume else plan_sweep(config, grid, output=output, save_runs=save_runs,
                                          overwrite=overwrite, max_output=max_output,
                                          max_steps=max_steps, max_points=max_points)
    if output is None:
        return _sweep(config, plan, None, jobs, scheduler, save_runs, resume, overwrite,
                      progress, command, handle_signals, flush_interval, max_points, device,
                      batch_size)
    output = Path(output)
    if resume and not output.is_file():
        open_file(output).close()      # the one-line reason: missing, a directory, ...
    # the writer lock of the sweep file, held until it is closed (see output.lock)
    with WriterLock(output):
        return _sweep(config, plan if plan is not None else grid, output, jobs, scheduler,
                      save_runs, resume, overwrite, progress, command, handle_signals,
                      flush_interval, max_points, device, batch_size)


def _sweep(config, grid, output, jobs, scheduler, save_runs, resume, overwrite, progress,
           command, handle_signals, flush_interval, max_points, device=None,
           batch_size=None) -> SweepTable:
    """``sweep`` once this process holds the writer lock of ``output`` (if any); ``grid``
    is the checked SweepPlan of a new sweep, the grid given to a resume."""
    attrs = {}
    plan = None
    if resume:
        base, grid, columns, attrs = _open_resume(output, config, grid, max_points)
        check_memory(len(grid), True)
        if save_runs is None and attrs.get("save_runs"):
            save_runs = attrs["save_runs"]
    else:
        plan = grid
        base, grid = plan.config, plan.grid
        if output is not None:         # again, now that no one else can write it
            output = check_output(output, overwrite, "sweep", held=True)
        columns = _new_columns(grid, base)
    todo = [i for i in range(len(grid)) if columns["status"][i] != "completed"]
    runs_dir = (plan.runs_dir if plan is not None else
                check_runs_dir(save_runs, grid, todo, overwrite, resume, output))
    if command is None:
        command = f"rodjit.sweep(config, grid, output={str(output) if output else None!r})"

    table = SweepTable(grid=grid, base=base, columns=columns,
                       path=str(output) if output is not None else None, status="running")
    if not todo:                                   # a resume with nothing left to run
        table.status = "completed"
        table.stats = sweep_stats(0.0, 0, 0, None)
        sweep_file.finish(output, "completed")
        return table
    if scheduler != "inline" and device != "cuda":    # the GPU engine starts no workers
        check_main()
    t_start = time.perf_counter()
    first = grid.config(base, todo[0])
    # workers load the first point's kernels before they report ready, unless that means
    # running a user's law (which could crash a worker before it has taken any point)
    warm = first if not user_modules(first) else None
    if device == "cuda":   # every point checked for the GPU engine, before the file is made
        from ..gpu.executor import cuda_executor
        executor = cuda_executor(base, grid, todo[0])
    else:                  # last check: a cluster may be unreachable
        # (the points go in batches to the ensemble engine unless each writes a run file)
        executor = make_executor(scheduler, jobs, warm, batched=runs_dir is None and ENGINE)
    if runs_dir is not None:
        runs_dir.mkdir(parents=True, exist_ok=True)
    if output is not None:
        run_attrs = {"save_runs": str(runs_dir) if runs_dir else "", "scheduler": executor.name,
                     "jobs": executor.jobs}
        if resume:
            try:
                with deferred_signals():
                    sweep_file.reopen(output, history=f"resumed ({len(todo)} points to run) "
                                                      f"by: {command}")
            except WriteFailed as exc:
                executor.close(cancel=True)
                raise WriteFailed(f"cannot resume {str(output)!r}: {exc}; the file is as it "
                                  f"was: free space, then run the same command again",
                                  exc.cause) from None
        else:
            created = False
            try:
                with deferred_signals():  # a signal raised inside h5py would garble the layout
                    sweep_file.create(output, base, grid, command=command, attrs=run_attrs)
                    created = True
            except BaseException as exc:  # cut short (a signal, the disk): no file is left
                if created:               # (a signal that came while it was created)
                    Path(output).unlink(missing_ok=True)
                executor.close(cancel=True)
                if isinstance(exc, WriteFailed):
                    raise WriteFailed(f"cannot create {str(output)!r}: {exc}; nothing was "
                                      f"written", exc.cause) from None
                raise
    return _write_sweep(table, executor, todo, runs_dir, progress, command, handle_signals,
                  flush_interval, t_start, batch_size)


def _points(results) -> int:
    """The points of a list of results (PointResults and BatchResults)."""
    return sum(np.size(r.index) for r in results)


def _remove_unreported(runs_dir: Path, grid: Grid, todo, cols) -> None:
    """Remove the run files (and lock files) of the points that did not report before the
    workers were stopped: cut short, they are neither complete nor part of the sweep, and
    the points run again on ``--resume``."""
    for i in todo:
        if cols["status"][i] == "pending":
            path = runs_dir / grid.run_name(i)
            for p in (path, lock_path(path)):
                p.unlink(missing_ok=True)


def _disk_failed(table: SweepTable, output, batch, kept: int, disk) -> None:
    """Stop a sweep whose disk refused a write (``disk``: what was being written, the
    cause, whether it was the sweep file): record what still can be, raise WriteFailed.
    The sweep file keeps every point written before (``kept``); ``resume=True`` runs the
    others once there is space (SweepWriteFailed says so)."""
    what, cause, own = disk
    n = len(table.grid)
    if output is not None and not own:      # a run file failed: the sweep file may not
        try:
            sweep_file.write_results(output, batch)
            kept += _points(batch)
            sweep_file.finish(output, "failed", f"writing {what} failed: {cause}")
        except WriteFailed as exc:
            own, cause = True, f"{cause} (and writing {str(output)!r}: {exc})"
    if output is not None and own:
        note_failure(output, f"a write failed: {cause}")
    table.status = "failed"
    if output is not None:
        failure: WriteFailed = SweepWriteFailed(f"writing {what} failed: {cause}", cause,
                                                output, kept, n)
    else:
        failure = WriteFailed(f"writing {what} failed: {cause}; the sweep stopped after "
                              f"{int(np.sum(table.columns['status'] != 'pending'))} of {n} "
                              f"points", cause)
    table.message = str(failure)
    failure.table = table
    raise failure


def _say_held(output) -> None:
    warnings.warn(FileHeldOpen(
        f"{str(output)!r} is held open by another process (close it there: h5py, a "
        f"notebook, a viewer); the sweep goes on and writes its finished points once the "
        f"file is let go"), stacklevel=2)


def _when_free(write: Callable[[], object], table: SweepTable, points: int, stop,
               said: bool) -> bool:
    """Run ``write`` (a write of the sweep file at the sweep's end), waiting as long as
    another process holds the file open (said once, FileHeldOpen, unless ``said``
    already; returns whether it is said).  A SIGINT or SIGTERM ends the wait, one that
    came while it waits or before it (the sweep was told to stop: it does not wait on a
    reader for ever): SweepInterrupted, the ``points`` finished points held for the file
    not written (``resume=True`` runs them again)."""
    while True:
        try:
            write()
            return said
        except FileBusy:
            if not said:
                _say_held(table.path)
                said = True
            if stop.count:
                signum = stop.signum
                table.status = "interrupted"
                table.message = (f"interrupted by {signal.Signals(signum).name} while "
                                 f"waiting for another process to let go of {table.path!r}; "
                                 + (f"{points} finished points were not written" if points
                                    else "its status was not written"))
                raise SweepInterrupted(table.message, signum, table, table.path) from None


def _write_sweep(table: SweepTable, executor, todo, runs_dir, progress, command,
                 handle_signals, flush_interval, t0: float, batch_size=None) -> SweepTable:
    """Run ``todo`` on ``executor`` (started at ``t0``: its start-up counts in the wall
    time) into ``table`` and its file, writing the finished points every
    ``flush_interval`` seconds (one run's loop is ``driver.files._write_run_blocks``)."""
    grid, base, cols = table.grid, table.base, table.columns
    output = table.path
    n = len(grid)
    done0 = n - len(todo)
    summary = summary_columns(base)

    timing = {"points": 0, "wall": 0.0}

    def tasks():
        # the ensemble engine: batches of points (an executor that batches the points
        # itself, the GPU engine's, takes them one by one)
        if runs_dir is None and ENGINE and not getattr(executor, "takes_points", False):
            yield from batches(todo, base, grid, user_modules(grid.config(base, todo[0])),
                                batch_size, timing, executor.jobs)
            return
        for i in todo:
            cfg = grid.config(base, i)
            path = str(runs_dir / grid.run_name(i)) if runs_dir is not None else None
            yield PointTask(i, cfg, path, user_modules(cfg))

    ran = failed = written = 0
    said: set = set()      # the points' warnings issued so far (each text once)
    t_last = t0
    batch = []
    busy = False           # the last write found the file held by a reader
    last = time.monotonic()
    status, message, signum = "completed", "", None
    disk = None            # the disk refused a write: (what, cause, the sweep file's own?)
    progress = sweep_progress(progress)
    results = executor.results(tasks(), total=len(todo))
    with StopFlag(handle_signals) as stop:
        try:
            for result in results:
                if isinstance(result, BatchResult):
                    reissue_warnings(result, said)
                    for name in summary:
                        cols[name][result.index] = result.values[name]
                    if output is None:
                        for k, table_k in enumerate(split_bounces(result)):
                            table.keep_bounces(int(result.index[k]), table_k)
                    else:
                        batch.append(result)
                    done_k, wall_k = timed(result)
                    timing["points"] += done_k
                    timing["wall"] += wall_k
                    ran += result.index.size
                    failed += int(np.sum(result.values["status"] == "failed"))
                    t_last = time.perf_counter()
                elif result is not None:
                    reissue_warnings(result, said)
                    for name in summary:
                        cols[name][result.index] = result.values[name]
                    if output is None:
                        table.keep_bounces(result.index, result.bounces)
                    else:
                        batch.append(result)
                    ran += 1
                    failed += result.status == "failed"
                    t_last = time.perf_counter()
                    if result.disk:            # its run file: no point in going on
                        status = "failed"
                        disk = (f"the run file {result.values['run_file']!r} of point "
                                f"{result.index}", result.disk, False)
                if progress is not None:
                    progress(SweepProgress(done0 + ran, n, int(np.sum(cols["status"] == "failed")),
                                           ran, len(todo), time.perf_counter() - t0))
                if disk is not None:
                    break
                if stop.signum is not None:
                    status, signum = "interrupted", stop.signum
                    break
                if batch and (time.monotonic() - last >= flush_interval
                              or (len(batch) >= BATCH_ROWS and not busy)):
                    try:      # held by a reader: one try each interval, the points go on
                        sweep_file.write_results(output, batch,
                                                 wait=0.0 if busy else BUSY_WAIT)
                        written += _points(batch)
                        batch = []
                        busy = False
                    except FileBusy:   # a reader holds the file: keep them, retry later
                        if not busy:
                            _say_held(output)
                        busy = True
                    except WriteFailed as exc:
                        status, disk = "failed", (repr(str(output)), str(exc), True)
                        break
                    last = time.monotonic()
        except KeyboardInterrupt:          # a second signal while stopping
            status = "interrupted"
        except BaseException as exc:
            results.close()
            if output is not None:
                try:
                    sweep_file.write_results(output, batch)
                    sweep_file.finish(output, "failed", f"{type(exc).__name__}: {exc}")
                except WriteFailed as failure:
                    note_failure(output, f"a write failed: {failure}")
            raise
        finally:
            stop.abort = False      # tearing down: a signal now is recorded, no more
            results.close()
            executor.close(cancel=status != "completed")
            close_progress(progress)
            if status != "completed" and runs_dir is not None:
                _remove_unreported(runs_dir, grid, todo, cols)
        # still under the StopFlag: a signal during the last write cannot cut it
        if status == "interrupted" and not np.any(cols["status"] == "pending"):
            status = "completed"    # the signal came with the last point: nothing is left
        if disk is not None:
            _disk_failed(table, output, batch, written + done0, disk)
        now = time.perf_counter()
        table.stats = sweep_stats(now - t0, ran, failed, executor, teardown=now - t_last)
        if status == "interrupted":
            name = signal.Signals(signum).name if signum else "KeyboardInterrupt"
            message = f"interrupted by {name} after {done0 + ran} of {n} points"
        if status == "completed" and n and bool(np.all(cols["status"] == "failed")):
            status = "failed"       # nothing to show for it: the file says so, with why
            message = (f"every point of the sweep failed ({n}); the first: "
                       f"{grid.describe(0)}: {cols['message'][0]}")
        table.status, table.message = status, message
        if output is not None:
            try:
                busy = _when_free(lambda: sweep_file.write_results(output, batch,
                                                                   wait=BUSY_WAIT),
                                  table, _points(batch), stop, busy)
                written += _points(batch)
                batch = []
                _when_free(lambda: sweep_file.finish(
                    output, status, message if status != "interrupted" else
                    resume_note(message, output), wait=BUSY_WAIT), table, 0, stop, busy)
            except WriteFailed as exc:
                _disk_failed(table, output, batch, written + done0,
                             (repr(str(output)), str(exc), True))
    if status == "interrupted":
        raise SweepInterrupted(message, signum, table, output)
    if stop.signum is not None:     # after the last point: the sweep is complete
        name = signal.Signals(stop.signum).name
        raise SweepInterrupted(f"interrupted by {name} after the last point"
                               + (f"; {str(output)!r} is complete" if output else ""),
                               stop.signum, table)
    if status == "failed":
        raise SweepFailed(message, table)
    return table
