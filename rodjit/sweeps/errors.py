"""The typed errors of a sweep's input and of its writes: each carries the fields a message
needs (the path, the count, the limit, the key), and its own message speaks Python
(``max_points=``, ``overwrite=True``, ``resume=True``).  The command line words them in its
options (``rodjit/cli/wording.py``); every one is a ValueError (or, for a write the disk
refused, an OSError: ``WriteFailed``), so each ``except`` that caught them still does.

``resume_note`` is the one text here that names a command: the status message a sweep file
keeps when a signal stopped it (file contents are a contract: ``rodjit info`` shows it).
"""
from __future__ import annotations

import math
import os
from typing import Mapping

from ..output.estimate import format_size
from ..output.errors import WriteFailed

__all__ = ["TooManyPoints", "BadGridItem", "SweepFileTooLarge", "RunsDirUnusable",
           "ResumeMismatch", "SweepWriteFailed", "DaskMissing", "FormatNotContinued",
           "FileHeldOpen", "resume_note"]


def resume_note(message: str, output) -> str:
    """The status message an interrupted sweep file keeps: ``message`` and the command that
    continues it (as every sweep file written since format 1 says)."""
    return f"{message}; continue with: rodjit sweep --resume -o {output}"


class FileHeldOpen(UserWarning):
    """Another process holds the sweep file open (a reader: h5py in a notebook, a viewer),
    which keeps the sweep from writing to it: the sweep goes on, holds its finished points
    and writes them once the file is let go (waiting for that at its end).  Said under
    ``--quiet`` too (``said_when_quiet``): without it a quiet sweep could wait without a
    word for as long as the reader holds the file."""

    said_when_quiet = True


class TooManyPoints(ValueError):
    """A grid with more points than the limit (``max_points``), refused before it is made.

    Parameters
    ----------
    counts : dict of str to int
        Each swept key's number of values, in the grid's order (``counts``).
    limit : float
        The limit it exceeds (``limit``).

    Attributes
    ----------
    points : int
        The grid's points (the product of the counts).
    axes : str
        The counts as a message shows them: ``"11 (rod.mu) x 3 (floor.beta)"``.
    """

    def __init__(self, counts: Mapping[str, int], limit: float) -> None:
        self.counts = dict(counts)
        self.limit = limit
        self.points = math.prod(self.counts.values())
        self.axes = " x ".join(f"{c:,} ({k})" for k, c in self.counts.items())
        super().__init__(f"{self.stem()} (raise it with max_points=, or sweep fewer values)")

    def stem(self) -> str:
        """The message without its advice: the count and the limit."""
        return (f"the grid has {self.points:,} points ({self.axes}), more than the limit of "
                f"{self.limit:,.0f} points")

    def __reduce__(self):
        return type(self), (self.counts, self.limit)


class BadGridItem(ValueError):
    """A ``KEY=VALUES`` grid item (``parse_grid_option``) that cannot be read.

    Parameters
    ----------
    problem : str
        ``"form"`` (no ``KEY=``), ``"twice"`` (a key given in two items) or ``"none"`` (no
        item at all).
    item : str, optional
        The text of the item (``"form"``).
    key : str, optional
        The key given twice (``"twice"``).
    """

    def __init__(self, problem: str, item: str = "", key: str = "") -> None:
        self.problem, self.item, self.key = problem, item, key
        super().__init__(
            f"a grid item is KEY=VALUES (e.g. rod.mu=0,1,10 or "
            f"floor.beta=linspace(0.01,0.05,3)), got {item!r}" if problem == "form" else
            f"grid key {key} is given twice; list all its values in one item"
            if problem == "twice" else "a sweep needs at least one KEY=VALUES grid item")

    def __reduce__(self):
        return type(self), (self.problem, self.item, self.key)


class SweepFileTooLarge(ValueError):
    """The sweep file would be larger than the size limit (``max_output``).

    Parameters
    ----------
    points : int
        The grid's points (``points``).
    size : float
        The sweep file's estimated size in bytes (``size``).
    limit : float
        The limit in bytes (``limit``).
    """

    def __init__(self, points: int, size: float, limit: float) -> None:
        self.points, self.size, self.limit = points, size, limit
        super().__init__(f"{self.stem()} (raise it with max_output=, or sweep fewer points)")

    def stem(self) -> str:
        """The message without its advice: the points, the size and the limit."""
        return (f"the sweep file would hold {self.points:,} points, about "
                f"{format_size(self.size)}: more than the limit of {format_size(self.limit)}")

    def __reduce__(self):
        return type(self), (self.points, self.size, self.limit)


