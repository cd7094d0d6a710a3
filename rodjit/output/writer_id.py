"""Who writes a file, recorded so that this machine can tell whether the writer still runs
and a stranger holding a copy of the file learns neither its host name nor its process id.

A writing session stamps three root attributes (``writer_attrs``):

- ``writer_salt``: 32 random hex digits, new for every session;
- ``writer_machine``: SHA-256 of the salt and the machine key (``/etc/machine-id``, a
  random 128-bit id stable across reboots, with the host name; the host name alone where
  there is no machine id);
- ``writer_process``: SHA-256 of the salt, the machine key, the boot id and the process
  id with its start time (so a reused process id is not mistaken for the writer).

A process on the same machine recomputes ``writer_machine`` with the file's salt; if it
matches, it hashes the processes running now (``/proc``; without it, every possible
process id) and finds the writer among them or not.  Elsewhere it cannot tell (None).
Files of rodjit versions before this record carry ``writer_host``, ``writer_pid`` and
``writer_tag`` instead; they are still judged by those (``find_writer``), and a new
session on such a file replaces them (``stamp_writer``).
"""
from __future__ import annotations

import hashlib
import os
import secrets
import socket

__all__ = ["writer_attrs", "stamp_writer", "find_writer", "process_tag", "WRITER_ATTRS",
           "LEGACY_ATTRS"]

WRITER_ATTRS = ("writer_salt", "writer_machine", "writer_process")
LEGACY_ATTRS = ("writer_host", "writer_pid", "writer_tag")
_PID_MAX_SCAN = 100_000     # process ids tried where /proc cannot list the running ones


def _read(path: str) -> str:
    try:
        with open(path) as fh:
            return fh.read().strip()
    except OSError:
        return ""


def process_tag(pid: int) -> str:
    """Boot id and start time of process ``pid`` (Linux), so a reused pid is not mistaken
    for the writer; "" where /proc does not tell."""
    return _tag(_read("/proc/sys/kernel/random/boot_id"), pid)


def _tag(boot: str, pid: int) -> str:
    stat = _read(f"/proc/{pid}/stat")
    try:
        start = stat.rsplit(")", 1)[1].split()[19]    # field 22: start time
    except IndexError:
        return ""
    return f"{boot}:{start}" if boot else ""


def _machine_key() -> str:
    machine = _read("/etc/machine-id") or _read("/var/lib/dbus/machine-id")
    return f"{machine}|{socket.gethostname()}"


def _digest(*parts: str) -> str:
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


def _process_hash(salt: str, key: str, pid: int, tag: str) -> str:
    return _digest("rodjit writer process", salt, key, str(pid), tag)


def writer_attrs(pid: int | None = None) -> dict:
    """The liveness record of process ``pid`` (default: this one), with a new salt."""
    pid = os.getpid() if pid is None else int(pid)
    salt = secrets.token_hex(16)
    key = _machine_key()
    return {"writer_salt": salt,
            "writer_machine": _digest("rodjit writer machine", salt, key),
            "writer_process": _process_hash(salt, key, pid, process_tag(pid))}


def stamp_writer(attrs) -> None:
    """Record this process as the writer in the attributes ``attrs`` (an h5py
    AttributeManager), dropping the host name and process id older versions stored."""
    for name in LEGACY_ATTRS:
        if name in attrs:
            del attrs[name]
    for name, value in writer_attrs().items():
        attrs[name] = value


def _candidates():
    """Process ids to try: the running ones (/proc), or every possible one."""
    try:
        return [int(name) for name in os.listdir("/proc") if name.isdigit()]
    except OSError:
        return range(1, _PID_MAX_SCAN)


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    return True


def find_writer(attrs) -> tuple[bool | None, int | None]:
    """(alive, pid) of the writer the root attributes ``attrs`` record: alive True with its
    process id on this machine, False if it runs no more (or is this process), None if it
    ran on another machine (or the file records no writer we can judge)."""
    if "writer_process" in attrs:
        salt = str(attrs.get("writer_salt", ""))
        key = _machine_key()
        if str(attrs.get("writer_machine", "")) != _digest("rodjit writer machine", salt, key):
            return None, None
        target = str(attrs["writer_process"])
        boot = _read("/proc/sys/kernel/random/boot_id")
        for pid in _candidates():
            if _process_hash(salt, key, pid, _tag(boot, pid)) == target:
                if pid == os.getpid() or not _running(pid):
                    return False, None
                return True, pid
        return False, None
    if "writer_pid" not in attrs:
        return None, None
    return _find_legacy(attrs)


def _find_legacy(attrs) -> tuple[bool | None, int | None]:
    """``find_writer`` for a file that records host, pid and start tag in the clear."""
    if attrs.get("writer_host") != socket.gethostname():
        return None, None
    pid = int(attrs.get("writer_pid", -1))
    if pid <= 0 or pid == os.getpid() or not _running(pid):
        return False, None
    tag = str(attrs.get("writer_tag", ""))
    if tag and process_tag(pid) not in ("", tag):
        return False, None
    return True, pid
