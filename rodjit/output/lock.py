"""One writer per file: an advisory lock of rodjit's own, held for a whole write.

HDF5's own file lock is dropped once a file is in SWMR mode, and ``--overwrite`` truncates
or replaces the file, so neither can keep a second writer out.  rodjit therefore takes
``fcntl.flock`` on a lock file beside the output, ``.NAME.lock`` in the same directory
(``run.h5`` -> ``.run.h5.lock``), before it checks, creates, replaces, recovers or reopens
the output, and holds it until the file is closed.  A second writer (run, resume, sweep)
finds the lock taken and is refused with FileBusy before it touches anything.

The lock file holds the writer's process id.  The writer removes it before it lets go
(a process that opened it meanwhile finds, once it has the lock, that the path no longer
names its file, and starts over), except when it records why a write failed
(``note_failure``, for ``info``).  The kernel drops the lock when the process dies, whatever
the way (SIGKILL included), so a lock file left behind never blocks anyone; it says that
a writer died holding it (``left_behind``).
"""
from __future__ import annotations

import fcntl
import os
import time
from pathlib import Path

__all__ = ["FileBusy", "lock_path", "WriterLock", "is_locked", "held_here", "left_behind",
           "note_failure", "failure_note"]

# the lock files this process holds (``held_here``) -> the process id a writer that died
# left in it, found when it was taken ("" if none: ``left_behind``)
_HELD: dict[Path, str] = {}


class FileBusy(ValueError):
    """Another process holds the file (a live writer, or a reader blocking a write)."""


def lock_path(path) -> Path:
    """The lock file of the output ``path``: ``.NAME.lock`` beside it (beside the file a
    symbolic link names: the link and its target are one output)."""
    path = Path(path)
    if is_link(path):
        path = Path(os.path.realpath(path))
    return path.with_name(f".{path.name}.lock")


def is_link(path) -> bool:
    """Whether ``path`` is a symbolic link (False for a name the system refuses, too long
    or under a file: the checks of the output path say why)."""
    try:
        return os.path.islink(path)
    except (OSError, ValueError):
        return False


class WriterLock:
    """``with WriterLock(path):`` holds the writer lock of ``path`` (FileBusy if another
    process holds it).  Not re-entrant across open file descriptions: one per write."""

    def __init__(self, path):
        self.path = Path(path)
        self.fd: int | None = None

    def acquire(self) -> "WriterLock":
        lp = lock_path(self.path)
        while True:
            try:
                fd = os.open(lp, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            except OSError as exc:
                raise ValueError(f"cannot create the lock file {str(lp)!r} beside the output: "
                                 f"{exc.strerror}") from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _holder(fd, wait=1.0)
                os.close(fd)
                raise FileBusy(f"{str(self.path)!r} is being written by "
                               f"{f'process {holder}' if holder else 'another process'} (a "
                               f"running rodjit); wait for it to finish or stop it") from None
            except OSError:        # a file system without flock: fall back on HDF5's checks
                break
            try:                   # still the lock file, not one its holder just removed?
                if os.fstat(fd).st_ino == os.stat(lp).st_ino:
                    break
            except FileNotFoundError:
                pass
            os.close(fd)
        left = _holder(fd)         # a writer that died holding it (the lock is ours now)
        try:                       # who holds it, for the message a second writer gets
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        except OSError:
            pass
        self.fd = fd
        _HELD[lp] = left
        return self

    def release(self) -> None:
        """Remove the lock file (unless it records a failure, ``note_failure``), then drop
        the lock: a process that opened the file meanwhile sees it gone and starts over."""
        if self.fd is None:
            return
        _HELD.pop(lock_path(self.path), None)
        try:
            if failure_note(self.path) is None:
                lp = lock_path(self.path)
                if os.fstat(self.fd).st_ino == os.stat(lp).st_ino:
                    lp.unlink()
        except OSError:
            pass
        os.close(self.fd)          # closing the description drops the lock
        self.fd = None

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()


def _holder(fd: int, wait: float = 0.0) -> str:
    """The process id the lock file's holder wrote into it ("" if none).

    A holder writes its id just after it takes the lock, so a second writer that finds the
    lock taken waits up to ``wait`` seconds for the id to appear: without it, two writers
    started together were told "another process" or "process N" by chance."""
    deadline = time.monotonic() + wait
    while True:
        try:
            text = os.pread(fd, 32, 0).decode().strip()
        except (OSError, UnicodeDecodeError):
            return ""
        if text.isdigit() or time.monotonic() >= deadline:
            return text if text.isdigit() else ""
        time.sleep(0.01)


def is_locked(path) -> bool:
    """True if some process (this one included, through another descriptor) holds the
    writer lock of ``path``."""
    lp = lock_path(path)
    try:
        fd = os.open(lp, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        return False
    except BlockingIOError:
        return True
    except OSError:
        return False
    finally:
        os.close(fd)


def held_here(path) -> bool:
    """True if this process holds the writer lock of ``path`` (a ``WriterLock``)."""
    return lock_path(path) in _HELD


def left_behind(path) -> bool:
    """True if a rodjit writer of ``path`` died holding its lock: the lock file, which a
    writer removes when it lets go, names a process (found so when this process took the
    lock, or now, with no process holding it)."""
    lp = lock_path(path)
    if lp in _HELD:
        return bool(_HELD[lp])
    if is_locked(path):
        return False
    try:
        fd = os.open(lp, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return False
    try:
        return bool(_holder(fd))
    finally:
        os.close(fd)


def note_failure(path, message: str) -> None:
    """Record in the lock file why the writer of ``path`` stopped when the output itself can
    no longer be written (its disk full): ``info`` reports it instead of a killed writer.
    The next writer's lock replaces the note."""
    try:
        with open(lock_path(path), "r+") as fh:
            pid = fh.readline().strip()
            fh.seek(0)
            fh.truncate()
            fh.write(f"{pid}\nfailed: {' '.join(message.split())}\n")
    except OSError:
        pass


def failure_note(path) -> str | None:
    """The failure ``note_failure`` recorded for ``path``, if any."""
    try:
        with open(lock_path(path)) as fh:
            lines = fh.read(4096).splitlines()
    except (OSError, UnicodeDecodeError):
        return None
    note = next((ln for ln in lines if ln.startswith("failed: ")), None)
    return note[len("failed: "):] if note else None