class RunsDirUnusable(ValueError):
    """The directory for the points' run files (``save_runs``) cannot take them.

    Parameters
    ----------
    path : str or os.PathLike
        The directory as given (``path``, a str).
    problem : str
        ``"not_a_directory"``, ``"not_creatable"`` (its parent cannot be written),
        ``"holds"`` (it holds a run file of this sweep and neither overwriting nor resuming
        was asked for) or ``"holds_output"`` (the sweep file would be inside it, where a
        run file of the same name would replace it).
    clash : str, optional
        The run file it already holds (``"holds"``), the sweep file (``"holds_output"``).
    """

    def __init__(self, path: str | os.PathLike[str], problem: str, clash: str = "") -> None:
        self.path, self.problem, self.clash = str(path), problem, clash
        super().__init__(
            f"save_runs {self.path!r} is not a directory" if problem == "not_a_directory"
            else f"save_runs directory {self.path!r} cannot be created here"
            if problem == "not_creatable" else
            f"save_runs {self.path!r} would hold the sweep file {clash!r}; write the sweep "
            f"file outside the run files' directory" if problem == "holds_output" else
            f"save_runs {self.path!r} already holds {clash!r}; pass overwrite=True to "
            f"replace its run files, or resume=True")

    def __reduce__(self):
        return type(self), (self.path, self.problem, self.clash)


class ResumeMismatch(ValueError):
    """``resume=True`` was given a configuration or a grid other than its sweep file's.

    Parameters
    ----------
    path : str or os.PathLike
        The sweep file (``path``, a str).
    what : str
        ``"configuration"`` or ``"grid"``.
    detail : str
        The keys that differ (configuration), or the file's grid as JSON (grid).
    """

    def __init__(self, path, what: str, detail: str) -> None:
        self.path, self.what, self.detail = str(path), what, detail
        drop = "the changes" if what == "configuration" else "grid="
        super().__init__(f"{self.stem()}; resume=True continues the file's sweep: drop {drop} "
                         f"or start a new sweep")

    def stem(self) -> str:
        """The message without its advice: what differs from the file."""
        return f"the {self.what} differs from the one in {self.path!r} ({self.detail})"

    def __reduce__(self):
        return type(self), (self.path, self.what, self.detail)


class SweepWriteFailed(WriteFailed):
    """The disk refused a write of a sweep that has a sweep file: the file keeps the points
    written (``kept`` of ``total``), and ``resume=True`` runs the others once there is
    space.

    Parameters
    ----------
    stem : str
        What failed and why (``stem``): ``"writing 'x.h5' failed: disk full"``.
    cause : str
        What the disk said (``cause``).
    output : str or os.PathLike
        The sweep file (``output``, a str).
    kept, total : int
        Points the file keeps, points of the sweep.
    """

    def __init__(self, stem: str, cause: str | None, output, kept: int, total: int) -> None:
        self.stem, self.output, self.kept, self.total = stem, str(output), kept, total
        super().__init__(f"{self.kept_text()}; free space, then continue with resume=True "
                         f"(output={self.output!r})", cause)

    def kept_text(self) -> str:
        """The message without its advice: what failed and what the file keeps."""
        return (f"{self.stem}; the sweep stopped: {self.output!r} keeps the points written "
                f"({self.kept} of {self.total})")

    def __reduce__(self):
        return type(self), (self.stem, self.cause, self.output, self.kept, self.total)


class DaskMissing(ValueError):
    """A Dask scheduler was asked for without Dask distributed installed.

    Parameters
    ----------
    scheduler : str
        The scheduler asked for (``scheduler``): ``"local"`` or an address.
    """

    def __init__(self, scheduler: str) -> None:
        self.scheduler = scheduler
        super().__init__(self.worded(f"scheduler = {scheduler!r}"))

    def worded(self, asked: str) -> str:
        """The message, naming what was asked for as ``asked``."""
        return f"{asked} needs Dask distributed; install it with: pip install 'rodjit[dask]'"

    def __reduce__(self):
        return type(self), (self.scheduler,)


class FormatNotContinued(ValueError):
    """``resume=True`` on a sweep file of a format this version does not continue.

    Parameters
    ----------
    path : str or os.PathLike
        The sweep file (``path``, a str).
    version : int
        Its format (``version``).
    current : int or tuple of int
        The formats this version continues.
    """

    def __init__(self, path, version, current: int | tuple[int, ...]) -> None:
        self.path, self.version, self.current = str(path), version, current
        super().__init__(self.worded("resume=True"))

    def worded(self, resume: str) -> str:
        """The message, naming resuming as ``resume``."""
        formats = (self.current,) if isinstance(self.current, int) else tuple(self.current)
        said = (f"format {formats[0]}" if len(formats) == 1 else
                "formats " + ", ".join(map(str, formats[:-1])) + f" and {formats[-1]}")
        return (f"{self.path!r} is a sweep file of format {self.version}, whose bounces and "
                f"summary columns have older meanings; {resume} continues {said} only: "
                f"start a new sweep")

    def __reduce__(self):
        return type(self), (self.path, self.version, self.current)
