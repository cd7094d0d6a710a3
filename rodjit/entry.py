"""The command line's entry point, ``main()``: both ``python -m rodjit`` and the installed
``rodjit`` command run it.

SIGINT and SIGTERM are handled from here on: until a run or a sweep takes them over (with
a clean stop at its next checkpoint, ``driver.signals.StopFlag``), a signal ends the
command with one line and exit code 128 + the signal number (130, 143), not a Traceback
or click's "Aborted!".  Nothing is half-written then: no output file is open outside a
StopFlag except while a sweep file is created, which is removed if that is cut short.
Every error, click's usage errors included, is one line on stderr; so is an environment
Numba cannot start with (``NUMBA_NUM_THREADS``), refused before any verb runs (exit 2),
and standard output refusing a write (a full disk: exit 1).  SIGXFSZ is ignored: a
file-size limit (``ulimit -f``) then fails the write (EFBIG), which is reported in one line
like a full disk, instead of killing the process.
"""
import os
import signal
import sys
from typing import Any, NoReturn, TextIO

from .driver.signals import Interrupted, install_early_handlers

__all__ = ["main"]


def _finish(code: int) -> NoReturn:
    """Exit with ``code``. The command's work is over (its files are closed), so SIGINT and
    SIGTERM are ignored (process-wide, whichever thread the kernel picks) and blocked
    first: the interpreter's shutdown puts the default handlers back where Python had set
    one of its own (not where it was told to ignore), and a signal arriving then would kill
    the process (-15) after a successful run.  A
    process holding files the disk failed (``output.abandoned``) ends without the
    interpreter's shutdown, which would try to close them."""
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    code = _stdout_refused(code)
    held = sys.modules.get("rodjit.output.abandoned")
    if held is not None and held.abandoned():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


def _stdout_refused(code: int) -> int:
    """``code``, or 1 with one line naming the cause where standard output refused a write
    (``_PipeSafe.failed``) and the command had nothing else to say (exit 0)."""
    out = sys.stdout
    if not isinstance(out, _PipeSafe):
        return code
    out.flush()
    if out.failed is None or code != 0:
        return code
    cause = out.failed.strerror or str(out.failed)
    print(f"Error: could not write to standard output: {cause}", file=sys.stderr)
    return 1


def _exit_interrupted(signum: int) -> NoReturn:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    print(f"Error: interrupted by {signal.Signals(signum).name}", file=sys.stderr)
    _finish(128 + signum)


class _PipeSafe:
    """Standard output that cannot fail the command's work: a reader closing its end
    (``rodjit info x.h5 | head -1``, ``| true``) sends what is left to /dev/null and the
    command ends with the exit code of its work, as ``head``-style pipes expect; any other
    refused write (a full disk: ``rodjit config > /dev/full``, a size limit, EIO) does the
    same and is kept in ``failed``, which ``_finish`` reports in one line (exit 1) where
    the work itself succeeded, instead of a Traceback from wherever the write was."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream
        self.failed: OSError | None = None

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._drop()
        except OSError as exc:
            self._refused(exc)
        return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._drop()
        except OSError as exc:
            self._refused(exc)

    def _refused(self, exc: OSError) -> None:
        if self.failed is None:
            self.failed = exc
        self._drop()
        try:
            self._stream.flush()     # what the buffer still holds goes to /dev/null too
        except OSError:
            pass

    def _drop(self) -> None:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, self._stream.fileno())
        os.close(null)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


# multiprocessing's resource tracker, a process of its own that outlives a command killed
# with SIGKILL mid-sweep, cleans up the semaphores that command could not release and warns
# about them on the terminal in two lines of Python's: after a SIGKILL, rodjit says nothing
# (the processes it starts read this from the environment)
_QUIET_TRACKER = "ignore::UserWarning:multiprocessing.resource_tracker"


def _quiet_resource_tracker() -> None:
    given = os.environ.get("PYTHONWARNINGS", "")
    if _QUIET_TRACKER not in given.split(","):
        os.environ["PYTHONWARNINGS"] = f"{given},{_QUIET_TRACKER}" if given else _QUIET_TRACKER


def main() -> None:
    """Run the ``rodjit`` command line on ``sys.argv`` and exit with its code."""
    if sys.stdout is not None and not isinstance(sys.stdout, _PipeSafe):
        sys.stdout = _PipeSafe(sys.stdout)
    _quiet_resource_tracker()
    try:
        install_early_handlers()     # (already while ``rodjit/__init__`` was imported)
        if hasattr(signal, "SIGXFSZ"):
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        from ._jit import check_numba_environment

        try:
            check_numba_environment()    # before a verb makes a file it could not finish
        except ValueError as exc:
            print(f"Error: {exc}", file=sys.stderr)
            _finish(2)
        import click

        from .cli import main as command, one_line

        try:
            code = command.main(prog_name="rodjit", standalone_mode=False)
        except SystemExit as exc:           # a command's own sys.exit
            if exc.code is not None and not isinstance(exc.code, int):
                print(exc.code, file=sys.stderr)
            _finish(exc.code if isinstance(exc.code, int) else int(exc.code is not None))
        except click.exceptions.Abort:      # click's form of KeyboardInterrupt
            _exit_interrupted(signal.SIGINT)
        except click.exceptions.Exit as exc:
            _finish(exc.exit_code)
        except click.ClickException as exc:
            print(f"Error: {one_line(exc.format_message())}", file=sys.stderr)
            _finish(exc.exit_code)
        else:
            _finish(code if isinstance(code, int) else 0)
    except (Interrupted, KeyboardInterrupt) as exc:
        _exit_interrupted(exc.signum if isinstance(exc, Interrupted) else signal.SIGINT)
