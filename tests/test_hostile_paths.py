"""Hostile catalogue, paths: special files (FIFO, /dev/null, /dev/full, a directory) as the
output or the file to read, with or without --overwrite; names too long for the file
system; symbolic and hard links; unicode names.  Refusals are one line, exit code 2,
nothing written; a crash recovery through a symbolic link rebuilds the link's target and
keeps the link."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys

import h5py
import pytest
from click.testing import CliRunner

from conftest import assert_same_files, rodjit_cli
from rodjit import cli

TINY = ["--set", "time.t_end=0.3", "--set", "rod.N=3", "--set", "rod.mu=1", "-q",
        "--flush-interval", "0.0001"]
GRID = ["--grid", "rod.mu=1,2", "--set", "time.t_end=0.02", "--set", "rod.N=3",
        "--scheduler", "inline", "-q"]


def invoke(*args):
    if any(os.path.isdir(str(a)) and str(a).endswith(".h5") for a in args):
        # click itself refuses a directory for -o, with its usage lines in this process
        # and one line through the command line's entry point: run that one
        r = rodjit_cli(*args, timeout=120)
        return _Done(r.returncode, r.stderr, r.stdout + r.stderr)
    return CliRunner().invoke(cli.main, [str(a) for a in args])


class _Done:
    exception = None

    def __init__(self, code, stderr, output):
        self.exit_code, self.stderr, self.output = code, stderr, output


def refused(r, text):
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.output
    assert text in lines[0], lines[0]


@pytest.fixture
def fifo(tmp_path):
    p = tmp_path / "pipe.h5"
    os.mkfifo(p)
    return p


SPECIAL = ["fifo", "/dev/null", "/dev/full", "directory"]


def _special(kind, tmp_path):
    if kind == "fifo":
        p = tmp_path / "pipe.h5"
        os.mkfifo(p)
        return p
    if kind == "directory":
        p = tmp_path / "d.h5"
        p.mkdir()
        return p
    return kind


@pytest.mark.parametrize("overwrite", [False, True], ids=["plain", "--overwrite"])
@pytest.mark.parametrize("kind", SPECIAL)
def test_run_into_a_special_file(tmp_path, monkeypatch, kind, overwrite):
    monkeypatch.chdir(tmp_path)
    out = _special(kind, tmp_path)
    before = sorted(os.listdir(tmp_path))
    r = invoke("run", *TINY, "-o", out, *(["--overwrite"] if overwrite else []))
    refused(r, "directory" if kind == "directory" else "not a regular file")
    assert sorted(os.listdir(tmp_path)) == before


@pytest.mark.parametrize("kind", SPECIAL)
def test_sweep_into_a_special_file(tmp_path, monkeypatch, kind):
    monkeypatch.chdir(tmp_path)
    out = _special(kind, tmp_path)
    refused(invoke("sweep", *GRID, "-o", out, "--overwrite"),
            "directory" if kind == "directory" else "not a regular file")


@pytest.mark.parametrize("verb", ["info", "resume"])
@pytest.mark.parametrize("kind", ["fifo", "/dev/null", "/dev/full"])
def test_read_a_special_file(tmp_path, kind, verb):
    """Reading a FIFO would block for ever: refused before it is opened."""
    p = _special(kind, tmp_path)
    args = ("info", p) if verb == "info" else ("run", "--resume", p)
    refused(invoke(*args), "not a rodjit file")


@pytest.mark.parametrize("args", [
    ["run", *TINY, "-o", "N" * 300 + ".h5"],
    ["sweep", *GRID, "-o", "N" * 300 + ".h5"],
    ["info", "N" * 300 + ".h5"],
    ["run", "--resume", "N" * 300 + ".h5"],
], ids=["run", "sweep", "info", "resume"])
def test_a_name_too_long(tmp_path, monkeypatch, args):
    monkeypatch.chdir(tmp_path)
    refused(invoke(*args), "too long")
    assert list(tmp_path.iterdir()) == []


def test_a_name_too_long_through_the_real_command_line(tmp_path):
    r = rodjit_cli("run", *TINY, "-o", "N" * 300 + ".h5", cwd=tmp_path, timeout=120)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr


@pytest.mark.parametrize("name", ["ünïcødé €.h5", "日本語.h5", "space and 'quote'.h5"])
def test_unicode_names(tmp_path, monkeypatch, name):
    monkeypatch.chdir(tmp_path)
    assert invoke("run", *TINY, "-o", name).exit_code == 0
    r = invoke("info", name)
    assert r.exit_code == 0 and "completed" in r.output
    assert invoke("run", "--resume", name, "--t-end", "0.4", "-q").exit_code == 0


def _killed(path) -> None:
    """Leave ``path`` as a writer killed mid-run leaves it: the SWMR flags set."""
    subprocess.run([sys.executable, "-c", "import h5py, os, sys\n"
                    "f = h5py.File(sys.argv[1], 'r+', libver=('v110', 'v110'))\n"
                    "f.attrs['status'] = 'running'\n"
                    "f.swmr_mode = True\nf.flush()\nos._exit(0)", str(path)], check=True)


def test_crash_recovery_through_a_symbolic_link(tmp_path, monkeypatch):
    """The link stays a link; its target is rebuilt and continued, the same run as one
    never killed; no second copy appears."""
    monkeypatch.chdir(tmp_path)
    assert invoke("run", *TINY, "-o", "ref.h5").exit_code == 0
    shutil.copy("ref.h5", "real.h5")
    assert invoke("run", "--resume", "ref.h5", "--t-end", "0.6", "-q").exit_code == 0
    os.symlink("real.h5", "link.h5")
    _killed(tmp_path / "real.h5")
    assert "the writing process is gone" in invoke("info", "link.h5").output
    r = invoke("run", "--resume", "link.h5", "--t-end", "0.6", "-q")
    assert r.exit_code == 0, r.output
    assert os.path.islink("link.h5") and os.readlink("link.h5") == "real.h5"
    with h5py.File("real.h5", "r") as f:
        assert f.attrs["status"] == "completed"
    assert_same_files("real.h5", "ref.h5")       # NaN (a pending bounce's) equal to NaN
    assert sorted(p for p in os.listdir(".") if not p.startswith(".")) == [
        "link.h5", "real.h5", "ref.h5"]


def test_a_link_and_its_target_share_one_writer_lock(tmp_path):
    from rodjit.output.lock import lock_path

    (tmp_path / "real.h5").write_bytes(b"")
    os.symlink("real.h5", tmp_path / "link.h5")
    assert lock_path(tmp_path / "link.h5") == lock_path(tmp_path / "real.h5")


def test_run_through_a_symbolic_link_writes_its_target(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    os.symlink("target.h5", "link.h5")
    assert invoke("run", *TINY, "-o", "link.h5").exit_code == 0
    assert os.path.islink("link.h5") and os.path.isfile("target.h5")
    assert invoke("run", *TINY, "-o", "link.h5", "--overwrite").exit_code == 0
    assert os.path.islink("link.h5")


def test_a_hard_link_is_continued_in_place(tmp_path, monkeypatch):
    """Continuing a closed file through one of its hard links changes the file both
    names share."""
    monkeypatch.chdir(tmp_path)
    assert invoke("run", *TINY, "-o", "a.h5").exit_code == 0
    os.link("a.h5", "b.h5")
    assert invoke("run", "--resume", "b.h5", "--t-end", "0.4", "-q").exit_code == 0
    assert os.stat("a.h5").st_ino == os.stat("b.h5").st_ino
    with h5py.File("a.h5", "r") as f:
        assert f["snapshots/t"][-1] >= 0.4 - 1e-12


def test_crash_recovery_of_a_file_with_hard_links_is_refused_up_front(tmp_path, monkeypatch):
    """A killed file that has two names (hard links): its recovery would rebuild it as a
    new file under one name only, leaving the other on the killed run.  Refused through
    either name in one line (exit 2), both names left byte for byte as they were; once it
    has a single name, it is recovered and continued, the same run as one never killed."""
    import hashlib

    monkeypatch.chdir(tmp_path)
    assert invoke("run", *TINY, "-o", "ref.h5").exit_code == 0
    shutil.copy("ref.h5", "a.h5")
    assert invoke("run", "--resume", "ref.h5", "--t-end", "0.6", "-q").exit_code == 0
    _killed(tmp_path / "a.h5")
    os.link("a.h5", "b.h5")
    before = hashlib.sha256(open("a.h5", "rb").read()).hexdigest()
    for name in ("a.h5", "b.h5"):
        r = invoke("run", "--resume", name, "--t-end", "0.6", "-q")
        assert r.exit_code == 2, r.output
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and "has 2 hard links" in lines[0], r.stderr
        assert "nothing was written" in lines[0]
        assert hashlib.sha256(open(name, "rb").read()).hexdigest() == before
    assert os.stat("a.h5").st_ino == os.stat("b.h5").st_ino
    assert sorted(p for p in os.listdir(".") if not p.startswith(".")) == [
        "a.h5", "b.h5", "ref.h5"]            # no rebuilt copy left beside them
    os.unlink("b.h5")
    r = invoke("run", "--resume", "a.h5", "--t-end", "0.6", "-q")
    assert r.exit_code == 0, r.output
    assert_same_files("a.h5", "ref.h5")


def test_an_older_format_file_with_hard_links_is_not_rebuilt(tmp_path, monkeypatch):
    """Continuing a file of an older format rebuilds it in the current one (a new file):
    with several hard links that is refused like a crash recovery, nothing written."""
    monkeypatch.chdir(tmp_path)
    fixture = os.path.join(os.path.dirname(__file__), "fixtures", "format1_run.h5")
    shutil.copy(fixture, "old.h5")
    os.link("old.h5", "other.h5")
    before = open("old.h5", "rb").read()
    r = invoke("run", "--resume", "old.h5", "--t-end", "0.3", "-q")
    assert r.exit_code == 2, r.output
    assert "has 2 hard links" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert open("old.h5", "rb").read() == before == open("other.h5", "rb").read()


@pytest.mark.parametrize("verb", ["plot", "animate"])
@pytest.mark.parametrize("onto", ["itself", "itself through a link", "another run file"])
def test_a_picture_never_replaces_its_input_or_any_hdf5_file(tmp_path, monkeypatch, verb,
                                                             onto):
    """``-o`` naming the file drawn (under a picture's suffix, or through a link) or another
    HDF5 file is refused in one line even with --overwrite, the file unchanged; before,
    ``rodjit plot r.png -o r.png --overwrite`` replaced a run file named r.png by its own
    picture."""
    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    suffix = ".png" if verb == "plot" else ".gif"
    run = tmp_path / f"r{suffix}"
    r = invoke("run", "-o", "r.h5", *TINY)
    assert r.exit_code == 0, r.output
    shutil.copy("r.h5", run)
    target = run
    if onto == "itself through a link":
        target = tmp_path / f"link{suffix}"
        target.symlink_to(run)
    elif onto == "another run file":
        run = tmp_path / "r.h5"
        target = tmp_path / f"other{suffix}"
        shutil.copy("r.h5", target)
    before = {p: p.read_bytes() for p in (run, target)}
    r = invoke(verb, run, "-o", target, "--overwrite")
    refused(r, "is the file being drawn" if onto != "another run file" else
            "is an HDF5 file, not a picture")
    assert {p: p.read_bytes() for p in before} == before


@pytest.mark.parametrize("inside", ["runs/s.h5", "runs/sub/s.h5", "runs/0_rod.mu=1.h5"])
def test_a_sweep_file_inside_the_run_files_directory_is_refused_up_front(tmp_path,
                                                                          monkeypatch, inside):
    """-o inside --save-runs (where a run file of its name would replace it) is refused in
    one line before anything is written, on the command line and in Python."""
    monkeypatch.chdir(tmp_path)
    r = invoke("sweep", *GRID, "--save-runs", "runs", "-o", inside)
    refused(r, "would hold the sweep file -o")
    assert not (tmp_path / "runs").exists()
    with pytest.raises(ValueError, match="would hold the sweep file"):
        import rodjit

        rodjit.sweep(rodjit.Config().override({"time.t_end": 0.02, "rod.N": 3}),
                     {"rod.mu": [1, 2]}, output=inside, save_runs="runs", scheduler="inline",
                     handle_signals=False)
    assert not (tmp_path / "runs").exists()
    r = invoke("sweep", *GRID, "--save-runs", "runs", "-o", "beside.h5")
    assert r.exit_code == 0, r.output
