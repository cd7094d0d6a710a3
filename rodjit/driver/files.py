"""Runs that stream to an HDF5 file: ``run_to_file`` and ``resume_file``.

The command line is a thin layer over these two functions (so is ``sweep --save-runs``).
They validate everything before touching the disk, checkpoint at least every
``flush_interval`` seconds of wall time and at every stop, and turn SIGINT/SIGTERM into a
clean stop between two compiled calls.  The compiled calls and the writing of their
blocks take turns in the calling thread.
"""
from __future__ import annotations

import math
import os
import signal
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from ..config import Config
from ..output import run_writer
from ..output.estimate import (MAX_OUTPUT, MAX_STEPS, Estimate, check_run, format_size,
                               free_space)
from ..output.h5files import (FileBusy, OutputExists, WriteFailed, abandon, check_output,
                              damaged, disk_cause, open_file, repair_truncated, writer_alive,
                              writer_pid)
from ..output.lock import WriterLock, note_failure
from ..output.run_reader import check_not_lost, check_run_file, read_checkpoint, read_config
from ..output.summary import RunSummary, closed_summary
from ..stepping import layout as L
from .errors import RunWriteFailed, resume_command
from .progress import close as close_progress
from .progress import run_progress
from .run import Run, SimulationError, warn_config
from .signals import StopFlag

__all__ = ["run_to_file", "plan_run", "RunPlan", "resume_file", "RunInterrupted", "OutputExists",
           "check_output"]

RUN_FLUSH_INTERVAL = 2.0   # seconds of wall time between checkpoints of a run file


class RunInterrupted(RuntimeError):
    """A run stopped by SIGINT/SIGTERM; its file holds a checkpoint (``summary``).

    ``resume_file`` continues the run from that checkpoint.

    Parameters
    ----------
    message : str
        Which signal stopped the run, at which simulated time (``stem``).
    signum : int
        The signal number (``signal.SIGINT``, ``signal.SIGTERM``).
    summary : RunSummary
        The summary of the file as checkpointed.
    path : str or os.PathLike, optional
        The run file that ``resume_file`` continues (``path``, a str); the message then
        ends with how to resume.
    """

    def __init__(self, message: str, signum: int, summary: RunSummary,
                 path: str | os.PathLike[str] | None = None):
        self.stem = message
        self.path = None if path is None else str(path)
        super().__init__(message if path is None else
                         f"{message}; continue with resume_file({self.path!r})")
        self.signum = signum
        self.summary = summary


def run_to_file(config: Config | None, path: str | os.PathLike[str], *,
                overwrite: bool = False, command: str | None = None,
                progress: bool | Callable[[Any], object] | None = None, t_end: float | None = None,
                flush_interval: float = RUN_FLUSH_INTERVAL, handle_signals: bool = True,
                max_output: float = MAX_OUTPUT, max_steps: float = MAX_STEPS) -> RunSummary:
    """Run ``config`` (None: the built-in run), streaming everything to the HDF5 file
    ``path``; return its summary.

    Parameters
    ----------
    config : Config or None
        The run; ``None`` is ``Config()``.
    path : str or os.PathLike
        The run file to write.
    overwrite : bool
        Replace an existing file (otherwise ``OutputExists`` is raised).
    command : str, optional
        The command line recorded in the file (default: this call).
    progress : bool or callable, optional
        True for a progress bar (tqdm; a widget in notebooks, saying when the kernels are
        first compiled), or a callable: ``progress(run)`` is called between compiled calls.
    t_end : float, optional
        Overrides ``time.t_end``.
    flush_interval : float
        Wall-clock seconds between saves of data and checkpoint.
    handle_signals : bool
        Catch SIGINT/SIGTERM, stop between two compiled calls and checkpoint.
    max_output : float, optional
        Refuse (ValueError) a run whose file is estimated above this many bytes, or above
        the free space of its disk (``output.estimate.check_run``).
    max_steps : float, optional
        Refuse a fixed step that needs more steps than this (and, whatever the limit, one
        that time cannot resolve or that does not divide the output intervals).

    Returns
    -------
    RunSummary
        What ``rodjit run`` prints at the end (``.report()``).

    Raises
    ------
    ValueError
        Bad input, or a run that could not finish or fit, before anything is written.
    SimulationError
        The run failed; raised after the file is closed with its status and a checkpoint,
        and carries ``summary``.
    RunInterrupted
        SIGINT/SIGTERM while ``handle_signals``; likewise after the file is closed.
    """
    plan = plan_run(config, path, overwrite=overwrite, t_end=t_end, max_output=max_output,
                    max_steps=max_steps, flush_interval=flush_interval)
    config, out = plan.config, plan.path
    if out is None:        # plan_run returns the path it was given, checked
        raise ValueError("run_to_file needs an output path")
    if command is None:
        command = f"rodjit.run_to_file(config, {str(out)!r})"
    run = Run(config)
    warn_config(config)
    first = run.checkpoint()     # the file's first checkpoint: the run before it starts
    # the writer lock, held from the last check until the file is closed: no second
    # writer can create, replace or resume the file meanwhile
    with WriterLock(out), StopFlag(handle_signals) as stop:
        check_output(out, overwrite, "run", held=True)   # again, now that no one else can write it
        return _write_run(run, lambda: run_writer.create_run_file(out, config, first,
                                                                  command=command),
                          out, progress, flush_interval, stop)


