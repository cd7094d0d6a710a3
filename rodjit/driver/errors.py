"""The typed errors of a run that streams to a file, which the command line words in its
options (``rodjit/cli/wording.py``); their own messages speak Python (``resume_file``).

``resume_command`` is the one text here that names a command: the status message a run
file keeps when a signal stopped it (file contents are a contract: ``rodjit info`` shows
it).
"""
from __future__ import annotations

import os

from ..output.h5files import WriteFailed

__all__ = ["RunWriteFailed", "resume_command"]


def resume_command(message: str, path) -> str:
    """The status message an interrupted run file keeps: ``message`` and the command that
    continues it (as every run file has said)."""
    return f"{message}; continue with: rodjit run --resume {path}"


class RunWriteFailed(WriteFailed):
    """The disk refused a write of a run file: the file keeps its last checkpoint (at
    ``t``), and ``resume_file`` continues it once there is space.

    Parameters
    ----------
    path : str or os.PathLike
        The run file (``path``, a str).
    cause : str
        What the disk said (``cause``).
    t : float
        The simulated time of the last checkpoint (``t``).
    """

    def __init__(self, path: str | os.PathLike[str], cause: str, t: float) -> None:
        self.path, self.t = str(path), t
        super().__init__(f"{self.stem(cause)}; free space, then continue with "
                         f"resume_file({self.path!r})", cause)

    def stem(self, cause: str | None = None) -> str:
        """The message without its advice: what failed and what the file keeps."""
        return (f"writing {self.path!r} failed: {self.cause if cause is None else cause}; "
                f"the file keeps its last checkpoint (t = {self.t:.9g})")

    def __reduce__(self):
        return type(self), (self.path, self.cause, self.t)
