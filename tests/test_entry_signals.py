"""The command's entry point and the signals at its edges: the installed ``rodjit`` command
behaves as ``python -m rodjit`` (one-line errors, 130 on SIGINT), and a SIGINT that lands
while a finished sweep tears down (closing its workers, its last write, releasing its
lock, printing its table) ends with exit 130, the table, one line, and a complete file."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import rodjit
from conftest import one_line, rodjit_cli
from rodjit.output.summary import summarize
from rodjit.sweeps import sweep_file
from rodjit.sweeps.executors import InlineExecutor

GRID = {"rod.mu": [5.0, 10.0]}
ARGS = ["--grid", "rod.mu=5,10", "--set", "time.t_end=0.05", "--scheduler", "inline"]


def _script() -> Path:
    script = Path(sys.executable).with_name("rodjit")
    if not script.exists():
        pytest.skip("no rodjit console script beside the interpreter")
    return script


def test_the_console_script_reports_a_bad_option_as_python_m_rodjit_does(tmp_path):
    args = ["run", "--no-such-option"]
    r = subprocess.run([_script(), *args], cwd=tmp_path, capture_output=True, text=True,
                       timeout=120)
    m = rodjit_cli(*args, cwd=tmp_path)
    assert r.returncode == m.returncode == 2
    assert one_line(r.stderr) == one_line(m.stderr)
    assert "No such option '--no-such-option'" in r.stderr


def test_the_console_script_exits_130_on_sigint_with_one_line(tmp_path):
    """SIGINT once the run file exists: a clean stop at the next checkpoint."""
    p = subprocess.Popen([_script(), "run", "--set", "time.t_end=30", "-q", "-o", "x.h5"],
                         cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not (tmp_path / "x.h5").exists() and p.poll() is None:
            assert time.monotonic() < deadline
            time.sleep(0.01)
        p.send_signal(signal.SIGINT)
        err = p.communicate(timeout=120)[1]
    finally:
        p.kill()
    assert p.returncode == 130, err
    assert "interrupted by SIGINT" in one_line(err) and "--resume" in err
    assert summarize(tmp_path / "x.h5").status == "interrupted"


def _signal_self():
    os.kill(os.getpid(), signal.SIGINT)


@pytest.mark.parametrize("where", ["closing the executor", "the last write"])
def test_a_signal_during_the_teardown_leaves_a_complete_file(tmp_path, monkeypatch, where):
    """In-process, the signal sent from inside the teardown step (deterministic)."""
    if where == "closing the executor":
        monkeypatch.setattr(InlineExecutor, "close", lambda self, cancel=False: _signal_self())
    else:
        finish = sweep_file.finish
        monkeypatch.setattr(sweep_file, "finish",
                            lambda *a, **k: (_signal_self(), finish(*a, **k)))
    out = tmp_path / "s.h5"
    cfg = rodjit.Config().override({"time.t_end": 0.05})
    with pytest.raises(rodjit.SweepInterrupted, match="SIGINT after the last point") as e:
        rodjit.sweep(cfg, GRID, output=out, scheduler="inline")
    assert e.value.signum == signal.SIGINT and e.value.table.status == "completed"
    table = rodjit.load_sweep(out)
    assert table.status == "completed" and table.counts["completed"] == 2


SEND = "import os, signal\ndef _sigint(*a, **k):\n    os.kill(os.getpid(), signal.SIGINT)\n"


@pytest.mark.parametrize("where,code", [
    ("the last write", SEND + "import rodjit.sweeps.sweep_file as s\nf = s.finish\n"
                              "s.finish = lambda *a, **k: (_sigint(), f(*a, **k))"),
    # after the sweep's own handlers are gone: the lock released, the table not printed
    ("releasing the lock", SEND + "from rodjit.output.lock import WriterLock as W\n"
                                  "r = W.release\nW.release = lambda self: (r(self), _sigint())"),
])
def test_the_command_prints_the_table_then_exits_130(tmp_path, where, code):
    r = rodjit_cli("sweep", *ARGS, "-o", "s.h5", cwd=tmp_path, code=code)
    assert r.returncode == 130, r.stderr
    line = one_line(r.stderr)
    assert "interrupted by SIGINT after the last point" in line and "is complete" in line
    lines = r.stdout.splitlines()
    assert lines[0].startswith("s.h5: sweep completed, 2 points") and len(lines) == 4
    assert rodjit.load_sweep(tmp_path / "s.h5").status == "completed"


@pytest.mark.slow     # three real sweeps signalled and resumed (about a minute)
def test_sigint_at_any_moment_of_a_sweep_exits_130_or_0_with_a_usable_file(tmp_path):
    """A real sweep signalled at spread delays once its file exists (from mid-run to after
    its end, whatever the machine's load makes of them): each outcome is 0 (it had ended)
    or 130 with one line; the file is complete, or interrupted and resumable."""
    for k, delay in enumerate((0.0, 0.5, 3.0)):
        out = tmp_path / f"s{k}.h5"
        p = subprocess.Popen([sys.executable, "-m", "rodjit", "sweep", *ARGS, "-o", out.name],
                             cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True)
        try:
            deadline = time.monotonic() + 120
            while not out.exists() and p.poll() is None:
                assert time.monotonic() < deadline
                time.sleep(0.005)
            time.sleep(delay)
            p.send_signal(signal.SIGINT)
            stdout, err = p.communicate(timeout=120)
        finally:
            p.kill()
        assert p.returncode in (0, 130), err
        if p.returncode == 130:
            assert "interrupted by SIGINT" in one_line(err)
        else:
            assert err == ""
        if not out.exists():            # its creation was cut: removed
            assert p.returncode == 130
            continue
        table = rodjit.load_sweep(out)
        if table.status == "completed":
            assert table.counts["completed"] == 2
            assert stdout.startswith(f"{out.name}: sweep completed")
        else:
            assert table.status == "interrupted" and p.returncode == 130
            assert rodjit.sweep(output=out, resume=True, scheduler="inline").status == \
                "completed"


def test_a_signal_inside_llvmlites_callbacks_arrives_just_after_them():
    """A start-up signal handled while the interpreter runs llvmlite's Python code (the
    callbacks LLVM makes through ctypes while Numba compiles or loads a kernel, where an
    exception is printed with its traceback and dropped) raises Interrupted once outside
    it, instead of inside the callback.  The callback is imitated by a function whose code
    lives in llvmlite's binding package."""
    import llvmlite.binding.executionengine as engine

    from rodjit.driver import signals

    fake = os.path.join(os.path.dirname(engine.__file__), "executionengine.py")
    namespace = {"sys": sys}
    exec(compile("def callback(handler):\n    handler(15, sys._getframe())\n", fake, "exec"),
         namespace)
    old = signal.getsignal(signal.SIGALRM)
    try:
        namespace["callback"](signals.raise_interrupted)    # no exception inside it
        with pytest.raises(signals.Interrupted) as exc:
            deadline = time.monotonic() + 5.0
            while time.monotonic() < deadline:
                time.sleep(0.001)
        assert exc.value.signum == signal.SIGTERM
        assert not signals._PENDING
        assert signal.getsignal(signal.SIGALRM) == old        # put back as it was
        with pytest.raises(signals.Interrupted):          # outside llvmlite: at once
            signals.raise_interrupted(signal.SIGINT, sys._getframe())
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
        signals._PENDING.clear()
        signals._ALARM_BEFORE.clear()


def test_a_signal_inside_the_import_of_multiprocessing_is_not_taken_for_a_worker(monkeypatch):
    """A signal that lands while this process imports ``multiprocessing`` (found under load,
    at the command's start) meets the module half made, without ``parent_process``: the
    early handler must still say its one line and exit, not fail with a traceback."""
    import types

    from rodjit.driver import signals

    monkeypatch.setitem(sys.modules, "multiprocessing", types.ModuleType("multiprocessing"))
    assert signals.in_worker() is False
    monkeypatch.delitem(sys.modules, "multiprocessing")
    assert signals.in_worker() is False
