"""How a sweep ends, as its caller sees it: the exceptions of an interrupted or wholly failed
sweep, the progress record passed as points finish, and the statistics of the call
(``SweepTable.stats``)."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

from .sweep_table import SweepTable

__all__ = ["SweepInterrupted", "SweepFailed", "SweepProgress", "sweep_stats"]


class SweepInterrupted(RuntimeError):
    """A sweep stopped by SIGINT/SIGTERM; its file holds every finished point (``table``).

    Running the same sweep again with ``resume=True`` runs only the points not finished.

    Parameters
    ----------
    message : str
        Which signal stopped the sweep and how many points finished (``stem``).
    signum : int or None
        The signal number; None when a second interrupt arrived while stopping.
    table : SweepTable
        The table at the stop: finished points ``"completed"`` or ``"failed"``, the rest
        ``"pending"``.
    output : str or os.PathLike, optional
        The sweep file that ``resume=True`` continues (``output``, a str); None when there
        is nothing to continue (no file, or every point finished).  The message then ends
        with how to resume.
    """

    def __init__(self, message: str, signum: int | None, table: SweepTable,
                 output: str | os.PathLike[str] | None = None):
        self.stem = message
        self.output = None if output is None else str(output)
        super().__init__(message if output is None else
                         f"{message}; continue with resume=True (output={self.output!r})")
        self.signum = signum
        self.table = table


class SweepFailed(RuntimeError):
    """Every point of a sweep failed (the file, if any, was closed with their messages).

    Parameters
    ----------
    message : str
        What failed, in one line.
    table : SweepTable
        The sweep's table, each point's message in its ``message`` column.
    """

    def __init__(self, message: str, table: SweepTable):
        super().__init__(message)
        self.table = table


@dataclass
class SweepProgress:
    """Where a sweep stands, passed to ``progress`` after every result and heartbeat.

    Attributes
    ----------
    done : int
        Points finished, earlier sessions of a resumed sweep included.
    total : int
        Points in the grid.
    failed : int
        Points failed so far.
    run : int
        Points finished in this call.
    todo : int
        Points this call set out to run.
    elapsed : float
        Seconds since this call started.
    """

    done: int          # points finished, earlier sessions included
    total: int
    failed: int
    run: int           # points finished in this call
    todo: int          # points this call set out to run
    elapsed: float     # seconds since this call started

    @property
    def eta(self) -> float:
        """Seconds left at the rate of this call so far (NaN before the first point)."""
        if self.run == 0:
            return math.nan
        return self.elapsed / self.run * (self.todo - self.run)


def sweep_stats(wall: float, ran: int, failed: int, executor, teardown: float = 0.0) -> dict:
    """What ``SweepTable.stats`` reports of this call: wall time from the start of the
    executor, of which ``startup_time`` until its workers were ready and ``teardown_time``
    after the last result (stopping them, the last write)."""
    return {"wall_time": wall, "points_run": ran, "points_failed": failed,
            "points_per_second": ran / wall if wall > 0 else 0.0,
            "startup_time": getattr(executor, "startup_time", None),
            "teardown_time": teardown,
            "worker_deaths": getattr(executor, "deaths", 0),
            "tasks": getattr(executor, "tasks", ran),
            "backend": executor.name if executor is not None else "none",
            "jobs": executor.jobs if executor is not None else 0}