@dataclass
class RunPlan:
    """What ``run_to_file`` would do, checked but not done (``plan_run``).

    Parameters
    ----------
    config : Config
        The resolved configuration (``t_end`` applied).
    path : pathlib.Path or None
        The output, None if no path was checked.
    estimate : Estimate
        Snapshot and diagnostics rows, file bytes, memory bytes, fixed steps.
    replaces : bool
        The output exists and would be replaced.
    free : float or None
        Bytes free on the output's disk (None: unknown).
    max_output : float
        The size limit the run was checked against.
    """

    config: Config
    path: Path | None
    estimate: Estimate
    replaces: bool
    free: float | None
    max_output: float

    def report(self) -> str:
        """The lines ``rodjit run --dry-run`` prints."""
        e, c = self.estimate, self.config
        lines = ["dry run: checked, nothing written"]
        if self.path is not None:
            what = "replaces the existing run file" if self.replaces else "a new file"
            lines.append(f"output       {self.path.absolute()} ({what})")
        for name, rows, key in (("snapshots", e.snapshots, "snapshot_interval"),
                                ("diagnostics", e.diagnostics, "diagnostics_interval")):
            every = getattr(c.output, key)
            if name == "snapshots" and c.output.times:
                lines.append(f"{name:<13}{rows} rows (at output.times)")
                continue
            lines.append(f"{name:<13}{rows} rows" + (f" (every {every:g} s to t = "
                                                     f"{c.time.t_end:g})" if every else ""))
        free = f", {format_size(self.free)} free" if self.free is not None else ""
        lines.append(f"file         about {format_size(e.file_bytes)} before contact "
                     f"episodes and bounces (limit {format_size(self.max_output)}{free})")
        lines.append(f"memory       about {format_size(e.memory_bytes)}")
        lines.append(f"steps        {e.steps:.6g} fixed steps of time.dt = {c.time.dt:g}"
                     if e.steps is not None else
                     f"steps        adaptive ({c.ran_with()})")
        return "\n".join(lines)


def plan_run(config: Config | None = None, path: str | os.PathLike[str] | None = None, *,
             overwrite: bool = False, t_end: float | None = None,
             max_output: float = MAX_OUTPUT, max_steps: float = MAX_STEPS,
             flush_interval: float = RUN_FLUSH_INTERVAL) -> RunPlan:
    """Check everything ``run_to_file`` checks before it writes, and say what it would
    write, without writing anything (no file, no lock, no directory).

    Parameters
    ----------
    config : Config or None
        The run; ``None`` is ``Config()``.
    path : str or os.PathLike, optional
        The run file that would be written: its directory must exist and be writable, and
        an existing file may be replaced only with ``overwrite`` and only if it is a rodjit
        run file whose writer is not running.  None: check the configuration only.
    overwrite : bool
        As in ``run_to_file``.
    t_end : float, optional
        Overrides ``time.t_end``.
    max_output, max_steps, flush_interval : float, optional
        As in ``run_to_file``: the largest file (bytes), the most fixed steps allowed, the
        seconds between checkpoints.

    Returns
    -------
    RunPlan
        The resolved configuration and path, the estimate (snapshot and diagnostics rows,
        file size, memory, fixed steps) and the free space; ``.report()`` is what
        ``rodjit run --dry-run`` prints.

    Raises
    ------
    ValueError
        What ``run_to_file`` would refuse, with the same message.
    """
    if config is None:
        config = Config()
    elif not isinstance(config, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(config).__name__}")
    if t_end is not None:
        config = config.override({"time.t_end": t_end})
    config = config.resolve()        # "auto": the integrator this run takes, chosen once
    _check_interval(flush_interval)
    replaces = False
    if path is not None:
        path = check_output(path, overwrite, "run")
        replaces = path.exists()
    estimate = check_run(config, path, max_output=max_output, max_steps=max_steps)
    return RunPlan(config, path, estimate, replaces,
                   free_space(path) if path is not None else None, max_output)


