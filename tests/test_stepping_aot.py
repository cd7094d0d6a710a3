"""The loop compiled ahead of time (``stepping.aot``): the same bits as the JIT, resumable
across the two, used only where its record matches, and releasing the GIL.

The suite runs on the JIT (conftest sets ``RODJIT_AOT=0``); these tests build the
extension into a temporary directory and point the loader at it."""
from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from conftest import assert_same_files

import rodjit
from rodjit.driver import run as run_module
from rodjit.driver.run import Run
from rodjit.driver.setup import parameters
from rodjit.records.result import MemorySink
from rodjit.stepping import aot
from rodjit.stepping import layout as L
from rodjit.stepping.arrays import RunArrays
from rodjit.stepping.registry import NAMES, SCHEMES

# a simulated second and a half: flight, contact, one bounce
SHORT = {"time.t_end": 1.5}


def _scheme(name: str) -> dict:
    return {"time.integrator": name}


# the runs the install compiles ahead of time: the default run's types with each of the
# registry's ``aot`` schemes (setup.py)
def _install_runs() -> list:
    return [parameters(rodjit.Config().override(_scheme(n))) for n in aot.schemes()]


# paper-mu0 on dop853 and paper-mu100 on radau5, what ``time.integrator = "auto"`` chooses
MU0 = rodjit.load_preset("paper-mu0").override({**SHORT, **_scheme("dop853")})
MU100 = rodjit.load_preset("paper-mu100").override({**SHORT, **_scheme("radau5")})


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """``(module, {key: suffix}, directory)`` of an extension built as the install builds
    it."""
    directory = tmp_path_factory.mktemp("aot")
    path = aot.build(directory, _install_runs())
    spec = importlib.util.spec_from_file_location(aot.EXTENSION, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    record = aot.extension_record(directory)
    tags = {tuple((c, tuple(t)) for c, t in k): suffix for suffix, k in record["entries"]}
    return module, tags, directory


@pytest.fixture
def use(monkeypatch):
    """``use(built)`` makes runs find that extension; ``use(None)``: none (the JIT)."""
    def _use(ext):
        monkeypatch.setattr(aot, "_EXT", [ext[:2] if ext is not None else (None, {})])
    return _use


def _assert_same_results(a, b):
    for name in ("t", "u", "v", "u_final", "v_final"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for table in ("diagnostics", "episodes", "bounces"):
        ta, tb = getattr(a, table), getattr(b, table)
        assert sorted(ta) == sorted(tb)
        for col in tb:
            assert np.array_equal(ta[col], tb[col], equal_nan=True), (table, col)
    assert (a.t_final, a.energy0, a.dissipated) == (b.t_final, b.energy0, b.dissipated)
    assert a.stats["steps"] == b.stats["steps"] and a.stats["rejected_steps"] == b.stats[
        "rejected_steps"]


# ---- the parts that need no compiler -----------------------------------------------------

@pytest.mark.parametrize("integrator", sorted(NAMES))
def test_the_wrappers_rebuild_every_schemes_parameters(integrator):
    """``pack`` and the generated wrappers round-trip each parameter tuple: same classes,
    same field values, same Python field types (what fixes the compiled signature)."""
    args = Run(rodjit.Config().override({"time.integrator": integrator}))._args()
    source, glob = aot.wrapper_source(args, "x")
    seen = {}
    glob.update(_save_thread=lambda: "token", _restore_thread=lambda ts: seen.setdefault(
        "restored", ts))
    passed = {}
    for name in aot.ENTRIES:
        glob[f"_{name}"] = lambda *a, _n=name: (seen.setdefault(_n, a[:6]),
                                                passed.setdefault(_n, a[6:])) and 7
    exec(source, glob)
    p = aot.pack(args)
    assert p.dtype == np.float64 and p.ndim == 1
    for name, (_, extra) in aot.ENTRIES.items():
        exported = aot._expand(extra)
        assert glob[f"{name}_x"](p, *range(len(exported))) == 7
        # the exported function takes the run's arrays one by one, and the loop gets them
        # as its one RunArrays, field for field
        values = dict(zip((a for a, _ in exported), range(len(exported))))
        got = passed[name]
        assert len(got) == len(extra)
        for a, value in zip(extra, got):
            if a == aot.ARRAYS:
                assert isinstance(value, RunArrays)
                assert value == tuple(values[f] for f in RunArrays._fields)
            else:
                assert value == values[a[0]]
        rebuilt = seen[name]
        for a, b in zip(rebuilt, args):
            assert type(a) is type(b)
            # ints and bools come back as NumPy scalars here (compiled code gives them
            # their Numba types); the values must be the same
            assert tuple(a) == tuple(b)
    assert seen["restored"] == "token"


def test_the_key_is_made_of_types_not_values():
    run = Run(rodjit.Config())
    assert aot.key(run._args()) == tuple(
        (f"{type(p).__module__}.{type(p).__qualname__}", tuple(type(x).__name__ for x in p))
        for p in run._args())
    assert run._compiled_key() == aot.key(run._args())
    other = Run(rodjit.Config().override({"time.integrator": "dp54"}))
    assert aot.key(other._args()) != aot.key(run._args())
    # values do not matter, types do (paper-mu100 with the default's integrator)
    mu100 = rodjit.load_preset("paper-mu100").override({"time.integrator": "dop853"})
    assert aot.key(Run(mu100)._args()) == aot.key(run._args())
    # a field of another type makes another key, also after the first was seen
    args = run._args()
    field = args[0]._fields[0]
    retyped = (args[0]._replace(**{field: int(getattr(args[0], field) > 0)}),) + args[1:]
    assert aot.key(retyped) != aot.key(args)
    assert aot.key(retyped)[0][1][0] == "int" and aot.key(args)[0][1][0] == "float"


def test_a_field_without_a_compiled_form_is_refused():
    run = Run(rodjit.Config())
    scheme, *rest = run._args()
    odd = scheme._replace(rtol=np.float32(1e-6))
    with pytest.raises(TypeError, match="float32"):
        aot.pack((odd, *rest))


def test_the_record_decides_its_use(monkeypatch):
    record = {"entries": [], "sources": aot.SOURCES_DIGEST, **aot._host()}
    assert aot._usable(record)
    # a record of one entry set (an extension of one scheme's types, before the entries
    # were named per scheme) is not this module's
    old = {k: v for k, v in record.items() if k != "entries"}
    assert not aot._usable({**old, "key": []})
    for field, other in (("sources", "0" * 40), ("numba", "0.0"), ("llvmlite", "0.0"),
                         ("cpu", "i486"), ("python", "cpython-20")):
        assert not aot._usable({**record, field: other}), field
    assert not aot._usable(None)


def test_no_record_no_extension_and_the_switch(monkeypatch, tmp_path):
    monkeypatch.setattr(aot, "_EXT", [])
    monkeypatch.setattr(aot, "extension_record", lambda directory=None: None)
    assert aot.loop_for(Run(rodjit.Config())._args()) is None
    for off in ("0", "off", "False"):
        monkeypatch.setattr(aot, "_EXT", [])
        monkeypatch.setenv("RODJIT_AOT", off)
        monkeypatch.setattr(aot, "extension_record", lambda directory=None: {
            "entries": [], "sources": aot.SOURCES_DIGEST, **aot._host()})
        assert aot._extension() == (None, {})


def test_a_failed_build_leaves_no_record(monkeypatch, tmp_path):
    from numba.pycc import CC

    def fail(self):
        raise RuntimeError("no C compiler")

    (tmp_path / aot.RECORD).write_text("{}")         # a record of an earlier build
    monkeypatch.setattr(CC, "compile", fail)
    with pytest.raises(RuntimeError, match="no C compiler"):
        aot.build(tmp_path, [Run(rodjit.Config())._args()])
    assert aot.extension_record(tmp_path) is None


def test_numba_pycc_still_builds_the_loop(built):
    """The ahead-of-time loop is built with ``numba.pycc``, marked for deprecation by Numba:
    this fails the day it is gone or stops building the loop (docs/getting-started.md has
    the plan for that day)."""
    from numba.pycc import CC

    assert callable(CC.export) and callable(CC.compile)
    module, tags, directory = built
    assert aot.reusable(directory) is not None
    assert all(callable(getattr(module, f"{name}_{suffix}")) for name in aot.ENTRIES
               for suffix in tags.values())


def test_an_extension_is_reused_only_where_its_record_and_file_say_so(tmp_path):
    """``reusable``: what an install keeps instead of compiling again: the extension file
    of this interpreter beside a record of these sources and this host."""
    import sysconfig

    so = tmp_path / (aot.EXTENSION + sysconfig.get_config_var("EXT_SUFFIX"))
    record = {"entries": [], "sources": aot.SOURCES_DIGEST, **aot._host()}
    assert aot.reusable(tmp_path) is None                       # nothing there
    (tmp_path / aot.RECORD).write_text(json.dumps(record))
    assert aot.reusable(tmp_path) is None                       # a record, no file
    so.write_bytes(b"")
    assert aot.reusable(tmp_path) == so
    for field, other in (("sources", "0" * 40), ("numba", "0.0"), ("cpu", "i486")):
        (tmp_path / aot.RECORD).write_text(json.dumps({**record, field: other}))
        assert aot.reusable(tmp_path) is None, field


@pytest.mark.slow     # a wheel built from a copy of the checkout (the compile kept)
def test_an_install_keeps_the_extension_built_for_its_sources(built, tmp_path):
    """An install of a checkout whose source tree holds the extension built for its sources
    (an editable install made it) keeps it: no second compile of the loop."""
    import shutil
    import subprocess
    import sys

    import setuptools

    if int(setuptools.__version__.split(".")[0]) < 77:
        pytest.skip("the build needs setuptools >= 77 in this environment")
    from pathlib import Path

    _, _, directory = built
    path = aot.reusable(directory)
    assert path is not None
    root = Path(__file__).resolve().parents[1]
    listed = subprocess.run(["git", "ls-files"], cwd=root, capture_output=True, text=True)
    if listed.returncode != 0:
        pytest.skip("not a git checkout")
    src = tmp_path / "src"
    for name in listed.stdout.split():
        if (root / name).is_file():
            (src / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(root / name, src / name)
    shutil.copy2(path, src / "rodjit" / "stepping" / path.name)
    shutil.copy2(directory / aot.RECORD, src / "rodjit" / "stepping" / aot.RECORD)
    out = subprocess.run([sys.executable, "-m", "pip", "wheel", "-v", "--no-deps",
                          "--no-build-isolation", "-w", str(tmp_path / "dist"), str(src)],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    assert "the ahead-of-time loop built for these sources is kept" in out.stdout + out.stderr
    import zipfile

    wheel = next((tmp_path / "dist").glob("rodjit-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert f"rodjit/stepping/{path.name}" in names and f"rodjit/stepping/{aot.RECORD}" in names


# ---- the built extension ------------------------------------------------------------------

def test_the_build_records_what_it_is_tied_to(built):
    _, tags, directory = built
    record = json.loads((directory / aot.RECORD).read_text())
    assert record["sources"] == aot.SOURCES_DIGEST
    assert aot._usable(record)
    # one entry set per scheme of the registry's aot rows, for the default run's types
    assert aot.schemes() == tuple(s.name for s in SCHEMES if s.aot)
    assert tags == {aot.key(parameters(rodjit.Config().override(_scheme(n)))): n
                    for n in aot.schemes()}


def test_the_integrators_built_are_the_ones_auto_chooses_from():
    """The install builds dop853 (μ = 0) and radau5 (μ > 0), not the others."""
    assert aot.schemes() == ("dop853", "radau5")


@pytest.mark.parametrize("cfg", [
    MU0,
    MU100,
    rodjit.Config().override({**SHORT, **_scheme("dop853"), "time.dt": 2e-4}),  # fixed steps
    rodjit.Config().override({**SHORT, **_scheme("radau5"), "rod.N": 40,
                              "floor.kappa_b": 3e4}),
], ids=["paper-mu0-dop853", "paper-mu100-radau5", "fixed-dt-dop853",
        "N40-stiff-floor-radau5"])
def test_the_ahead_of_time_loop_gives_the_jits_bits(built, use, cfg):
    use(built)
    run = Run(cfg)
    assert run._aot is not None
    a = rodjit.simulate(cfg)
    assert a.stats["compile_time"] < 0.5          # nothing compiled
    use(None)
    assert Run(cfg)._aot is None
    b = rodjit.simulate(cfg)
    _assert_same_results(a, b)


def test_each_run_takes_the_entries_of_its_scheme_and_others_the_jit(built, use):
    module, _, _ = built
    use(built)
    for name in aot.schemes():
        for base in (rodjit.Config(), rodjit.load_preset("paper-mu100")):
            loop = Run(base.override(_scheme(name)))._aot
            assert loop is not None
            assert loop._start is getattr(module, f"start_{name}")
            assert loop._advance is getattr(module, f"advance_{name}")
    for name in ("energy", "verlet", "dp54"):
        assert Run(rodjit.Config().override(_scheme(name)))._aot is None
        assert aot.batch_for(parameters(rodjit.Config().override(_scheme(name)))) is None


@pytest.mark.parametrize("cfg", [MU0, MU100], ids=["dop853", "radau5"])
def test_a_run_paused_on_one_path_resumes_on_the_other_bit_for_bit(built, use, cfg):
    use(None)
    whole = rodjit.simulate(cfg)
    for first, second in ((built, None), (None, built)):
        use(first)
        run = Run(cfg)
        sink = MemorySink()
        run.start(sink)
        run.advance(sink, max_steps=whole.stats["steps"] // 2)
        assert not np.isclose(run.t, cfg.time.t_end)
        ck = run.checkpoint()
        use(second)
        resumed = Run.from_checkpoint(cfg, ck)
        assert (resumed._aot is None) == (second is None)
        while resumed.advance(sink) != L.DONE:
            pass
        np.testing.assert_array_equal(resumed.arrays.state[:2], np.stack([whole.u_final,
                                                                   whole.v_final]))
        assert resumed.steps == whole.stats["steps"]
        assert resumed.dissipated == whole.dissipated


def test_the_loop_releases_the_gil_while_it_computes(built, use, monkeypatch):
    """A Python thread keeps running during a long call (as with the JIT's ``nogil``): it
    wakes from 10 ms sleeps throughout the call, which it could not while the GIL is held
    (each wake-up needs it)."""
    use(built)
    monkeypatch.setattr(run_module, "NODE_STEPS_PER_CALL", 10**12)
    # radau5: dop853 fills the event buffers in a tenth of a second here
    run = Run(rodjit.Config().override({**_scheme("radau5"), "time.t_end": 200.0,
                                        "output.snapshot_interval": 0.0,
                                        "output.diagnostics_interval": 0.0}))
    assert run._aot is not None
    run.start(None)
    worker = threading.Thread(target=run.compute)
    wakes = 0
    t0 = time.perf_counter()
    worker.start()
    while worker.is_alive():
        time.sleep(0.01)
        wakes += 1
    worker.join()
    took = time.perf_counter() - t0
    assert run.t > 50.0 and took > 0.2, (run.t, took)   # (until the event buffers fill)
    # with the GIL held through the call: one or two wake-ups, whatever its length
    assert wakes > 0.2 * took / 0.01, (wakes, took)


def _without_numba(module, tags) -> str:
    """Python that makes an import of Numba or llvmlite end the process with that message,
    then points the loader at the built extension ``module`` (its entries' suffixes by key,
    ``tags``): the start of a child process that must run on the extension alone."""
    return ("import importlib.abc, importlib.util, sys\n"
            "class Refuse(importlib.abc.MetaPathFinder):\n"
            "    def find_spec(self, name, path=None, target=None):\n"
            "        if name.partition('.')[0] in ('numba', 'llvmlite'):\n"
            "            raise SystemExit(f'{name} was imported')\n"
            "sys.meta_path.insert(0, Refuse())\n"
            "from rodjit.stepping import aot\n"
            "spec = importlib.util.spec_from_file_location(aot.EXTENSION, "
            f"{str(module.__file__)!r})\n"
            "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
            f"aot._EXT[:] = [(m, {tags!r})]\n")


# ``rodjit run`` of paper-mu0 on dop853 (what the default chooses), from "-o"
_COMMAND = ["run", "paper-mu0", "--set", "time.integrator=dop853", "--t-end", "1.5", "-o"]


def test_the_command_never_imports_numba(built, tmp_path):
    """``rodjit run`` of paper-mu0 on dop853 on the extension: Numba and llvmlite are never
    imported (nothing is compiled or loaded from the JIT's cache), and the file is the
    JIT's, bit for bit."""
    module, tags, directory = built
    code = _without_numba(module, tags) + (
        f"sys.argv = ['rodjit', *{_COMMAND!r}, 'aot.h5']\n"
        "from rodjit.entry import main\n"
        "main()\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path,
                          env={**os.environ, "RODJIT_AOT": "1"},
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    jit = subprocess.run([sys.executable, "-m", "rodjit", *_COMMAND, "jit.h5"],
                         cwd=tmp_path, env={**os.environ, "RODJIT_AOT": "0"},
                         capture_output=True, text=True, timeout=600)
    assert jit.returncode == 0, jit.stderr
    assert_same_files(tmp_path / "aot.h5", tmp_path / "jit.h5")


def test_a_run_on_the_ahead_of_time_loop_gets_no_compiling_notice(built, use):
    from rodjit.driver.progress import kernels_cold

    use(built)
    assert kernels_cold(MU0) is False
    assert kernels_cold(MU100) is False
    # any other run: the disk cache decides, as without a configuration
    assert kernels_cold(rodjit.Config().override(_scheme("energy"))) == kernels_cold()


# ---- the sweeps' batch kernel ------------------------------------------------------------

_GRID = {"rod.mu": [0.0, 40.0, 100.0], "floor.beta": [0.03, 0.1]}


def test_the_ahead_of_time_batch_kernel_gives_the_jits_table(built, use, monkeypatch):
    """A sweep's batches on the extension (paper-mu100 on radau5) and on the JIT: the same
    table to the bit, timings apart; the batches took the extension's entry."""
    from test_sweep_driver import same_values

    cfg = MU100
    use(built)
    assert aot.batch_for(run_module.parameters(cfg)) is not None
    taken = []
    real = aot.batch_for
    monkeypatch.setattr(aot, "batch_for", lambda args: taken.append(real(args)) or taken[-1])
    a = rodjit.sweep(cfg, _GRID, scheduler="inline")
    monkeypatch.setattr(aot, "batch_for", real)
    assert taken and all(t is not None for t in taken)
    use(None)
    assert aot.batch_for(run_module.parameters(cfg)) is None
    b = rodjit.sweep(cfg, _GRID, scheduler="inline")
    assert a.status == b.status == "completed"
    same_values(a, b)
    for k in range(len(a)):
        ta, tb = a.bounces(k), b.bounces(k)
        assert sorted(ta) == sorted(tb)
        for col in tb:
            assert np.array_equal(ta[col], tb[col], equal_nan=True), (k, col)


def test_a_sweep_on_the_extension_never_imports_numba(built, tmp_path):
    """A sweep of paper-mu100 on radau5, batches and file included, on the extension: Numba
    and llvmlite are never imported (a worker that loaded them would spend half a second on
    it before its first point)."""
    module, tags, directory = built
    code = _without_numba(module, tags) + (
        "import rodjit\n"
        "from rodjit.sweeps.workers import start_worker\n"
        "cfg = rodjit.load_preset('paper-mu100').override({'time.t_end': 1.5,\n"
        "                                                  'time.integrator': 'radau5'})\n"
        "info = start_worker(cfg, batched=True)\n"
        "t = rodjit.sweep(cfg, {'rod.mu': [0.0, 50.0]}, scheduler='inline', output='s.h5')\n"
        "print(t.status, t.counts['completed'], info['numba_threads'])\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path,
                          env={**os.environ, "RODJIT_AOT": "1", "NUMBA_NUM_THREADS": "3"},
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    # the worker's thread count told from the environment, as Numba would read it
    assert done.stdout.split() == ["completed", "2", "3"]
