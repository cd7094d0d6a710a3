"""Runs that stream to an HDF5 file: ``run_to_file`` and ``resume_file``.

The command line is a thin layer over these two functions (so is ``sweep --save-runs``).
They validate everything before touching the disk, checkpoint at least every
``flush_interval`` seconds of wall time and at every stop, and turn SIGINT/SIGTERM into a
clean stop between two compiled calls.  With ``OVERLAP`` the compiled calls run in a worker
thread (``driver.pipeline``): each block is written while the next one computes, and a new
file's layout is created while the first one does.
"""
from __future__ import annotations

import math
import os
import signal
import threading
import time
from pathlib import Path

from ..output import hdf5
from ..output.summary import RunSummary, closed_summary
from ..stepping import layout as L
from .pipeline import Inline, Pipeline
from .run import Run, SimulationError

__all__ = ["run_to_file", "resume_file", "RunInterrupted", "OutputExists"]

FLUSH_INTERVAL = 2.0   # seconds of wall time between checkpoints
OVERLAP = True         # compute the next block in a worker thread while writing the last


class RunInterrupted(RuntimeError):
    """A run stopped by SIGINT/SIGTERM; its file holds a checkpoint (``summary``)."""

    def __init__(self, message: str, signum: int, summary: RunSummary):
        super().__init__(message)
        self.signum = signum
        self.summary = summary


class OutputExists(ValueError):
    """The output file exists and overwriting was not asked for."""


class _StopFlag:
    """While active (main thread only), SIGINT and SIGTERM record the signal instead of
    killing the process; the run stops cleanly at the next return from compiled code.
    A second signal aborts at once."""

    def __init__(self, install: bool):
        self.install = install and threading.current_thread() is threading.main_thread()
        self.signum: int | None = None
        self._old = {}

    def _handler(self, signum, frame):
        if self.signum is not None:
            raise KeyboardInterrupt
        self.signum = signum

    def __enter__(self):
        if self.install:
            for s in (signal.SIGINT, signal.SIGTERM):
                self._old[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *exc):
        for s, old in self._old.items():
            signal.signal(s, old)
        self._old = {}


def check_output(path, overwrite: bool) -> Path:
    """Raise ValueError (one line) unless ``path`` can be created or replaced."""
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.exists():
        raise ValueError(f"output directory {str(parent)!r} does not exist")
    if not parent.is_dir():
        raise ValueError(f"output directory {str(parent)!r} is not a directory")
    if path.is_dir():
        raise ValueError(f"output {str(path)!r} is a directory, not a file")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"output directory {str(parent)!r} is not writable")
    if path.exists():
        if not overwrite:
            raise OutputExists(f"output file {str(path)!r} already exists; pass "
                               f"overwrite=True to replace it")
        if _is_live(path):
            raise hdf5.FileBusy(f"output file {str(path)!r} is being written by a running "
                                f"rodjit process; stop it before replacing the file")
    return path


def _is_live(path) -> bool:
    """True if ``path`` is a rodjit file (a run or a sweep) whose writer is still running
    on this host."""
    try:
        with hdf5.open_file(path) as f:
            return f.attrs.get("status") == "running" and hdf5.writer_alive(f) is True
    except (ValueError, OSError):
        return False


def run_to_file(config, path, *, overwrite: bool = False,
                command: str | None = None, progress=None, t_end: float | None = None,
                flush_interval: float = FLUSH_INTERVAL, handle_signals: bool = True,
                overlap: bool | None = None) -> RunSummary:
    """Run ``config`` (None: the built-in run), streaming everything to the HDF5 file
    ``path``; return its summary.

    ``t_end`` overrides ``time.t_end``; ``progress(run)`` is called between compiled calls;
    ``command`` is recorded in the file (default: this call); ``overlap`` (default
    ``OVERLAP``) computes in a worker thread while writing, False keeps to one thread (the
    file is the same bit for bit).  Bad input raises ValueError
    before anything is written.  A failure raises SimulationError and an interruption
    (SIGINT/SIGTERM, caught while ``handle_signals``) raises RunInterrupted, both after
    the file is closed with its status and a checkpoint; both carry ``summary``.
    """
    from ..config import Config

    if config is None:
        config = Config()
    elif not isinstance(config, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(config).__name__}")
    if t_end is not None:
        config = config.override({"time.t_end": t_end})
    _check_interval(flush_interval)
    path = check_output(path, overwrite)
    if command is None:
        command = f"rodjit.run_to_file(config, {str(path)!r})"
    run = Run(config)
    first = run.checkpoint()     # the file's first checkpoint: the run before it starts
    with _StopFlag(handle_signals) as stop:
        return _drive(run, lambda: hdf5.create_run_file(path, config, first, command=command),
                      path, progress, flush_interval, stop, overlap)


