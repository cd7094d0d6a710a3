"""Shared helpers: small configurations, a subprocess runner for the CLI, file comparison."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

# the suite runs on the JIT, in this process and in the processes it starts; the loop
# compiled ahead of time is tested against it (tests/test_stepping_aot.py).  RODJIT_AOT=1
# runs the suite on the ahead-of-time loop where it applies.
os.environ.setdefault("RODJIT_AOT", "0")

import h5py
import numpy as np
import pytest

import rodjit

ROOT = Path(__file__).resolve().parent.parent


def quiet(**over):
    """A Config with outputs off unless asked (fast runs); dotted-key overrides.  The
    integrator is verlet with fixed-fraction steps (time.control = "cfl") unless asked:
    the cheap explicit baseline these tests measure their bounds on."""
    base = {"output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0,
            "time.integrator": "verlet", "time.control": "cfl"}
    base.update(over)
    return rodjit.Config().override(base)


# The compiled loops the suite's workers all need, compiled once into Numba's disk cache
# before they start: on a cold cache (a fresh clone, as on CI) every xdist worker would
# otherwise compile the same loops at the same time, each paying the whole cold compile.
# Two processes share the integrators, one per core; on a warm cache each only loads.
_WARM_SETS = (("verlet", "energy", "dop853"), ("semi-implicit", "dp54", "radau5"))
_WARM = """
import sys, warnings
warnings.simplefilter("ignore")
import rodjit
for name in sys.argv[1:]:
    over = {"output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0,
            "time.integrator": name, "time.t_end": 0.01}
    if name in ("verlet", "semi-implicit"):
        over["time.control"] = "cfl"
    cfg = rodjit.Config().override(over)
    rodjit.simulate(cfg)
    if name == "verlet":      # the sweeps' batch kernel too
        rodjit.sweep(cfg, {"rod.mu": [0.0, 1.0]}, jobs=1, scheduler="inline")
"""


def pytest_sessionstart(session):
    """On the xdist controller, before its workers start: fill Numba's disk cache with the
    loops of every integrator (``_WARM_SETS``), so that no two workers compile the same
    loop.  A failure here only costs the warm-up: the tests compile what they need."""
    if os.environ.get("PYTEST_XDIST_WORKER") or not getattr(session.config.option,
                                                            "numprocesses", None):
        return
    procs = [subprocess.Popen([sys.executable, "-c", _WARM, *names],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
             for names in _WARM_SETS]
    for proc in procs:
        try:
            proc.wait(timeout=900)
        except subprocess.TimeoutExpired:
            proc.kill()


@pytest.fixture
def jit_only(monkeypatch):
    """Runs on the JIT even under RODJIT_AOT=1: for tests of the JIT's own warm-up and
    disk cache, which the loop compiled ahead of time does not use."""
    from rodjit.stepping import aot

    monkeypatch.setattr(aot, "_EXT", [(None, None)])


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


@pytest.fixture
def small_config():
    """The default rod for one simulated second: contact, chattering episodes, one bounce."""
    return rodjit.Config().override({"time.t_end": 1.0})


@pytest.fixture
def many_calls(monkeypatch):
    """Cut runs into many short compiled calls, so a test can stop one anywhere."""
    import rodjit.driver.run as run_module

    # ten steps a call at N = 5: the default run's first second is some thirty calls
    monkeypatch.setattr(run_module, "NODE_STEPS_PER_CALL", 60)


def module_runs(cfg):
    """Module-scoped fixtures ``result`` (``simulate(cfg)``) and ``run_file`` (the same
    configuration streamed to a file), for a test module to bind:
    ``result, run_file = module_runs(CFG)``."""
    @pytest.fixture(scope="module")
    def result():
        return rodjit.simulate(cfg)

    @pytest.fixture(scope="module")
    def run_file(tmp_path_factory):
        path = tmp_path_factory.mktemp("run") / "run.h5"
        rodjit.run_to_file(cfg, path)
        return path

    return result, run_file


# SIGINT and SIGTERM as the worker process found them, before any test
_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_SESSION_HANDLERS = {s: signal.getsignal(s) for s in _SIGNALS}


@pytest.fixture(autouse=True)
def _session_signal_handlers():
    """Every test starts with the session's SIGINT and SIGTERM handlers, unblocked.  A
    command run in-process (CliRunner) ends the way a process that exits does: a sweep
    leaves the signals recorded (``signals.hold_on_exit``), the entry point ignores and
    blocks them (``entry._finish``); a later test in the same worker that delivers SIGINT
    would otherwise depend on which files that worker ran before it."""
    for s, handler in _SESSION_HANDLERS.items():
        signal.signal(s, handler)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, set(_SIGNALS))
    yield


def run_simulated(args, **kw) -> subprocess.CompletedProcess:
    """``python ARGS`` in a fresh interpreter with numba-cuda's simulator chosen (it must be
    before ``numba.cuda`` is first imported, and other tests import it for real)."""
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1", PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                          timeout=900, **kw)


def simulated_json(script: str):
    """The JSON a ``script`` prints last, run under the GPU simulator (``run_simulated``)."""
    p = run_simulated(["-c", script])
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


def simulated_sweeps(setup: str, grid: dict, columns) -> dict:
    """The same sweep on the GPU engine (under the simulator) and inline on the CPU:
    ``setup`` is Python that defines ``cfg``; ``{column: [gpu values, cpu values]}``."""
    return simulated_json(f"""
