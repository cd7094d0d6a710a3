"""Opening rodjit's HDF5 files and telling what they are: read-only opening of a file
that may be being written (SWMR), the kind and format checks, opening for writing, the
liveness of the process that writes a file (``output.writer_id``), and the checks an
output path passes before a run or a sweep writes to it.

Both file kinds (runs, ``output.run_writer``; sweeps, ``sweeps.sweep_file``) use these.
"""
from __future__ import annotations

import datetime
import errno
from contextlib import contextmanager
import os
import re
import stat
from pathlib import Path

import h5py
import numpy as np

from ..config import MissingFile
from .abandoned import abandon, abandoned, quiet_disk_errors
from .cf import LIBVER
from .errors import OutputNotRegular, OutputOtherKind, WriteFailed
from .journal import recover
from .lock import FileBusy, held_here, is_link, is_locked, left_behind
from .writer_id import find_writer, process_tag, stamp_writer, writer_attrs

__all__ = ["NotARunFile", "FileMissing", "FileCutShort", "FileLeftOpen", "FileBusy",
           "OutputExists", "looks_hdf5",
           "OutputNotRegular", "OutputOtherKind", "open_file", "file_kind", "check_kind",
           "open_for_writing", "now", "history_with", "process_tag", "writer_attrs",
           "stamp_writer", "writer_alive", "writer_pid", "is_live", "check_output",
           "WriteFailed", "disk_cause", "truncation", "repair_truncated", "abandon",
           "abandoned", "quiet_disk_errors", "damaged"]


class NotARunFile(ValueError):
    """The path is not a rodjit run file (missing, not HDF5, or another kind of file)."""


class FileMissing(NotARunFile, MissingFile):
    """The path does not exist: a ``FileNotFoundError`` (as ``open`` raises) and, like every
    file rodjit cannot read, a NotARunFile (a ValueError: one line, exit code 2)."""


class FileCutShort(NotARunFile):
    """A file shorter than HDF5 recorded (its disk filled, or a size limit was hit, while it
    was written): its last checkpoint is kept, and resuming continues it.

    Parameters
    ----------
    path : str or os.PathLike
        The file (``path``, a str).
    size, stored : int
        Its bytes, and the bytes HDF5 recorded.
    """

    def __init__(self, path: str | os.PathLike[str], size: int, stored: int) -> None:
        self.path, self.size, self.stored = str(path), size, stored
        super().__init__(f"{self.stem()}: continue it with resume_file({self.path!r}) (or "
                         f"sweep(resume=True, output={self.path!r})) once there is space")

    def stem(self) -> str:
        """The message without its advice."""
        return (f"{self.path!r} is cut short ({self.size} of {self.stored} bytes: its disk "
                f"filled or a size limit was hit while it was written); its last checkpoint "
                f"is kept")

    def __reduce__(self):
        return type(self), (self.path, self.size, self.stored)


class FileLeftOpen(NotARunFile):
    """An HDF5 file whose writer stopped (killed) while it had the file open for writing,
    outside SWMR mode, and which nothing undoes: HDF5 refuses to open it ("already open
    for write"), and what clearing that flag would show is not what was written.  rodjit's
    own files are never left so (run files are written in SWMR mode, sweep files through
    ``output.journal``); a sweep file of an earlier rodjit killed while it wrote is, and
    ``check_output`` lets ``--overwrite`` replace it when its writer lock says a rodjit
    writer died on it (``lock.left_behind``).

    Parameters
    ----------
    path : str or os.PathLike
        The file (``path``, a str).
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = str(path)
        super().__init__(f"{self.path!r} was left open for writing by a process that stopped "
                         f"before closing it (killed while it wrote) and cannot be read; write "
                         f"it again, replacing it (if rodjit wrote it)")

    def __reduce__(self):
        return type(self), (self.path,)


_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _head(path, size: int) -> bytes:
    try:
        with open(path, "rb") as fh:
            return fh.read(size)
    except OSError:
        return b""


def looks_hdf5(path) -> bool:
    """Whether the file at ``path`` starts with HDF5's signature (read without h5py)."""
    return _head(path, 8) == _SIGNATURE