def resume_file(path: str | os.PathLike[str], *, t_end: float | None = None,
                command: str | None = None, progress: bool | Callable[[Any], object] | None = None, flush_interval: float = RUN_FLUSH_INTERVAL,
                handle_signals: bool = True, max_output: float = MAX_OUTPUT,
                max_steps: float = MAX_STEPS) -> RunSummary:
    """Continue the run in ``path`` from its checkpoint (to ``t_end`` if given, which also
    extends a completed run); the result equals an uninterrupted run bit for bit.  An
    extension continues from the end state: for the integrators that land on the output
    times it equals a run made to the new end at once, bit for bit; those with a dense
    output (``dp54``, ``dop853``, ``radau5``: ``auto``'s) step toward ``time.t_end``, so the
    first run's last step, which ended on its end, is one a longer run did not take.

    A file whose writer was killed (SIGKILL, power loss) is first rebuilt from its last
    checkpoint.  Errors and return value as in ``run_to_file``.

    Parameters
    ----------
    path : str or os.PathLike
        The run file to continue.
    t_end : float, optional
        The new end time (default: the file's ``time.t_end``).
    command, progress, flush_interval, handle_signals
        As in ``run_to_file``.
    max_output, max_steps : float, optional
        As in ``run_to_file``, for the file the continued run makes (its estimate to the
        new end, the same as a new run's; only what it adds must fit the free space).
    """
    path = Path(path)
    _check_interval(flush_interval)
    if not os.path.isfile(path):     # (False for a name too long: open_file says so)
        open_file(path).close()      # the one-line reason: missing, a directory, ...
    with WriterLock(path):
        return _resume_locked(path, t_end, command, progress, flush_interval,
                              handle_signals, max_output, max_steps)


def _resume_locked(path: Path, t_end, command, progress, flush_interval,
                   handle_signals, max_output=MAX_OUTPUT,
                   max_steps=MAX_STEPS) -> RunSummary:
    """``resume_file`` once this process holds the writer lock of ``path``."""
    cut = repair_truncated(path)   # cut short by a full disk: its checkpoint is still there
    try:
        with open_file(path) as f, damaged(path):
            check_run_file(f, path)
            config = read_config(f)
            ck = read_checkpoint(f)
            if cut is not None:
                check_not_lost(f, ck, cut[0], path)
            needs_recovery = f.swmr_mode   # SWMR-read mode: the writer never closed it
            alive = writer_alive(f, lock=False) if needs_recovery else False
            pid = writer_pid(f) if alive else None
    except ValueError:
        if cut is not None:        # refused: the file goes back to what it was
            os.truncate(path, cut[0])
        raise
    t = float(ck["clock"][L.T])
    complete = t >= float(ck["clock"][L.T_END]) - float(ck["clock"][L.TOL])
    if complete and t < config.time.t_end - float(ck["clock"][L.TOL]):
        # ended before time.t_end by time.stop_after_bounces or time.stop_at_rest: it
        # would end again at once
        raise ValueError(f"{str(path)!r} is complete: it ended at t = {t:.9g} by "
                         f"time.stop_after_bounces or time.stop_at_rest, before time.t_end "
                         f"= {config.time.t_end:g}")
    if t_end is not None:
        if not (math.isfinite(t_end) and t_end > t):
            raise ValueError(f"time.t_end = {t_end!r} is out of range (must be > the "
                             f"checkpoint time t = {t!r})")
        config = config.override({"time.t_end": t_end})
    elif complete and not needs_recovery:
        raise ValueError(f"{str(path)!r} is already complete at t = {t:.9g}; give a later "
                         f"t_end to extend it")
    if alive:
        raise FileBusy(f"{str(path)!r} is being written by a live rodjit process on this "
                       f"machine (process {pid}); stop it before resuming")
    if needs_recovery and alive is None:
        raise FileBusy(f"{str(path)!r} was being written on another machine, whose process "
                       f"this one cannot see; if that process has stopped, run 'h5clear -s "
                       f"{path}' and resume again")
    run = Run.from_checkpoint(config, ck)
    if t_end is not None:
        run.set_t_end(t_end)
    if command is None:
        command = f"rodjit.resume_file({str(path)!r})"
    finish_only = complete and t_end is None    # killed after its last checkpoint
    if not finish_only:       # the limits of a new run, on the file it makes to its end
        check_run(config, path, max_output=max_output, max_steps=max_steps,
                  what="the continued run", written=path.stat().st_size)
    with StopFlag(handle_signals) as stop:
        with damaged(path):
            if needs_recovery:
                run_writer.recover(path)
            writer = run_writer.reopen_run_file(
                path, config_toml=config.to_toml() if t_end is not None else None,
                history=(f"closed at its end t = {t!r} by: {command}" if finish_only else
                         f"resumed at t = {t!r} by: {command}"))
        if finish_only:
            writer.close(run, "completed")
            return closed_summary(writer)
        return _write_run(run, lambda: writer, path, progress, flush_interval, stop)


