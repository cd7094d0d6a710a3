"""Exit codes of the ``rodjit`` command and the two errors that end a verb with one line.

Exit codes: 0 done, 1 the run failed (or a sweep point did), 2 usage or configuration error
(nothing written), 130/143 interrupted by SIGINT/SIGTERM (checkpoint written).
"""
from __future__ import annotations

import os
import sys
from typing import NoReturn

import click

__all__ = ["EXIT_OK", "EXIT_FAILED", "EXIT_USAGE", "EXIT_SIGNAL", "EXIT_CODES", "UsageError",
           "RunFailed", "one_line", "disk_failed"]

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_SIGNAL = 128          # + the signal's number: 130 SIGINT, 143 SIGTERM
# the table of exit codes, as ``rodjit --help`` and docs/reference/cli.md print it
EXIT_CODES = {
    EXIT_OK: "done (every run or point completed)",
    EXIT_FAILED: "a run, a sweep point or a fit failed, or the disk refused a write (the "
                 "file keeps its last checkpoint and says why)",
    EXIT_USAGE: "usage, configuration, path or file error: one line, nothing written",
    EXIT_SIGNAL + 2: "stopped by SIGINT (a checkpoint is written; --resume continues)",
    EXIT_SIGNAL + 15: "stopped by SIGTERM (likewise)",
}


def one_line(message: object) -> str:
    """``message`` on one line (HDF5's messages embed newlines).

    Parameters
    ----------
    message : object
        An error or a text.

    Returns
    -------
    str
        Its text, runs of white space (newlines included) as one space.
    """
    return " ".join(str(message).split())


def _line(message: object) -> str:
    """An error as the command line words it (``wording.word``), or a text; on one line."""
    from .wording import word

    return one_line(word(message) if isinstance(message, BaseException) else message)


class UsageError(click.ClickException):
    """One line on stderr, exit code 2; raised before anything is written.

    Parameters
    ----------
    message : object
        The error (worded for the command line, ``wording.word``) or a text; put on one
        line.
    """

    exit_code = EXIT_USAGE

    def __init__(self, message: object) -> None:
        super().__init__(_line(message))


class RunFailed(click.ClickException):
    """One line on stderr, exit code 1: the work ran and failed.

    Parameters
    ----------
    message : object
        The error (worded for the command line, ``wording.word``) or a text; put on one
        line.
    """

    exit_code = EXIT_FAILED

    def __init__(self, message: object) -> None:
        super().__init__(_line(message))


def disk_failed(exc: OSError) -> NoReturn:
    """Exit 1 with one line when the disk failed a write.  The process ends at once
    (``os._exit``): HDF5 would otherwise try to flush the abandoned file again while the
    interpreter shuts down, printing tracebacks or crashing.

    Parameters
    ----------
    exc : OSError
        What the write raised.
    """
    from ..output.h5files import WriteFailed, disk_cause
    from .wording import word

    cause = disk_cause(exc)
    text = word(exc) if isinstance(exc, WriteFailed) or cause is None else (
        f"a write failed: {cause} ({exc})")
    click.echo(f"Error: {one_line(text)}", err=True)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(EXIT_FAILED)
