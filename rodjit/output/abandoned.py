"""Files the disk failed (full, a size limit): their h5py objects kept alive and never
closed, and h5py's reports about releasing them silenced.

Apart from ``h5files`` (which re-exports these) so that a process can set this up and ask
it without importing h5py: the command line before any verb runs, and a sweep's worker,
which opens files only to save its points' runs.
"""
from __future__ import annotations

import re
import sys

__all__ = ["abandon", "abandoned", "quiet_disk_errors"]

_DISK_ERRNO = re.compile(r"errno = (5|27|28|122)\b")


def quiet_disk_errors() -> None:
    """Silence the errors h5py reports while releasing the handles of a file the disk
    refused (full, a size limit): they cannot be acted on, and the one-line error of the
    write that failed says what happened (through ``sys.unraisablehook``, and
    ``sys.excepthook`` for the tracebacks its compiled deallocators print)."""
    def unraisable(u):
        if not _DISK_ERRNO.search(str(u.exc_value)):
            sys.__unraisablehook__(u)

    def excepthook(kind, value, tb):
        if not (isinstance(value, RuntimeError) and _DISK_ERRNO.search(str(value))):
            sys.__excepthook__(kind, value, tb)

    sys.unraisablehook = unraisable
    sys.excepthook = excepthook


# h5py objects of files the disk failed.  HDF5 cannot close a file it can no longer
# write, and trying (h5py's deallocators do, at any garbage collection or at exit) prints
# tracebacks or crashes the process: they are kept here, never released, and a process
# that holds any ends by os._exit (the command line, a sweep's workers).
_ABANDONED: list = []


def abandon(*objects) -> None:
    """Keep ``objects`` (h5py files, datasets, writers, a traceback with the frames that
    hold them) alive for the rest of the process: never closed, flushed or freed."""
    _ABANDONED.extend(o for o in objects if o is not None)


def abandoned() -> bool:
    """Whether this process holds files the disk failed (``abandon``): it must end by
    ``os._exit``, without the interpreter's shutdown."""
    return bool(_ABANDONED)
