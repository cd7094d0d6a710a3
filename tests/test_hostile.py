"""A catalogue of hostile inputs and faults, each run through the real command line in a
subprocess: the exit code, exactly one line on stderr and no Traceback, no new file that
is neither complete nor resumable, every existing file untouched (hashed before and after),
a bounded wall time (the subprocess timeout)."""
from __future__ import annotations

import hashlib
import resource
import shutil
import signal
import subprocess
import sys

import h5py
import pytest

from conftest import rodjit_cli

TINY = ["--set", "time.t_end=0.02", "--set", "rod.N=3", "-q"]
GRID = ["--grid", "rod.mu=0,1", "--set", "time.t_end=0.02", "-j", "1", "-q"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A directory of the files the cases aim at."""
    d = tmp_path_factory.mktemp("hostile")
    (d / "cfg.toml").write_text("[rod]\nN = 3\n[time]\nt_end = 0.02\n")
    (d / "syntax.toml").write_text("[rod\nN = = 3\n")
    (d / "unknown.toml").write_text("[rod]\nNN = 3\n")
    (d / "range.toml").write_text("[rod]\nN = -4\n")
    (d / "plain.txt").write_text("not a rodjit file\n")
    (d / "data.h5").write_bytes(b"")
    with h5py.File(d / "other.h5", "w") as f:
        f["x"] = [1, 2, 3]
    (d / "adir").mkdir()
    (d / "adir.h5").mkdir()
    assert rodjit_cli("run", "-o", d / "run.h5", *TINY).returncode == 0
    assert rodjit_cli("sweep", *GRID, "-o", d / "sweep.h5").returncode == 0
    shutil.copy(d / "run.h5", d / "cut.h5")
    with open(d / "cut.h5", "r+b") as fh:
        fh.truncate((d / "cut.h5").stat().st_size // 2)
    return d


# (name, arguments (FILES stands for the directory), exit code, text of the one line)
CASES = [
    ("N zero", ["run", *TINY, "--set", "rod.N=0", "-o", "n.h5"], 2, "rod.N"),
    ("N not a number", ["run", "--set", "rod.N=abc", "-o", "n.h5"], 2, "rod.N"),
    ("N float", ["run", "--set", "rod.N=2.5", "-o", "n.h5"], 2, "rod.N"),
    ("mu negative", ["run", "--set", "rod.mu=-1", "-o", "n.h5"], 2, "rod.mu"),
    ("kappa nan", ["run", "--set", "rod.kappa=nan", "-o", "n.h5"], 2, "rod.kappa"),
    ("t_end inf", ["run", "--set", "time.t_end=inf", "-o", "n.h5"], 2, "time.t_end"),
    ("t_end negative", ["run", "--set", "time.t_end=-1", "-o", "n.h5"], 2, "time.t_end"),
    ("t_end 1e300", ["run", "--set", "time.t_end=1e300", "-o", "n.h5"], 2, "limit"),
    ("snapshots every 1e-12", ["run", "--set", "output.snapshot_interval=1e-12", "-o",
                               "n.h5"], 2, "more than the limit"),
    ("diagnostics every 1e-12", ["run", "--set", "output.diagnostics_interval=1e-12", "-o",
                                 "n.h5"], 2, "more than the limit"),
    ("N 10^7", ["run", "--set", "rod.N=10000000", "-o", "n.h5"], 2, "memory"),
    ("output above --max-output", ["run", *TINY, "--max-output", "1K", "-o", "n.h5"], 2,
     "limit of"),
    ("bad --max-output", ["run", *TINY, "--max-output", "lots", "-o", "n.h5"], 2,
     "not understood"),
    ("dt 1e-30", ["run", "--set", "time.dt=1e-30", "-o", "n.h5"], 2, "resolution of t"),
    ("dt needs too many steps", ["run", "--set", "time.dt=1e-9", "--set", "time.t_end=100",
                                 "--set", "output.snapshot_interval=0", "--set",
                                 "output.diagnostics_interval=0", "-o", "n.h5"], 2,
     "--max-steps"),
    ("unknown key", ["run", "--set", "rod.nosuch=1", "-o", "n.h5"], 2, "rod.nosuch"),
    ("--set without =", ["run", "--set", "rod.N", "-o", "n.h5"], 2, "KEY=VALUE"),
    ("missing config", ["run", "FILES/missing.toml", "-o", "n.h5"], 2, "missing.toml"),
    ("TOML syntax error", ["run", "FILES/syntax.toml", "-o", "n.h5"], 2, "syntax.toml"),
    ("TOML unknown key", ["run", "FILES/unknown.toml", "-o", "n.h5"], 2, "NN"),
    ("TOML out of range", ["run", "FILES/range.toml", "-o", "n.h5"], 2, "rod.N"),
    ("unknown preset", ["run", "nosuchpreset", "-o", "n.h5"], 2, "preset"),
    ("a run file as config", ["run", "FILES/run.h5"], 2, "--resume"),
    ("config overwritten by its output", ["run", "FILES/cfg.toml", "-o", "FILES/cfg.toml",
                                          "--overwrite"], 2, "not a rodjit file"),
    ("overwrite a text file", ["run", *TINY, "-o", "FILES/plain.txt", "--overwrite"], 2,
     "not a rodjit file"),
    ("overwrite a foreign HDF5", ["run", *TINY, "-o", "FILES/other.h5", "--overwrite"], 2,
     "not a rodjit file"),
    ("overwrite a sweep with a run", ["run", *TINY, "-o", "FILES/sweep.h5", "--overwrite"], 2,
     "rodjit sweep file"),
    ("existing run, no --overwrite", ["run", *TINY, "-o", "FILES/run.h5"], 2,
     "already exists"),
    ("missing output directory", ["run", *TINY, "-o", "nodir/x.h5"], 2, "does not exist"),
    ("output is a directory", ["run", *TINY, "-o", "FILES/adir.h5"], 2, "directory"),
    ("output directory is a file", ["run", *TINY, "-o", "FILES/plain.txt/x.h5"], 2,
     "not a directory"),
    ("flush interval 0", ["run", *TINY, "--flush-interval", "0", "-o", "n.h5"], 2,
     "flush_interval"),
    ("t-end not a number", ["run", "--t-end", "abc"], 2, "--t-end"),
    ("unknown verb", ["bounce"], 2, "No such command"),
    ("unknown option", ["run", "--nosuch"], 2, "--nosuch"),
    ("resume missing", ["run", "--resume", "FILES/missing.h5"], 2, "does not exist"),
    ("resume completed", ["run", "--resume", "FILES/run.h5"], 2, "already complete"),
    ("resume text file", ["run", "--resume", "FILES/plain.txt"], 2, "not"),
    ("resume a sweep file", ["run", "--resume", "FILES/sweep.h5"], 2, "sweep"),
    ("resume with --set", ["run", "--resume", "FILES/run.h5", "--set", "rod.mu=1"], 2,
     "--set cannot"),
    ("resume to an earlier t", ["run", "--resume", "FILES/run.h5", "--t-end", "0.001"], 2,
     "time.t_end"),
    ("info missing", ["info", "FILES/missing.h5"], 2, "does not exist"),
    ("info text file", ["info", "FILES/plain.txt"], 2, "not"),
    ("info empty file", ["info", "FILES/data.h5"], 2, "not"),
    ("info foreign HDF5", ["info", "FILES/other.h5"], 2, "rodjit_kind"),
    ("info a file cut short", ["info", "FILES/cut.h5"], 2, "cut short"),
    ("plot into a missing directory", ["plot", "FILES/run.h5", "-o", "nodir/x.png"], 2,
     "does not exist"),
    ("plot sweep kind of a run", ["plot", "FILES/run.h5", "--kind", "heatmap"], 2,
     "sweep files"),
    ("plot run kind of a sweep", ["plot", "FILES/sweep.h5", "--kind", "heights"], 2,
     "run files"),
    ("sweep without grid", ["sweep", "--set", "time.t_end=0.02", "-o", "s.h5"], 2, "grid"),
    ("sweep empty values", ["sweep", "--grid", "rod.mu=", "-o", "s.h5"], 2, "rod.mu"),
    ("sweep unknown key", ["sweep", "--grid", "rod.nosuch=1,2", "-o", "s.h5"], 2,
     "rod.nosuch"),
    ("sweep invalid value", ["sweep", "--grid", "rod.N=0,1", "-o", "s.h5"], 2, "rod.N"),
    ("sweep jobs 0", ["sweep", *GRID[:2], "-j", "0", "-o", "s.h5"], 2, "jobs"),
    ("sweep bad scheduler", ["sweep", *GRID, "--scheduler", "bogus", "-o", "s.h5"], 2,
     "bogus"),
    ("sweep resume completed", ["sweep", "--resume", "-o", "FILES/sweep.h5"], 2,
     "already complete"),
    ("sweep resume missing", ["sweep", "--resume", "-o", "FILES/missing.h5"], 2,
     "does not exist"),
    ("sweep overwrites a run", ["sweep", *GRID, "-o", "FILES/run.h5", "--overwrite"], 2,
     "rodjit run file"),
    ("sweep overwrites its config", ["sweep", "FILES/cfg.toml", *GRID, "-o",
                                     "FILES/cfg.toml", "--overwrite"], 2, "not a rodjit file"),
    ("save-runs onto a file", ["sweep", *GRID, "--save-runs", "FILES/plain.txt", "-o",
                               "s.h5"], 2, "plain.txt"),
    ("dt not dividing the outputs", ["run", *TINY, "--set", "time.dt=3e-4", "-o", "n.h5"], 2,
     "does not divide output.snapshot_interval"),
    ("dt above the output interval", ["run", *TINY, "--set", "time.dt=2.5e-3", "-o", "n.h5"],
     2, "does not divide output.diagnostics_interval"),
    ("dry run of dt 1e-30", ["run", "--dry-run", "--set", "time.dt=1e-30", "-o", "n.h5"], 2,
     "resolution of t"),
    ("dry run above --max-output", ["run", "--dry-run", *TINY, "--max-output", "1K", "-o",
                                    "n.h5"], 2, "limit of"),
    ("dry run into a missing directory", ["run", "--dry-run", *TINY, "-o", "nodir/x.h5"], 2,
     "does not exist"),
    ("dry run onto its config", ["run", "--dry-run", "FILES/cfg.toml", "-o", "FILES/cfg.toml",
                                 "--overwrite"], 2, "not a rodjit file"),
    ("dry run of a resume", ["run", "--dry-run", "--resume", "FILES/run.h5"], 2, "--dry-run"),
    ("grid of 10^7 points", ["sweep", "--grid", "rod.mu=linspace(0,1,10000000)", "-o",
                             "s.h5"], 2, "--max-points"),
    ("grid product of 10^7", ["sweep", "--grid", "rod.mu=linspace(0,1,10000)", "--grid",
                              "rod.kappa=logspace(1,3,1000)", "-o", "s.h5"], 2,
     "10,000,000 points"),
    ("dry run of 10^7 points", ["sweep", "--dry-run", "--grid",
                                "rod.mu=linspace(0,1,10000000)"], 2, "--max-points"),
    ("bad --max-points", ["sweep", *GRID, "--max-points", "many", "-o", "s.h5"], 2,
     "--max-points"),
    ("sweep point with dt 1e-30", ["sweep", *GRID[2:], "--grid", "time.dt=1e-3,1e-30", "-o",
                                   "s.h5"], 2, "grid point 1 (time.dt=1e-30)"),
    ("sweep point needing too many steps", ["sweep", *GRID[4:], "--grid", "time.dt=1e-9",
                                            "--set", "time.t_end=100", "-o", "s.h5"], 2,
     "--max-steps"),
    ("sweep point dt not dividing", ["sweep", *GRID[2:], "--grid", "time.dt=1e-3,3e-4", "-o",
                                     "s.h5"], 2, "does not divide"),
    ("sweep file above --max-output", ["sweep", *GRID, "--max-output", "20K", "-o", "s.h5"],
     2, "the sweep file would hold 2 points"),
    ("run files above --max-output", ["sweep", *GRID, "--save-runs", "runs", "--max-output",
                                      "100K", "-o", "s.h5"], 2, "the run file of grid point"),
    ("sweep dry run over a run file", ["sweep", "--dry-run", *GRID, "-o", "FILES/run.h5",
                                       "--overwrite"], 2, "rodjit run file"),
]


def _digest(d):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(d.rglob("*")) if p.is_file() and not p.name.endswith(".lock")}


def _check_new_files(cwd, before):
    """Every new rodjit file is complete or resumable (``info`` reads it)."""
    for p in cwd.rglob("*.h5"):
        if p.name not in before:
            r = rodjit_cli("info", p)
            assert r.returncode == 0, (p, r.stderr)


@pytest.mark.parametrize("name,args,code,text", CASES, ids=[c[0] for c in CASES])
def test_hostile_input(files, tmp_path, name, args, code, text):
    args = [str(a).replace("FILES", str(files)) for a in args]
    before = _digest(files)
    r = rodjit_cli(*args, cwd=tmp_path, timeout=120)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == code, r.stderr
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert text in lines[0], lines[0]
    assert _digest(files) == before
    if code == 2:       # refused: nothing written (no file, no lock, no directory)
        assert list(tmp_path.iterdir()) == []
    _check_new_files(tmp_path, ())


def _limited(limit, args, cwd):
    def pre():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return subprocess.run([sys.executable, "-m", "rodjit", *map(str, args)], cwd=cwd,
                          preexec_fn=pre, capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("limit", [4000, 60000])
def test_fault_file_size_limit_on_a_run(tmp_path, limit):
    r = _limited(limit, ["run", "--set", "time.t_end=0.3", "-q", "--flush-interval", "0.01",
                         "-o", "x.h5"], tmp_path)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "file size limit" in lines[0]
    _check_new_files(tmp_path, ())
    if (tmp_path / "x.h5").exists():
        assert rodjit_cli("run", "--resume", tmp_path / "x.h5", "-q").returncode == 0


@pytest.mark.parametrize("args", [["plot", "r.h5", "-o", "x.png"],
                                  ["plot", "r.h5", "-o", "old.pdf", "--overwrite"],
                                  ["animate", "r.h5", "-o", "x.gif", "--fps", "4",
                                   "--duration", "1"]], ids=["plot png", "plot over an old pdf",
                                                             "animate gif"])
def test_fault_file_size_limit_on_a_picture(tmp_path, args):
    """A plot or a movie the disk refuses: exit 1, one line naming the cause, no partial
    picture, and an older picture of the same name left as it was."""
    # Matplotlib's per-user font cache is built here, before the limit: on a machine where
    # it doesn't exist yet the child would build it, fail to save it under the limit and
    # log a line of its own about its cache, which is not rodjit's output.
    pytest.importorskip("matplotlib.font_manager")
    import rodjit

    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.3, "rod.N": 10,
                                                 "rod.mu": 1.0}), tmp_path / "r.h5")
    (tmp_path / "old.pdf").write_bytes(b"%PDF-1.4 an older picture")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    r = _limited(2000, args, tmp_path)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "file size limit" in lines[0] and "nothing was written" in lines[0]
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


@pytest.mark.parametrize("threads", ["0", "abc", "-2", ""])
def test_an_environment_numba_cannot_use_is_named(tmp_path, threads):
    """NUMBA_NUM_THREADS=0 failed the run with Numba's "Number of threads specified must be
    > 0." once it compiled (after the run file was made), "abc" printed Numba's warning with
    its traceback: one line naming the variable, exit 2, before anything is written."""
    import os

    env = dict(os.environ, NUMBA_NUM_THREADS=threads)
    r = subprocess.run([sys.executable, "-m", "rodjit", "run", *TINY, "-o", "x.h5"],
                       cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert lines[0].startswith(f"Error: environment variable NUMBA_NUM_THREADS = "
                               f"{threads!r} is out of range"), lines[0]
    assert list(tmp_path.iterdir()) == []


def _importing_numpy(pid: int) -> bool:
    """Has process ``pid`` started loading NumPy (rodjit's own import is under way)?"""
    try:
        with open(f"/proc/{pid}/maps") as fh:
            return "numpy" in fh.read()
    except OSError:
        return False


@pytest.mark.parametrize("delay", [0.0, 0.5, 1.5])
def test_fault_signal_during_start_up(tmp_path, delay):
    """SIGINT/SIGTERM while importing or loading kernels (``delay`` seconds after NumPy
    starts loading, inside rodjit's import; before that the interpreter itself is starting
    and no program can handle a signal): 130/143, one line, no Traceback, no file that is
    neither complete nor resumable."""
    import time

    if not _importing_numpy(__import__("os").getpid()):
        pytest.skip("no /proc/PID/maps here to tell when the import has begun")
    for sig in (signal.SIGINT, signal.SIGTERM):
        p = subprocess.Popen([sys.executable, "-m", "rodjit", "run", *TINY, "-o", "x.h5",
                              "--overwrite"], cwd=tmp_path, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 60
        while not _importing_numpy(p.pid) and p.poll() is None and time.monotonic() < deadline:
            time.sleep(0.002)
        time.sleep(delay)
        p.send_signal(sig)
        err = p.communicate(timeout=120)[1]
        assert p.returncode in (0, 128 + sig), err      # 0: it finished first
        assert "Traceback" not in err and len(err.strip().splitlines()) <= 1, err
        _check_new_files(tmp_path, ())


# ---- sweeps on a disk that refuses writes ---------------------------------------------------
# (tests/test_disk_full_sweep.py and tests/test_disk_full_tmpfs.py hold the fill levels and
# the resumes; here, each fault once through the catalogue's checks)
SWEEP_CUT = ["--grid", "rod.mu=5,10", "--set", "time.t_end=0.02", "-q"]


@pytest.mark.parametrize("limit,args,text", [
    (2000, ["--scheduler", "inline"], "nothing was written"),            # creating the file
    (None, ["--scheduler", "inline"], "keeps the points written ("),     # its later writes
    (300000, ["-j", "1", "--save-runs", "runs"], "the run file"),        # a run file
], ids=["sweep file created", "sweep file rows", "save-runs run file"])
def test_fault_file_size_limit_on_a_sweep(tmp_path, limit, args, text):
    cut = SWEEP_CUT
    if limit is None:
        # one byte short of the finished file: the file is made whole, a later write fails.
        # One point, so one write of rows whatever the wall clock (two points are written
        # once or twice, as the flush interval falls, and the files' sizes differ)
        cut = ["--grid", "rod.mu=5", *SWEEP_CUT[2:]]
        whole = tmp_path / "whole"
        whole.mkdir()
        done = subprocess.run([sys.executable, "-m", "rodjit", "sweep", *cut, *args,
                               "-o", "s.h5"], cwd=whole, capture_output=True, timeout=120)
        assert done.returncode == 0, done.stderr
        limit = (whole / "s.h5").stat().st_size - 1
        shutil.rmtree(whole)
    r = _limited(limit, ["sweep", *cut, *args, "-o", "s.h5"], tmp_path)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert "file size limit" in lines[0] and text in lines[0], lines[0]
    _check_new_files(tmp_path, ())
    if (tmp_path / "runs").exists():       # no run file left cut short
        assert not [p for p in (tmp_path / "runs").iterdir() if p.name.startswith(".")]
