"""Dask's own log lines through rodjit's reporting.

Distributed logs through the standard ``logging`` module, with stderr handlers it installs
when imported, in its own format (``2026-12-05 11:34:38,587 - distributed.scheduler -
ERROR - Task ... marked as failed ...``, and a traceback over many lines for some).  On the
command line that is a second voice beside rodjit's own one-line ``warning:``/``Error:``
lines.  ``route_dask_logs`` (called when a sweep, ``converge`` or ``fit`` starts a Dask
executor, once distributed is imported) puts one handler of its own in place of those:
each record becomes a ``DaskLogWarning``, which the command line says as one ``warning:``
line like every other warning (``cli.say_warning``: once per text, on stderr) and a Python
caller can filter like any warning.  The record keeps its origin in the text:
``distributed.scheduler (ERROR): Task ... marked as failed ...``; a traceback is cut to
its exception's type and message.

Levels are left as they are: ``-q`` raises the Dask loggers' levels (``cli._quiet_dask``),
so nothing reaches the handler then, and a LocalCluster's ``silence_logs`` still sets this
handler's level (it is a StreamHandler) for the cluster's lifetime, as it did the handler it
replaces.  The worker processes log in their own process: the log format they read from
the environment (``DASK_DISTRIBUTED__ADMIN__LOG_FORMAT``, unless the user set one) makes
each of their lines start like rodjit's.
"""
from __future__ import annotations

import logging
import os
import sys
import warnings

__all__ = ["DaskLogWarning", "route_dask_logs", "WORKER_LOG_FORMAT"]

LOGGERS = ("distributed", "dask", "tornado", "bokeh")
WORKER_LOG_FORMAT = "warning: %(name)s (%(levelname)s): %(message)s"
_FORMAT_ENV = "DASK_DISTRIBUTED__ADMIN__LOG_FORMAT"


class DaskLogWarning(UserWarning):
    """A log record of Dask or distributed, issued as a warning (one line)."""


class _AsWarnings(logging.StreamHandler):
    """Each record as one ``DaskLogWarning`` naming its logger and level.  A StreamHandler
    only so that distributed's ``silence_logs`` sets its level as it did the handler's it
    replaces; it writes nothing to a stream itself."""

    def __init__(self):
        super().__init__(sys.stderr)
        self.setLevel(logging.WARNING)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = " ".join(record.getMessage().split())
            if record.exc_info and record.exc_info[1] is not None:
                exc = record.exc_info[1]
                text += f" ({type(exc).__name__}: {' '.join(str(exc).split())})"
            warnings.warn_explicit(f"{record.name} ({record.levelname}): {text}",
                                   DaskLogWarning, record.pathname or "dask",
                                   record.lineno or 0, module=record.name)
        except Exception:           # never let a log line break the work (logging's rule)
            self.handleError(record)


_HANDLER = _AsWarnings()


def route_dask_logs() -> None:
    """Replace the stderr handlers of the Dask, distributed, tornado and bokeh loggers of
    this process by ``_HANDLER`` (idempotent), and give the worker processes started from
    here the one-line format (``WORKER_LOG_FORMAT``)."""
    os.environ.setdefault(_FORMAT_ENV, WORKER_LOG_FORMAT)
    loggers = [logging.getLogger(name) for name in
               [n for n in logging.root.manager.loggerDict
                if n.split(".")[0] in LOGGERS] + list(LOGGERS)]
    for logger in loggers:
        theirs = [h for h in logger.handlers if type(h) is logging.StreamHandler]
        for h in theirs:
            logger.removeHandler(h)
        # a top-level logger with no handler anywhere would reach logging's last resort,
        # which prints the bare message on stderr
        bare = (logger.name in LOGGERS and not logger.handlers and not logging.root.handlers)
        if (theirs or bare) and _HANDLER not in logger.handlers:
            logger.addHandler(_HANDLER)
