"""Journaled writes of the sweep file (``rodjit.output.journal``): a writer killed at any of
the disk writes of a batch, of reopening or of finishing, or while it copies a page into
the journal, leaves a file that the next reader puts back exactly as it was before that
write, byte for byte; a write the disk refuses half-way is rolled back by the writer
itself; a file being created appears whole or not at all.

Each kill is a SIGKILL in a forked child, at the k-th write it makes, for every k."""
from __future__ import annotations

import os
import resource
import signal

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.output import journal
from rodjit.output.h5files import WriteFailed, open_file
from rodjit.records.bounces import empty_bounces
from rodjit.sweeps import sweep_file
from rodjit.sweeps.batch import BatchResult
from rodjit.sweeps.grid import Grid
from rodjit.sweeps.point import SUMMARY_COLUMNS, empty_columns

GRID = Grid.from_spec({"rod.mu": [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]})
ATTRS = {"save_runs": "", "scheduler": "inline", "jobs": 1}


def batch(points, rows: int = 3) -> BatchResult:
    """Made-up results of ``points``: every summary column set, ``rows`` bounce rows each
    (the counts and message as a completed point's)."""
    idx = np.asarray(points, np.int64)
    values = empty_columns(idx.size)
    for name, (kind, _) in SUMMARY_COLUMNS.items():
        values[name][:] = ("completed" if name == "status" else f"text {name}"
                           if kind == "str" else idx + 0.5 if kind == "float" else idx)
    # what a completed point with ``rows`` bounces carries (a sweep file proves its rows)
    values["message"][:] = ""
    values["n_bounces"][:] = values["n_complete_bounces"][:] = rows
    bounces = {name: np.resize(np.arange(idx.size * rows) % 2 if col.dtype == bool
                               else np.arange(idx.size * rows), idx.size * rows)
               .astype(col.dtype) for name, col in empty_bounces().items()}
    return BatchResult(idx, values, bounces, np.full(idx.size, rows, np.int64))


@pytest.fixture
def sweep(tmp_path):
    """A sweep file with its first two points written."""
    path = tmp_path / "s.h5"
    sweep_file.create(path, rodjit.Config(), GRID, command="test", attrs=ATTRS)
    sweep_file.write_batch(path, batch([0, 1]))
    return path


WRITES = {"a batch": lambda path: sweep_file.write_batch(path, batch([2, 4, 5], rows=700)),
          "reopening": lambda path: sweep_file.reopen(path, history="resumed by: test"),
          "finishing": lambda path: sweep_file.finish(path, "completed", "done " * 50)}


def _writes(write, path) -> tuple[int, int]:
    """How many times ``write`` writes to the file (``Journaled.write`` and ``truncate``)
    and how many pages (runs of pages) it copies into the journal; done on a copy."""
    copy = path.with_name("count.h5")
    copy.write_bytes(path.read_bytes())
    calls, copies = [], []
    original = journal.Journaled.write, journal.Journaled.truncate, journal._write_all

    def counted(method, into):
        def wrapper(*args):
            into.append(1)
            return method(*args)
        return wrapper

    journal.Journaled.write, journal.Journaled.truncate = (counted(m, calls)
                                                           for m in original[:2])
    journal._write_all = counted(original[2], copies)
    try:
        write(copy)
    finally:
        journal.Journaled.write, journal.Journaled.truncate, journal._write_all = original
    return len(calls), len(copies) - 1          # the journal's header is no copy


