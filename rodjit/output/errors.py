"""The typed errors of a file's checks before it is written: each carries the fields a
message needs (the path, the count, the limit), and its own message speaks Python
(``max_steps=``, ``max_output=``, ``overwrite=True``).  The command line words them in its
options (``rodjit/cli/wording.py``); every one is a ValueError, so each ``except
ValueError`` that caught them still does.
"""
from __future__ import annotations

import os
from typing import Any

__all__ = ["TooManySteps", "FileTooLarge", "OutputNotRegular", "OutputOtherKind", "WriteFailed"]


class TooManySteps(ValueError):
    """A fixed time.dt that needs more steps than the limit (``max_steps``).

    Parameters
    ----------
    dt, t_end : float
        The fixed step and the end time (``dt``, ``t_end``).
    steps : float
        The steps it needs (``steps``).
    limit : float
        The limit it exceeds (``limit``).
    where : str, optional
        What the configuration is, as a message's prefix (``"grid point 3 (rod.mu = 1)"``);
        empty for a run.
    """

    def __init__(self, dt: float, t_end: float, steps: float, limit: float,
                 where: str = "") -> None:
        self.dt, self.t_end, self.steps, self.limit, self.where = dt, t_end, steps, limit, where
        super().__init__(f"{self.stem()} (raise it with max_steps=)")

    def stem(self) -> str:
        """The message without its advice: the step, the steps and the limit."""
        return ((f"{self.where}: " if self.where else "")
                + f"time.dt = {self.dt!r} needs {self.steps:.3g} steps to reach time.t_end = "
                  f"{self.t_end!r}, more than the limit of {self.limit:.3g}")

    def at(self, where: str) -> TooManySteps:
        """The same refusal for the configuration ``where`` names."""
        return TooManySteps(self.dt, self.t_end, self.steps, self.limit, where)

    def __reduce__(self):
        return type(self), (self.dt, self.t_end, self.steps, self.limit, self.where)


class FileTooLarge(ValueError):
    """A file whose estimate is above the size limit (``max_output``).

    Parameters
    ----------
    what : str
        The file, as a message names it (``"the run"``).
    estimate : str
        What it would write (``Estimate.describe()``).
    limit : float
        The limit in bytes (``limit``).
    limit_text : str
        The limit as a message shows it (``"10 GiB"``, ``format_size``).
    """

    def __init__(self, what: str, estimate: str, limit: float, limit_text: str) -> None:
        self.what, self.estimate, self.limit, self.limit_text = what, estimate, limit, limit_text
        super().__init__(self.worded("max_output="))

    def worded(self, option: str) -> str:
        """The message, with ``option`` as the way to raise the limit."""
        return (f"{self.what} would write {self.estimate}: more than the limit of "
                f"{self.limit_text} (raise it with {option}, or write less: "
                f"output.snapshot_interval, output.diagnostics_interval, time.t_end)")

    def __reduce__(self):
        return type(self), (self.what, self.estimate, self.limit, self.limit_text)


class OutputNotRegular(ValueError):
    """The output path names something other than a regular file or a directory (a FIFO,
    a device, a socket), which no overwriting replaces.

    Parameters
    ----------
    path : str or os.PathLike
        The output (``path``, a str).
    special : str
        What it is (``"named pipe (FIFO)"``).
    """

    def __init__(self, path: str | os.PathLike[str], special: str) -> None:
        self.path, self.special = str(path), special
        super().__init__(f"{self.stem()} (with or without overwrite=True)")

    def stem(self) -> str:
        """The message without its last words."""
        return (f"output {self.path!r} is a {self.special}, not a regular file: rodjit "
                f"writes only regular files")

    def __reduce__(self):
        return type(self), (self.path, self.special)


class OutputOtherKind(ValueError):
    """The output file exists and is not a rodjit file of the kind to be written, which
    overwriting never replaces.

    Parameters
    ----------
    path : str or os.PathLike
        The output (``path``, a str).
    found : str or None
        The kind of rodjit file it is (``"run"``), None if it is not a rodjit file.
    kind : str
        The kind to be written (``"sweep"``).
    """

    def __init__(self, path: str | os.PathLike[str], found: str | None, kind: str) -> None:
        self.path, self.found, self.kind = str(path), found, kind
        super().__init__(self.worded("overwrite=True"))

    def worded(self, option: str) -> str:
        """The message, naming overwriting as ``option``."""
        what = f"a rodjit {self.found} file" if self.found else "not a rodjit file"
        return (f"output file {self.path!r} is {what}; {option} replaces only rodjit "
                f"{self.kind} files: choose another output path")

    def __reduce__(self):
        return type(self), (self.path, self.found, self.kind)


class WriteFailed(OSError):
    """The disk refused a write (full, a size limit or quota, an I/O error): the file keeps
    its last checkpoint and ``rodjit run --resume`` continues it once there is space.
    ``cause``: what the disk said, if the message says more; ``table``, set only where a
    sweep stopped on the refusal: its ``SweepTable`` (a floor above this one)."""

    cause: str | None = None
    table: Any

    def __init__(self, message: str, cause: str | None = None):
        super().__init__(message)
        self.cause = cause