import json
import rodjit
{setup}
gpu = rodjit.sweep(cfg, {grid!r}, device="cuda", progress=False)
cpu = rodjit.sweep(cfg, {grid!r}, scheduler="inline", progress=False)
print(json.dumps({{k: [gpu[k].tolist(), cpu[k].tolist()] for k in {tuple(columns)!r}}}))
""")


def rodjit_cli(*args, cwd=None, timeout=300, limit: int | None = None,
               code: str | None = None) -> subprocess.CompletedProcess:
    """Run ``rodjit ARGS`` in a fresh interpreter (as a user would).  ``limit``: its files
    may not grow past that many bytes (RLIMIT_FSIZE, SIGXFSZ ignored: a write past it
    fails with EFBIG).  ``code``: Python run first in that interpreter (a test's fault
    injection), then the command line."""
    head = [sys.executable, "-m", "rodjit"] if code is None else [
        sys.executable, "-c", f"{code}\nimport sys\nsys.argv[0] = 'rodjit'\n"
                              f"from rodjit.entry import main\nmain()"]
    return subprocess.run([*head, *map(str, args)], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, preexec_fn=None if limit is None else
                          lambda: _limit_files(limit))


def _limit_files(limit: int) -> None:
    import resource
    import signal

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))


def datasets(path) -> dict[str, np.ndarray]:
    """Every dataset of an HDF5 file by path (checkpoint slots excluded, see ``final_state``)."""
    from rodjit.output import hdf5

    out = {}
    with hdf5.open_file(path) as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and not name.startswith("checkpoint"):
                out[name] = obj[()]
        f.visititems(visit)
    return out


def final_state(path) -> dict[str, np.ndarray]:
    """The stepper arrays of the file's valid checkpoint (what a resume continues from)."""
    from rodjit.output import hdf5

    with hdf5.open_file(path) as f:
        ck = hdf5.read_checkpoint(f)
    return {k: ck[k] for k in ("state", "clock", "count", "ev", "sstats")} | {
        "lengths": np.array(list(ck["lengths"].values()))}


def assert_same_files(a, b) -> None:
    """Same datasets and the same final checkpoint, bit for bit (NaN equal to NaN)."""
    da, db = datasets(a), datasets(b)
    assert sorted(da) == sorted(db)
    for name in db:
        assert da[name].dtype == db[name].dtype, name
        assert np.array_equal(da[name], db[name], equal_nan=da[name].dtype.kind == "f"), name
    sa, sb = final_state(a), final_state(b)
    for name in sb:
        assert np.array_equal(sa[name], sb[name], equal_nan=True), name


# the columns of a sweep table that time a point rather than compute it
SWEEP_TIMINGS = ("wall_time", "compile_time", "run_time")


def same_table(a, b) -> None:
    """Two sweep tables have the same points and results, timings apart, and the same
    bounce rows (NaN equal to NaN)."""
    assert list(a.columns) == list(b.columns)
    for name in a.columns:
        if name in SWEEP_TIMINGS:
            continue
        x, y = np.asarray(a.columns[name]), np.asarray(b.columns[name])
        if x.dtype.kind == "f":
            assert np.array_equal(x, y, equal_nan=True), name
        else:
            assert list(x) == list(y), name
    ra, rb = a.bounce_rows(), b.bounce_rows()
    assert list(ra) == list(rb)
    for name in ra:
        assert np.array_equal(ra[name], rb[name], equal_nan=ra[name].dtype.kind == "f"), name


def one_line(err: str) -> str:
    """The one line of a command's stderr (asserting there is one, and no Traceback)."""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err and "Exception ignored" not in err, err
    return lines[0]


def assert_resume_is_bit_identical(cfg, max_steps) -> None:
    """A run paused after ``max_steps`` steps and resumed from its checkpoint ends in the
    uninterrupted run's state, step counts, dissipated energy and scheme counters, bit for
    bit."""
    from rodjit.driver.run import Run
    from rodjit.records.result import MemorySink
    from rodjit.stepping import layout as L
    one = Run(cfg)
    one.start(MemorySink())
    while one.advance(MemorySink()) != L.DONE:
        pass
    first = Run(cfg)
    first.start(MemorySink())
    first.advance(MemorySink(), max_steps=max_steps)
    assert first.t < cfg.time.t_end
    second = Run.from_checkpoint(cfg, first.checkpoint())
    while second.advance(MemorySink()) != L.DONE:
        pass
    np.testing.assert_array_equal(second.arrays.state, one.arrays.state)
    np.testing.assert_array_equal(second.arrays.sstats, one.arrays.sstats)
    assert second.steps == one.steps and second.rejected == one.rejected
    assert second.dissipated == one.dissipated


def trial_step(cfg, step, dt):
    """One trial step of the scheme kernel ``step`` from a started run's initial state:
    ``(run, trial, result)``; the run's state must be left untouched by it."""
    from rodjit.driver.run import Run
    from rodjit.records.result import MemorySink
    run = Run(cfg)
    run.start(MemorySink())
    scheme, _, system, rod, floor, _ = run._args()
    a = run.arrays
    before = a.state.copy()
    trial = np.zeros_like(a.state)
    r = step(scheme, system, rod, floor, a.state[0], a.state[1], a.state[2],
             trial[0], trial[1], trial[2], a.work, a.sstats, dt)
    np.testing.assert_array_equal(a.state, before)
    return run, trial, r