def _killed_at(k: int, write, path, where: str) -> None:
    """Run ``write(path)`` in a forked child that SIGKILLs itself at its k-th write to the
    file (or cut of its length), before it (``"before"``) or after it (``"after"``), or
    half-way through its k-th copy of old pages into the journal (``"journal"``)."""
    def body():
        seen, copies = [0], [0]
        methods, write_journal = (journal.Journaled.write,
                                  journal.Journaled.truncate), journal._write_all

        def die():
            os.kill(os.getpid(), signal.SIGKILL)

        def dying(method):
            def wrapper(self, *args):
                seen[0] += 1
                if seen[0] == k and where == "before":
                    die()
                out = method(self, *args)
                if seen[0] == k and where == "after":
                    die()
                return out
            return wrapper

        def half(fd, data):
            copies[0] += 1
            if copies[0] == k + 1 and where == "journal":     # (the first: the header)
                os.write(fd, bytes(memoryview(data)[:len(data) // 2]))
                die()
            write_journal(fd, data)

        journal.Journaled.write, journal.Journaled.truncate = map(dying, methods)
        journal._write_all = half
        write(path)
        return 3                                    # the kill did not come

    assert _in_child(body) == -signal.SIGKILL


def _in_child(body) -> int:
    """Run ``body()`` in a forked child; its exit code (``body`` returns it), or minus the
    signal that killed it."""
    pid = os.fork()
    if pid == 0:
        code = 9
        try:
            code = body()
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status)


@pytest.mark.parametrize("what", list(WRITES))
def test_a_writer_killed_at_any_of_its_disk_writes_leaves_the_file_as_before(sweep, what):
    write = WRITES[what]
    before = sweep.read_bytes()
    n, copies = _writes(write, sweep)
    assert n >= 3 and copies >= 1
    for where, last in (("before", n), ("after", n), ("journal", copies)):
        for k in range(1, last + 1):
            _killed_at(k, write, sweep, where)
            assert journal.journal_path(sweep).exists()
            open_file(sweep).close()                # a reader puts the file back first
            assert not journal.journal_path(sweep).exists()
            assert sweep.read_bytes() == before, (k, where)
    table = rodjit.load_sweep(sweep)
    assert list(table["status"]) == ["completed"] * 2 + ["pending"] * 4
    write(sweep)                                    # and the write then goes through
    assert rodjit.load_sweep(sweep).status == ("completed" if what == "finishing"
                                               else "running")


@pytest.mark.parametrize("what", list(WRITES))
def test_a_write_the_disk_refuses_half_way_is_rolled_back(sweep, what):
    """A file-size limit (RLIMIT_FSIZE) at every level between the file's size before and
    after the write: the write fails (WriteFailed naming the cause) and is rolled back by
    the writer, leaving the file as it was and no journal; or it fits."""
    write = WRITES[what]
    before = sweep.read_bytes()
    copy = sweep.with_name("after.h5")
    copy.write_bytes(before)
    write(copy)
    after = copy.stat().st_size

    def limited(limit):
        def body():
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
            try:
                write(sweep)
            except WriteFailed as exc:
                return 0 if "the file size limit was reached" in str(exc) else 4
            return 6
        return body

    codes = []
    for limit in np.linspace(len(before), after + journal.PAGE, 9).astype(int):
        codes.append(_in_child(limited(int(limit))))
        assert codes[-1] in (0, 6), codes
        if codes[-1] == 0:
            assert sweep.read_bytes() == before, limit
            assert not journal.journal_path(sweep).exists()
        else:
            sweep.write_bytes(before)
    assert codes[0] == 0 and codes[-1] == 6, codes


def test_a_file_killed_while_it_is_created_is_not_there_or_is_the_old_one(tmp_path):
    """A new file appears under its name whole: killed at any attribute written while it
    is created, the name holds nothing (a new sweep) or the file it was to replace (an
    overwrite)."""
    path = tmp_path / "s.h5"

    def create():
        sweep_file.create(path, rodjit.Config(), GRID, command="test", attrs=ATTRS)

    original = h5py.AttributeManager.__setitem__
    calls = []
    h5py.AttributeManager.__setitem__ = lambda self, *a: (calls.append(1), original(self, *a))
    try:
        create()
    finally:
        h5py.AttributeManager.__setitem__ = original
    path.unlink()
    for k in range(1, len(calls) + 1, 7):
        for existing in (False, True):
            if existing:
                create()
                sweep_file.write_batch(path, batch([3]))
            before = path.read_bytes() if existing else None

            def body(k=k):
                def dying(self, *a, n=[0]):
                    n[0] += 1
                    if n[0] == k:
                        os.kill(os.getpid(), signal.SIGKILL)
                    return original(self, *a)
                h5py.AttributeManager.__setitem__ = dying
                create()
                return 3
            assert _in_child(body) == -signal.SIGKILL
            if existing:
                assert path.read_bytes() == before
                assert rodjit.load_sweep(path).counts["completed"] == 1
            else:
                assert not path.exists()
            path.unlink(missing_ok=True)


def test_the_journal_copies_the_pages_a_write_changes_not_the_chunks_it_rewrites(tmp_path):
    """HDF5 writes whole chunks back for a few rows: a batch of 50 points into a file of
    10⁴ rewrites every summary column's chunk (80 KB each), the journal keeps only the pages
    that change, and records a page of zeros without its bytes."""
    path = tmp_path / "s.h5"
    sweep_file.create(path, rodjit.Config(), Grid.from_spec({"rod.mu": list(range(10_000))}),
                      command="test", attrs=ATTRS)
    sweep_file.write_batch(path, batch(range(50)))
    written, kept = [], []
    original = journal.Journaled.write, journal.Journaled.end

    def write(self, data):
        written.append(len(memoryview(data).cast("B")))
        return original[0](self, data)

    def end(self, ok):
        kept.append(self.jpath.stat().st_size)
        return original[1](self, ok)

    journal.Journaled.write, journal.Journaled.end = write, end
    try:
        sweep_file.write_batch(path, batch(range(50, 100), rows=2000))
    finally:
        journal.Journaled.write, journal.Journaled.end = original
    assert sum(written) > 2_000_000
    assert kept[0] < sum(written) / 20, (kept, sum(written))
    assert list(rodjit.load_sweep(path)["status"][:101]) == ["completed"] * 100 + ["pending"]