def left_open(path) -> bool:
    """Whether the file at ``path`` is HDF5 with a superblock (version 2 or 3, at the
    start) that still says "open for writing", not in SWMR mode: its writer never closed
    it (``FileLeftOpen``)."""
    head = _head(path, 12)
    return (len(head) == 12 and head[:8] == _SIGNATURE and head[8] in (2, 3)
            and head[11] & 0x01 != 0 and head[11] & 0x04 == 0)


class OutputExists(ValueError):
    """The output file exists and overwriting was not asked for.

    Parameters
    ----------
    path : str or os.PathLike
        The file, kept as the ``path`` attribute (the command line words its own advice
        from it: ``use --overwrite``).
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = str(path)
        super().__init__(f"output file {self.path!r} already exists; pass overwrite=True "
                         f"to replace it")

    def __reduce__(self):
        return type(self), (self.path,)


def open_file(path) -> h5py.File:
    """Open a rodjit file read-only: plainly if it was closed, in SWMR-read mode if a writer
    has it open or was killed before closing it (both leave the SWMR flags set).  A journaled
    write its writer did not finish (a sweep file's, ``output.journal``) is undone first."""
    path = Path(path)
    mode = _mode(path)
    if mode is None:
        raise FileMissing(path)
    if stat.S_ISDIR(mode):
        raise NotARunFile(f"{str(path)!r} is a directory, not a rodjit file")
    if not stat.S_ISREG(mode):
        raise NotARunFile(f"{str(path)!r} is a {_special(mode)}, not a rodjit file")
    if not os.access(path, os.R_OK):
        raise NotARunFile(f"{str(path)!r} is not readable")
    try:
        recover(path)
    except OSError as exc:
        raise NotARunFile(f"{str(path)!r} was being written when its writer stopped, and "
                          f"undoing that write failed: {exc.strerror or exc}") from None
    if not h5py.is_hdf5(path):
        raise NotARunFile(f"{str(path)!r} is not a rodjit file (not an HDF5 file)")
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        if "already open for write" not in str(exc):
            raise _unopenable(path, exc) from None
    try:
        return h5py.File(path, "r", swmr=True)
    except OSError as exc:
        if left_open(path) and (held_here(path) or not is_locked(path)):   # its writer died
            raise FileLeftOpen(path) from None
        raise _unopenable(path, exc) from None


def _mode(path) -> int | None:
    """The ``st_mode`` of what ``path`` names (through symbolic links), None if nothing
    is there; ValueError (one line) for a name the system refuses (too long, a loop of
    links, a directory that cannot be searched)."""
    try:
        return os.stat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            raise ValueError(f"the file name {str(path)[:60]!r}... is too long for the file "
                             f"system ({len(os.fsencode(Path(path).name))} bytes)") from None
        if exc.errno == errno.ELOOP:
            raise ValueError(f"{str(path)!r} is a loop of symbolic links") from None
        raise ValueError(f"cannot look at {str(path)!r}: {exc.strerror}") from None


def _special(mode: int) -> str:
    """What a file that is neither regular nor a directory is, for a message."""
    return ("named pipe (FIFO)" if stat.S_ISFIFO(mode) else "character device"
            if stat.S_ISCHR(mode) else "block device" if stat.S_ISBLK(mode) else "socket"
            if stat.S_ISSOCK(mode) else "special file")


def _unopenable(path, exc) -> NotARunFile:
    """The one-line reason a file does not open."""
    m = re.search(r"truncated file: eof = (\d+).*stored_eof = (\d+)", str(exc))
    if m and int(m.group(2)) > int(m.group(1)):
        return FileCutShort(path, int(m.group(1)), int(m.group(2)))
    return NotARunFile(f"cannot open {str(path)!r}: {' '.join(str(exc).split())}")


@contextmanager
def damaged(path):
    """``with damaged(path):`` reading a rodjit file, whose errors on a damaged or
    incomplete file (a missing object or attribute, unreadable HDF5 structures) become
    one NotARunFile line naming the file; a disk error passes unchanged."""
    try:
        yield
    except NotARunFile:
        raise
    except (KeyError, OSError, RuntimeError, TypeError, IndexError, AttributeError,
            UnicodeError) as exc:
        if disk_cause(exc) is not None:
            raise
        detail = " ".join(str(exc).split()) or type(exc).__name__
        raise NotARunFile(f"{str(path)!r} is damaged or not a complete rodjit file "
                          f"({detail})") from None


def check_kind(f: h5py.File, kind: str, version, path=None) -> None:
    """Raise NotARunFile unless ``f`` is a rodjit ``kind`` file ("run", "sweep") of format
    ``version`` (an int, or the tuple of formats read)."""
    name = str(path if path is not None else f.filename)
    found = f.attrs.get("rodjit_kind")
    if found is None:
        raise NotARunFile(f"{name!r} is not a rodjit file (no 'rodjit_kind' attribute)")
    if found != kind:
        raise NotARunFile(f"{name!r} is a rodjit {found!r} file, not a {kind} file")
    got = int(f.attrs.get("format_version", 0))
    versions = version if isinstance(version, tuple) else (version,)
    if got not in versions:
        wanted = " or ".join(str(v) for v in versions)
        raise NotARunFile(f"{name!r} has {kind}-file format {got}; this rodjit reads format "
                          f"{wanted}")


def file_kind(path) -> str:
    """The ``rodjit_kind`` root attribute of the file at ``path`` ("run", "sweep", ...);
    NotARunFile if it is not a readable rodjit file."""
    with open_file(path) as f:
        kind = f.attrs.get("rodjit_kind")
    if kind is None:
        raise NotARunFile(f"{str(path)!r} is not a rodjit file (no 'rodjit_kind' attribute)")
    return str(kind)


def open_for_writing(path, mode: str) -> h5py.File:
    """``h5py.File(path, mode)`` in the HDF5 1.10 file format (``cf.LIBVER``: the oldest
    with SWMR, readable by HDF5 1.10 and netCDF-C); FileBusy if
    another process holds the file, ValueError (one line) for any other failure."""
    try:
        return h5py.File(path, mode, libver=LIBVER)
    except OSError as exc:
        if "lock" in str(exc):
            raise FileBusy(f"{str(path)!r} is open in another process; close it there and "
                           f"retry") from None
        raise ValueError(f"cannot open {str(path)!r} for writing: {exc}") from None


def now() -> str:
    """The current UTC time as the files record it (ISO 8601, seconds)."""
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def history_with(f: h5py.File, entry: str) -> list[str]:
    """The file's ``history`` attribute with ``entry`` appended, stamped with ``now()``.
    A history that is not a list of lines (one text, a number: an edited file) is kept as
    one line: it is not worth refusing a file for, and continuing never fails on it."""
    old = f.attrs.get("history", [])
    lines = [old] if isinstance(old, (str, bytes)) or np.ndim(old) == 0 else np.ravel(old)
    return [s.decode("utf-8", "replace") if isinstance(s, bytes) else str(s)
            for s in lines] + [f"{now()} {entry}"]


def writer_alive(f: h5py.File, lock: bool = True) -> bool | None:
    """Is the process that last wrote ``f`` still running?  True if a process holds the
    file's writer lock (``output.lock``; skipped with ``lock=False``, for the holder
    itself); otherwise judged from the liveness record in the file (``output.writer_id``:
    also for files of rodjit versions without the lock); None if it ran on another
    machine."""
    if lock and is_locked(f.filename):
        return True
    return find_writer(f.attrs)[0]


def writer_pid(f: h5py.File) -> int | None:
    """The process id of ``f``'s writer if it is alive on this machine (for the messages
    that ask to stop it; the file itself does not record it)."""
    return find_writer(f.attrs)[1]


def is_live(path, lock: bool = True) -> bool:
    """True if ``path`` is a rodjit file (a run or a sweep) whose writer is still running
    on this host (``lock=False``: the caller holds the writer lock; judge by the file)."""
    try:
        with open_file(path) as f:
            return f.attrs.get("status") == "running" and writer_alive(f, lock) is True
    except (ValueError, OSError):
        return lock and is_locked(path)


def check_output(path, overwrite: bool, kind: str | None = None, held: bool = False) -> Path:
    """Raise ValueError (one line) unless ``path`` can be created or replaced: its directory
    exists and is writable, it is not the file of a live writer, and (given ``kind``) an
    existing file is replaced only if it is a rodjit file of that kind, or empty, or one a
    rodjit writer died on before it could be read (``FileLeftOpen``): never a
    configuration, an image or anyone else's data.  ``held``: the caller holds the writer
    lock of ``path`` (``output.lock``)."""
    path = Path(path)
    real = Path(os.path.realpath(path)) if is_link(path) else path   # written through
    parent = real.parent if str(real.parent) else Path(".")
    parent_mode = _mode(parent)
    if parent_mode is None:
        raise ValueError(f"output directory {str(parent)!r} does not exist")
    if not stat.S_ISDIR(parent_mode):
        raise ValueError(f"output directory {str(parent)!r} is not a directory")
    if len(os.fsencode(path.name)) > _name_max(parent):
        raise ValueError(f"the output file name {path.name[:40]!r}... is too long for the "
                         f"file system ({len(os.fsencode(path.name))} bytes; at most "
                         f"{_name_max(parent)})")
    mode = _mode(path)
    if mode is not None and stat.S_ISDIR(mode):
        raise ValueError(f"output {str(path)!r} is a directory, not a file")
    if mode is not None and not stat.S_ISREG(mode):
        raise OutputNotRegular(path, _special(mode))
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"output directory {str(parent)!r} is not writable")
    if mode is not None:
        if not overwrite:
            raise OutputExists(path)
        if is_live(path, lock=not held):
            raise FileBusy(f"output file {str(path)!r} is being written by a running "
                           f"rodjit process; stop it before replacing the file")
        if kind is not None and path.stat().st_size > 0:
            found: str | None
            try:
                found = file_kind(path)
            except FileLeftOpen:        # replaced only if a rodjit writer died on it
                found = kind if left_behind(path) else None
            except (ValueError, OSError):
                found = None
            if found != kind:
                raise OutputOtherKind(path, found, kind)
    return path