def _write_failed(path: Path, writer, cause: str) -> WriteFailed:
    """The error of a write the disk refused.  The file is left as the disk has it: HDF5
    cannot close a file it can no longer extend, and any further write could only make it
    worse; its last checkpoint is intact, and a resume repairs the end of the file."""
    if writer is None:
        return WriteFailed(f"cannot create {str(path)!r}: {cause}; nothing was written", cause)
    abandon(writer, writer.file)    # never closed nor flushed again by this process
    writer.file = None
    t = float(writer.checkpoint["clock"][L.T])
    note_failure(path, f"a write failed: {cause}")
    return RunWriteFailed(path, cause, t)


def _check_interval(flush_interval) -> None:
    if not (isinstance(flush_interval, (int, float)) and flush_interval > 0
            and math.isfinite(flush_interval)):
        raise ValueError(f"flush_interval = {flush_interval!r} is out of range (seconds > 0)")


def _write_run(run: Run, open_writer, path: Path, progress, flush_interval: float,
               stop: StopFlag) -> RunSummary:
    """Advance ``run`` until done, failed or stopped, into the writer ``open_writer()``
    returns (called once the run has started); close the file.  A write
    the disk refuses, at any point (layout, rows, checkpoints, closing), raises
    WriteFailed."""
    opened = []

    def open_and_keep():
        opened.append(open_writer())
        return opened[-1]

    try:
        return _write_run_blocks(run, open_and_keep, path, progress, flush_interval, stop)
    except BaseException as exc:
        if isinstance(exc, WriteFailed) and not opened:
            raise
        cause = disk_cause(exc)
        if cause is None:
            raise
        abandon(exc.__traceback__)  # the h5py objects its frames hold: never freed
        raise _write_failed(path, opened[-1] if opened else None, cause) from None


def _write_run_blocks(run: Run, open_writer, path: Path, progress, flush_interval: float,
                      stop: StopFlag) -> RunSummary:
    """``_write_run`` without the translation of disk errors: the loop that alternates the
    run's compiled calls with writing their blocks, and checkpoints every
    ``flush_interval`` seconds (a sweep's loop, ``sweeps.run_sweep._write_sweep``, collects
    finished points from an executor instead: it has no blocks, calls nor checkpoints)."""
    progress = run_progress(progress)
    writer = None
    opened = False

    def open_once():                      # the file, also when a run stops before it opens
        nonlocal writer, opened
        if not opened:
            opened = True
            writer = open_writer()
        return writer

    try:
        try:
            run.start(None)               # compile; the outputs at t0 wait in the buffers
            call = stop.signum is None    # no call if stopped while compiling
            writer = open_once()
            last = time.monotonic()
            while True:
                if call:
                    block = run.take(run.compute())
                    if progress is not None:
                        progress(run)
                else:                     # stopped before the first call
                    block = run.take()
                call = True
                more = (block.code in (L.PAUSED, L.FULL) and block.finite
                        and stop.signum is None)
                save = more and time.monotonic() - last >= flush_interval
                run.drain(block, writer)
                if block.code == L.FAILED:
                    raise SimulationError(run.failure_message())
                if block.code == L.DONE:
                    status = "completed"
                    break
                if not more:
                    status = "interrupted"
                    break
                if save:
                    writer.save(run)      # every computed row is written
                    last = time.monotonic()
        finally:
            close_progress(progress, run)
    except SimulationError as exc:
        failed = open_once()
        failed.close(run, "failed", str(exc))
        exc.summary = closed_summary(failed)
        raise
    except BaseException as exc:
        if disk_cause(exc) is not None:
            raise
        if not opened:
            try:
                open_once()
            except Exception:
                pass              # the original error is the one to report
        if writer is not None:
            kind = "interrupted" if isinstance(exc, KeyboardInterrupt) else "failed"
            writer.abandon(kind, f"{type(exc).__name__}: {exc}; the last checkpoint is kept")
        raise
    message = ""
    assert writer is not None        # opened above, on every path that gets here
    signum = stop.signum if stop.signum is not None else signal.SIGINT
    if status == "interrupted":
        name = signal.Signals(signum).name
        message = f"interrupted by {name} at t = {run.t:.9g}"
    writer.close(run, status, message and resume_command(message, path))
    summary = closed_summary(writer)
    if status == "interrupted":
        raise RunInterrupted(message, signum, summary, path)
    return summary
