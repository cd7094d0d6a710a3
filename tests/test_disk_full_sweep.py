"""Sweeps on a disk that refuses writes: a file-size limit (RLIMIT_FSIZE, real subprocesses)
at several fill levels of the sweep file, run files of ``--save-runs`` past the limit, and
a write that fails despite the space reserved for it.  Every time: exit 1, one line naming
the cause, no Traceback from the parent or the workers, the sweep file absent (its
creation was cut) or readable by ``info`` with every point written before, no run file
that is neither complete nor resumable, and ``sweep --resume`` with space finishing the
sweep with the results of an uncut one.  The fill levels the timing of batches decides
are checked in-process with the k-th write refused half-way; and a resume needs no more
space than the points it writes take."""
from __future__ import annotations

import errno
import shutil

import pytest

import rodjit
from conftest import one_line, rodjit_cli
from rodjit.output.h5files import WriteFailed
from rodjit.output import journal
from rodjit.output.lock import lock_path
from rodjit.output.summary import summarize
from rodjit.reports import info
from rodjit.sweeps import sweep_file
from test_sweep_driver import TIMINGS, _interrupt_after, same_values

ARGS = ["--grid", "rod.mu=5,10", "--grid", "floor.beta=0.01,0.05", "--set", "time.t_end=0.1",
        "-q"]