def _name_max(directory) -> int:
    """The longest file name (bytes) the file system of ``directory`` takes."""
    try:
        return os.pathconf(directory, "PC_NAME_MAX")
    except (OSError, ValueError):
        return 255


# ---- the disk failing a writer --------------------------------------------------------------
_CAUSES = {errno.ENOSPC: "no space left on the device",
           errno.EFBIG: "the file size limit was reached (file too large)",
           errno.EDQUOT: "the disk quota is exceeded",
           errno.EIO: "an input/output error of the device"}


def disk_cause(exc: BaseException | None) -> str | None:
    """What the disk said, if ``exc`` (or its cause) is a refused write: ENOSPC, EFBIG,
    EDQUOT or EIO, as raised by Python or reported inside an HDF5 message."""
    seen = 0
    while exc is not None and seen < 5:
        if isinstance(exc, WriteFailed):
            return exc.cause or str(exc)
        code = getattr(exc, "errno", None)
        if code in _CAUSES:
            return _CAUSES[code]
        m = re.search(r"errno = (\d+)", str(exc))
        if m and int(m.group(1)) in _CAUSES:
            return _CAUSES[int(m.group(1))]
        exc, seen = exc.__cause__ or exc.__context__, seen + 1
    return None


def truncation(path) -> tuple[int, int] | None:
    """(bytes on disk, bytes the superblock records) of an HDF5 file cut short because a
    write failed at the end of the file (the disk filled); None if it is not."""
    try:
        h5py.File(path, "r").close()
        return None
    except OSError as exc:
        m = re.search(r"truncated file: eof = (\d+).*stored_eof = (\d+)", str(exc))
        if m and int(m.group(2)) > int(m.group(1)):
            return int(m.group(1)), int(m.group(2))
        if "already open for write" in str(exc):
            try:
                h5py.File(path, "r", swmr=True).close()
                return None
            except OSError as exc2:
                m = re.search(r"truncated file: eof = (\d+).*stored_eof = (\d+)", str(exc2))
                if m and int(m.group(2)) > int(m.group(1)):
                    return int(m.group(1)), int(m.group(2))
    return None


def repair_truncated(path) -> tuple[int, int] | None:
    """Give a file cut short by a failed write its recorded length back (zeros at the end,
    which should lie beyond every checkpointed row: ``run_reader.check_not_lost`` makes
    sure), so it opens and its checkpoint can be recovered; (bytes that were on disk,
    bytes now) if it was cut short, else None.  The caller holds the writer lock."""
    cut = truncation(path)
    if cut is None:
        return None
    try:
        os.truncate(path, cut[1])
    except OSError as exc:
        raise WriteFailed(f"cannot repair {str(path)!r} ({cut[0]} of its {cut[1]} bytes are "
                          f"on disk): {disk_cause(exc) or exc.strerror}") from None
    return cut