def resume_file(path, *, t_end: float | None = None, command: str | None = None,
                progress=None, flush_interval: float = FLUSH_INTERVAL,
                handle_signals: bool = True, overlap: bool | None = None) -> RunSummary:
    """Continue the run in ``path`` from its checkpoint (to ``t_end`` if given, which also
    extends a completed run); the result equals an uninterrupted run bit for bit.

    A file whose writer was killed (SIGKILL, power loss) is first rebuilt from its last
    checkpoint.  Errors and return value as in ``run_to_file``.
    """
    path = Path(path)
    _check_interval(flush_interval)
    with hdf5.open_file(path) as f:
        hdf5.check_run_file(f, path)
        config = hdf5.read_config(f)
        ck = hdf5.read_checkpoint(f)
        needs_recovery = f.swmr_mode   # opened in SWMR-read mode: the writer never closed it
        alive = hdf5.writer_alive(f) if needs_recovery else False
        pid, host = f.attrs.get("writer_pid"), f.attrs.get("writer_host")
    t = float(ck["clock"][L.T])
    complete = t >= float(ck["clock"][L.T_END]) - float(ck["clock"][L.TOL])
    if t_end is not None:
        if not (math.isfinite(t_end) and t_end > t):
            raise ValueError(f"time.t_end = {t_end!r} is out of range (must be > the "
                             f"checkpoint time t = {t!r})")
        config = config.override({"time.t_end": t_end})
    elif complete and not needs_recovery:
        raise ValueError(f"{str(path)!r} is already complete at t = {t:.9g}; give a later "
                         f"t_end to extend it")
    if alive:
        raise hdf5.FileBusy(f"{str(path)!r} is being written by process {pid}; stop it "
                            f"before resuming")
    if needs_recovery and alive is None:
        raise hdf5.FileBusy(f"{str(path)!r} was being written by process {pid} on host "
                            f"{host!r}; if that process has stopped, run 'h5clear -s "
                            f"{path}' and resume again")
    run = Run.from_checkpoint(config, ck)
    if t_end is not None:
        run.set_t_end(t_end)
    if command is None:
        command = f"rodjit.resume_file({str(path)!r})"
    finish_only = complete and t_end is None    # killed after its last checkpoint
    with _StopFlag(handle_signals) as stop:
        if needs_recovery:
            hdf5.recover(path)
        writer = hdf5.reopen_run_file(
            path, config_toml=config.to_toml() if t_end is not None else None,
            history=(f"closed at its end t = {t!r} by: {command}" if finish_only else
                     f"resumed at t = {t!r} by: {command}"))
        if finish_only:
            writer.close(run, "completed")
            return closed_summary(writer)
        return _drive(run, lambda: writer, path, progress, flush_interval, stop, overlap)


def _check_interval(flush_interval) -> None:
    if not (isinstance(flush_interval, (int, float)) and flush_interval > 0
            and math.isfinite(flush_interval)):
        raise ValueError(f"flush_interval = {flush_interval!r} is out of range (seconds > 0)")


def _drive(run: Run, open_writer, path: Path, progress, flush_interval: float,
           stop: _StopFlag, overlap: bool | None = None) -> RunSummary:
    """Advance ``run`` until done, failed or stopped, into the writer ``open_writer()``
    returns (called once the first compiled call is under way); close the file."""
    calls = (Pipeline if (OVERLAP if overlap is None else overlap) else Inline)(run)
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
            if stop.signum is None:
                calls.launch()
            writer = open_once()
            last = time.monotonic()
            while True:
                if calls.busy:
                    block = calls.wait()
                    if progress is not None:
                        progress(run)
                else:                     # stopped before the first call
                    block = run.take()
                more = (block.code in (L.PAUSED, L.FULL) and block.finite
                        and stop.signum is None)
                save = more and time.monotonic() - last >= flush_interval
                if more and not save:
                    calls.launch()        # the next block computes while this one is written
                calls.drain(block, writer)
                if block.code == L.FAILED:
                    raise SimulationError(run.failure_message())
                if block.code == L.DONE:
                    status = "completed"
                    break
                if not more:
                    status = "interrupted"
                    break
                if save:                  # nothing in flight: every computed row is written
                    writer.save(run)
                    last = time.monotonic()
                    calls.launch()
        finally:
            calls.close()
    except SimulationError as exc:
        open_once().close(run, "failed", str(exc))
        exc.summary = closed_summary(writer)
        raise
    except BaseException as exc:
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
    if status == "interrupted":
        name = signal.Signals(stop.signum).name
        message = (f"interrupted by {name} at t = {run.t:.9g}; continue with: "
                   f"rodjit run --resume {path}")
    writer.close(run, status, message)
    summary = closed_summary(writer)
    if status == "interrupted":
        raise RunInterrupted(message, stop.signum, summary)
    return summary
