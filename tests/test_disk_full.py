"""Writes the disk refuses (here: a file-size limit, RLIMIT_FSIZE, in a real subprocess, with
SIGXFSZ ignored so that write() returns EFBIG): at every fill level the run stops with exit
1 and one line naming the cause, the file is either absent or keeps its last checkpoint
(``info`` reads it as failed, without a Traceback), and ``--resume`` with space continues it
bit for bit."""
from __future__ import annotations

import pytest

from conftest import assert_same_files, one_line, rodjit_cli

ARGS = ["--set", "time.t_end=0.6", "--set", "output.snapshot_interval=0.01", "-q",
        "--flush-interval", "0.01"]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("ref")
    r = rodjit_cli("run", "-o", d / "ref.h5", *ARGS)
    assert r.returncode == 0, r.stderr
    return d / "ref.h5"


@pytest.mark.parametrize("fraction", [0.003, 0.2, 0.6, 0.97])
def test_a_run_that_hits_the_size_limit_stops_cleanly_and_resumes_bit_for_bit(
        tmp_path, reference, fraction):
    limit = int(reference.stat().st_size * fraction)
    out = tmp_path / "cut.h5"
    r = rodjit_cli("run", "-o", out, *ARGS, cwd=tmp_path, limit=limit)
    assert r.returncode == 1, r.stderr
    line = one_line(r.stderr)
    assert "file size limit" in line
    if not out.exists():                          # during layout creation: nothing left
        assert "nothing was written" in line
        return
    assert "keeps its last checkpoint" in line and "--resume" in line
    info = rodjit_cli("info", out)
    assert info.returncode == 0 and "Traceback" not in info.stderr
    assert "failed (a write failed: the file size limit" in info.stdout
    r = rodjit_cli("run", "--resume", out, "-q")
    assert r.returncode == 0, r.stderr
    assert_same_files(out, reference)
