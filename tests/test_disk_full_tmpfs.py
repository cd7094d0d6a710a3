"""A real full disk: a small tmpfs (mounted for the test; skipped where mounting is not
permitted), filled up to a chosen free space, then written by a run, a sweep and the run
files of ``sweep --save-runs``.  The same guarantees as under a file-size limit: exit 1,
one line saying the device is full, the file absent or keeping its last checkpoint (every
point written before), readable by ``info``, and continued by ``--resume`` with space."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
import uuid

import pytest

import rodjit
from conftest import assert_same_files, one_line, rodjit_cli
from rodjit.output.summary import summarize
from rodjit.reports import info
from rodjit.sweeps.grid import parse_grid_option
from test_sweep_driver import same_values

FULL = "no space left on the device"
RUN = ["--set", "time.t_end=0.3", "-q", "--flush-interval", "0.01"]
GRIDS = ["rod.mu=5,10", "floor.beta=0.01,0.05"]
SWEEP = [x for g in GRIDS for x in ("--grid", g)] + ["--set", "time.t_end=0.1", "-q"]


@pytest.fixture
def disk(tmp_path):
    """A tmpfs of 8 MiB at tmp_path/disk, unmounted afterwards."""
    mnt = tmp_path / "disk"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=8m", f"rodjit-{uuid.uuid4().hex[:6]}",
                        str(mnt)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip() or r.returncode}")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def _fill(disk, leave: int):
    """Fill ``disk`` with a filler file until only about ``leave`` bytes are free (while
    another process may be writing to it: what it took meanwhile is not asked for)."""
    filler = disk / "filler"
    for _ in range(20):
        st = os.statvfs(disk)
        size = st.f_bavail * st.f_frsize - leave
        if size <= 0:
            break
        with open(filler, "ab") as fh:
            try:
                os.posix_fallocate(fh.fileno(), os.fstat(fh.fileno()).st_size, size)
                break
            except OSError:       # the writer took some of it first: measure again
                continue
    return filler


def _fill_while(args, cwd, started, leave: int = 0):
    """Run ``rodjit ARGS`` with space enough for what it estimates (it refuses up front
    otherwise); once ``started()`` says it writes, fill its disk (another process taking
    the space, as on a shared disk).  Returns the finished process and its stderr."""
    p = subprocess.Popen([sys.executable, "-m", "rodjit", *map(str, args)], cwd=cwd,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not started() and p.poll() is None:
            assert time.monotonic() < deadline
            time.sleep(0.005)
        if p.poll() is None:
            _fill(started.disk, leave)
        err = p.communicate(timeout=120)[1]
    finally:
        p.kill()
    return p, err


def test_a_run_onto_a_disk_that_fills_keeps_its_checkpoint_and_resumes_elsewhere(tmp_path,
                                                                                 disk):
    ref = tmp_path / "ref.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.3}), ref)
    out = disk / "r.h5"

    def started():
        return out.exists()
    started.disk = disk
    p, err = _fill_while(["run", "-o", out, *RUN], tmp_path, started)
    if p.returncode == 0:           # it had finished before the disk filled
        assert err == ""
        pytest.skip("the run finished before the disk filled")
    assert p.returncode == 1, err
    line = one_line(err)
    assert FULL in line, line
    if not out.exists():
        assert "nothing was written" in line
        return
    assert "keeps its last checkpoint" in line and "--resume" in line
    assert f"failed (a write failed: {FULL}" in info(out)
    moved = tmp_path / "r.h5"                  # to a disk with space
    shutil.move(out, moved)
    rodjit.resume_file(moved)
    assert_same_files(moved, ref)


def test_a_sweep_onto_a_full_disk_resumes_once_there_is_space(tmp_path, disk):
    cfg = rodjit.Config().override({"time.t_end": 0.1})
    ref = rodjit.sweep(cfg, parse_grid_option(GRIDS), scheduler="inline")
    # just the space the sweep is estimated to take (less is refused up front): not
    # enough for its file and, while it writes its points, their journal
    need = rodjit.plan_sweep(cfg, parse_grid_option(GRIDS), output=disk / "x.h5").sweep_bytes
    filler = _fill(disk, int(need) + 4096)
    out = disk / "s.h5"
    r = rodjit_cli("sweep", *SWEEP, "--scheduler", "inline", "-o", out, cwd=tmp_path)
    assert r.returncode == 1, r.stderr
    line = one_line(r.stderr)
    assert FULL in line, line
    if out.exists():
        assert f"rodjit sweep --resume -o {out}" in line
        assert "status    failed" in info(out)
        filler.unlink()
        table = rodjit.sweep(output=out, resume=True, scheduler="inline")
    else:
        assert "nothing was written" in line
        filler.unlink()
        table = rodjit.sweep(cfg, parse_grid_option(GRIDS), output=out, scheduler="inline")
    same_values(table, ref)


def test_run_files_of_save_runs_onto_a_disk_that_fills(tmp_path, disk):
    """The sweep file has space; the run files' disk fills once the first is written."""
    runs, out = disk / "runs", tmp_path / "s.h5"

    def started():
        return runs.is_dir() and any(p.suffix == ".h5" for p in runs.iterdir())
    started.disk = disk
    p, err = _fill_while(["sweep", *SWEEP, "-j", "2", "--save-runs", runs, "-o", out],
                         tmp_path, started)
    if p.returncode == 0:
        pytest.skip("the sweep finished before the disk filled")
    assert p.returncode == 1, err
    line = one_line(err)
    assert FULL in line and "the run file" in line, line
    assert "writing the run file failed" in " ".join(rodjit.load_sweep(out)["message"])
    assert "status    failed" in info(out)
    for f in runs.iterdir():           # nothing cut short left behind
        assert f.suffix == ".h5" and summarize(f).status == "completed", f
    assert rodjit.load_sweep(out).counts["failed"] >= 1