INLINE = [*ARGS, "--scheduler", "inline"]
N = 4


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uncut sweep, and the sizes of its file: complete, and its layout alone."""
    d = tmp_path_factory.mktemp("ref")
    r = rodjit_cli("sweep", *INLINE, "-o", d / "ref.h5")
    assert r.returncode == 0, r.stderr
    table = rodjit.load_sweep(d / "ref.h5")
    sweep_file.create(d / "layout.h5", table.base, table.grid, command="rodjit sweep " +
                      " ".join(INLINE), attrs={"save_runs": "", "scheduler": "inline",
                                               "jobs": 1})
    return table, (d / "ref.h5").stat().st_size, (d / "layout.h5").stat().st_size


def _check_cut(r, out, cause: str) -> rodjit.SweepTable | None:
    """The invariants of a sweep the disk stopped; its table if the file was kept."""
    assert r.returncode == 1, r.stderr
    line = one_line(r.stderr)
    assert cause in line, line
    if not out.exists():                          # its creation was cut: nothing left
        assert "nothing was written" in line, line
        assert not lock_path(out).exists()
        return None
    assert f"rodjit sweep --resume -o {out}" in line, line
    assert "status    failed" in info(out)      # what ``rodjit info`` prints
    return rodjit.load_sweep(out)


def _resume_matches(out, reference, skip=TIMINGS):
    """``sweep --resume`` (in this process: the command line is a thin layer over it)."""
    table = rodjit.sweep(output=out, resume=True, scheduler="inline")
    assert table.status == "completed" and rodjit.load_sweep(out).status == "completed"
    same_values(table, reference, skip)


@pytest.mark.parametrize("level", ["creation", "layout", "the points"])
def test_a_sweep_file_at_the_size_limit_keeps_its_points_and_resumes(tmp_path, reference,
                                                                    level):
    ref, full, layout = reference
    limit = {"creation": 1000, "layout": layout // 2,
             # room for the layout, not for its first write of points (which batches the
             # timing decides: the k-th write refused is checked in-process below)
             "the points": layout + 1000}[level]
    out = tmp_path / "s.h5"
    r = rodjit_cli("sweep", *INLINE, "-o", out, cwd=tmp_path, limit=limit)
    table = _check_cut(r, out, "the file size limit was reached")
    if level in ("creation", "layout"):
        assert table is None
        return
    assert table is not None and table.counts["completed"] < N
    # the rows written: completed points and failed ones alike
    kept = table.counts["completed"] + table.counts["failed"]
    assert f"keeps the points written ({kept} of {N})" in r.stderr, \
        (r.stderr, list(table.columns["status"]), list(table.columns["message"]))
    _resume_matches(out, ref)


@pytest.mark.parametrize("fail_at", [1, 3, N + 1])
def test_a_refused_write_keeps_exactly_the_points_written_before(
        tmp_path, reference, monkeypatch, fail_at):
    """Each point its own write (batches of one point, flush_interval tiny): the k-th write
    refused by the disk half-way (write k <= N: the rows of point k; N + 1: closing the
    file) is undone and leaves k - 1 points."""
    ref = reference[0]
    opened = []

    class Refusing(journal.Journaled):
        def __init__(self, path):
            super().__init__(path)
            opened.append(self)

        def _save(self, start, end, data=None):
            if len(opened) == 1 + fail_at:      # (the first: the file's creation)
                raise OSError(errno.ENOSPC, "No space left on device")
            super()._save(start, end, data)

    monkeypatch.setattr(sweep_file, "Journaled", Refusing)
    out = tmp_path / "s.h5"
    with pytest.raises(WriteFailed, match=rf"keeps the points written \({fail_at - 1} of "
                                          rf"{N}\).*continue with resume=True") as caught:
        rodjit.sweep(ref.base, {k: list(v) for k, v in zip(ref.grid.keys, ref.grid.values)},
                     output=out, scheduler="inline", flush_interval=1e-9, batch_size=1)
    assert caught.value.table.status == "failed"
    assert opened[fail_at].failure is not None
    kept = rodjit.load_sweep(out)
    assert kept.counts["completed"] == fail_at - 1 and kept.status == "running"
    assert "no space left" in info(out)
    monkeypatch.undo()
    table = rodjit.sweep(output=out, resume=True, scheduler="inline")
    same_values(table, ref)


# the sweep's clock for its writes of finished points runs 10 s a reading: every point is
# written on its own whatever the machine's load, so two resumes write alike (how many
# points a write holds sets the file's size; a loaded machine wrote the copy's two in one
# write and the limited resume's in two, which outgrew the copy's size)
ONE_POINT_A_WRITE = ("import itertools, types\n"
                     "import rodjit.sweeps.run_sweep as R\n"
                     "_t = itertools.count(0.0, 10.0)\n"
                     "R.time = types.SimpleNamespace(monotonic=lambda: next(_t),\n"
                     "                               perf_counter=R.time.perf_counter)")


def test_a_resume_needs_only_the_space_its_points_take(tmp_path, reference):
    """A sweep stopped after 2 of its 4 points, continued with its file allowed to grow to
    the size that finishing it gives (measured by finishing a copy) and no further: the
    resume completes, asking no space beyond what it writes."""
    ref = reference[0]
    cut = tmp_path / "cut.h5"
    with pytest.raises(rodjit.SweepInterrupted):
        rodjit.sweep(ref.base, {k: list(v) for k, v in zip(ref.grid.keys, ref.grid.values)},
                     output=cut, scheduler="inline", batch_size=1, progress=_interrupt_after(2))
    assert rodjit.load_sweep(cut).counts["completed"] == 2
    copy = tmp_path / "copy.h5"
    shutil.copy(cut, copy)
    resume = ["sweep", "--resume", "--scheduler", "inline", "--batch-size", "1", "-q", "-o"]
    r = rodjit_cli(*resume, copy, cwd=tmp_path, code=ONE_POINT_A_WRITE)
    assert r.returncode == 0, r.stderr
    finished = copy.stat().st_size
    assert finished > cut.stat().st_size
    r = rodjit_cli(*resume, cut, cwd=tmp_path, limit=finished, code=ONE_POINT_A_WRITE)
    assert r.returncode == 0, r.stderr
    same_values(rodjit.load_sweep(cut), ref)


def test_save_runs_past_the_size_limit_stops_the_sweep_cleanly(tmp_path, reference):
    """Run files bigger than the limit, written by two worker processes: the sweep stops
    at the first that fails; no worker prints a Traceback or crashes, no run file is left
    cut short (the failed one and those of the points in flight are removed), the sweep
    file records the failed point, and --resume writes every run file."""
    ref, full, _ = reference
    out, runs = tmp_path / "s.h5", tmp_path / "runs"
    args = [*ARGS, "-j", "2", "--save-runs", runs, "-o", out]
    r = rodjit_cli("sweep", *args, cwd=tmp_path, limit=full + 400_000)
    table = _check_cut(r, out, "the file size limit was reached")
    assert "the run file" in r.stderr
    assert table is not None and table.counts["failed"] >= 1
    assert "writing the run file failed" in " ".join(table.columns["message"])
    for p in runs.iterdir():            # only complete run files (none fits the limit)
        assert p.suffix == ".h5" and summarize(p).status == "completed", p
    _resume_matches(out, ref, skip=TIMINGS + ("run_file",))
    names = sorted(p.name for p in runs.iterdir())
    assert names == sorted(ref.grid.run_name(i) for i in range(N))
    assert all(summarize(runs / name).status == "completed" for name in names)
