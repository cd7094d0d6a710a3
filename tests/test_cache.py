"""Compiled code is cached on disk: a second process starts without compiling.

The test runs fresh interpreters against its own empty NUMBA_CACHE_DIR, so it neither
depends on nor disturbs the cache next to the sources.  (benchmarks/bench_cache.py times
the same thing; tests/test_cache_foreign_law.py covers an index holding a foreign law.)
"""
import json
import os
import subprocess
import sys
import textwrap

import pytest

# One short run per integrator, then the cache statistics of the kernels Python calls
# (``start`` and ``advance`` contain every other kernel of a run, inlined or linked).
PROBE = textwrap.dedent("""
    import json, sys
    import rodjit
    from rodjit.stepping import loop
    for integ in sys.argv[1:]:
        cfg = rodjit.Config().override({"time.integrator": integ, "time.t_end": 0.05})
        rodjit.simulate(cfg)
    stats = {name: {"hits": sum(f.stats.cache_hits.values()),
                    "misses": sum(f.stats.cache_misses.values())}
             for name, f in (("start", loop.start), ("advance", loop.advance))}
    print(json.dumps(stats))
""")


def _probe(cache_dir, *args):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_dir))
    env.pop("NUMBA_DISABLE_JIT", None)
    out = subprocess.run([sys.executable, "-c", PROBE, *args], env=env, capture_output=True,
                         text=True, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.slow   # compiles every kernel cold in fresh processes: minutes
def test_a_second_process_loads_every_kernel_from_the_cache(tmp_path):
    cold = _probe(tmp_path, "verlet", "semi-implicit")
    assert all(s["misses"] == 2 and s["hits"] == 0 for s in cold.values()), cold
    warm = _probe(tmp_path, "verlet", "semi-implicit")
    assert all(s["misses"] == 0 and s["hits"] == 2 for s in warm.values()), warm
    # the stale-cache guard finds these files (Numba names the directories
    # <dir>_<sha1 of its path> inside NUMBA_CACHE_DIR)
    code = ("import rodjit._jit as j, pathlib; root = pathlib.Path(j.__file__).resolve().parent; "
            "print(sum(len(list(d.glob('*.nbi'))) for d in j._cache_dirs(root) "
            f"if str(d).startswith({str(tmp_path)!r})))")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    found = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, check=True).stdout
    assert int(found) >= 10



# Every function Numba compiles for one short run, from a cold cache: rodjit's kernels with
# the signatures they were compiled for, and whether the compile made a C-ABI wrapper.
COMPILES = textwrap.dedent("""
    import json, sys
    from numba.core import event
    compiled = {}
    class Compiles(event.Listener):
        def on_start(self, ev):
            pass
        def on_end(self, ev):
            d = ev.data["dispatcher"]
            if d.py_func.__module__.startswith("rodjit"):
                args = tuple(ev.data["args"])
                lib = d.overloads[args].library
                cfunc = d.overloads[args].fndesc.llvm_cfunc_wrapper_name
                entry = compiled.setdefault(id(d), [d.py_func.__qualname__, [], False])
                entry[1].append(str(args))
                entry[2] |= any(f.name == cfunc for f in lib.get_defined_functions())
    event.register("numba:compile", Compiles())
    import rodjit
    rodjit.simulate(rodjit.Config().override({"time.integrator": sys.argv[1],
                                              "time.t_end": 0.05}))
    print(json.dumps(list(compiled.values())))
""")


@pytest.mark.slow   # a cold compile of every kernel per integrator: minutes
@pytest.mark.parametrize("integrator", ["energy", "dp54", "verlet", "radau5", "dop853"])
def test_a_cold_run_compiles_each_kernel_once(tmp_path, integrator):
    """A kernel called with a literal flag at one call site and another value (or a
    run-time bool) at the next compiles twice, each copy optimised again in every caller
    (rodjit._jit: literal flags); a run compiles each of rodjit's functions for one
    signature, and none with the C-ABI wrapper nothing calls."""
    # the JIT, also for the integrators the install compiles ahead of time
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), RODJIT_AOT="0")
    env.pop("NUMBA_DISABLE_JIT", None)
    out = subprocess.run([sys.executable, "-c", COMPILES, integrator], env=env,
                         capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    compiled = json.loads(out.stdout.strip().splitlines()[-1])
    assert len(compiled) > 20, compiled   # the events were seen
    twice = {name: sigs for name, sigs, _ in compiled if len(sigs) > 1}
    # deliberate: the energy step's two residual passes, one compile per literal ``jac``
    passes = twice.pop("_evaluate", [])
    assert len(passes) in (0, 2) and all("Literal[bool]" in sig for sig in passes), passes
    assert not twice, twice
    assert not [name for name, _, cfunc in compiled if cfunc]


def _fresh_kernel(tmp_path, name):
    """A cached njit function in a module of its own (so Numba has a cache to save to)."""
    import importlib
    import sys

    (tmp_path / f"{name}.py").write_text(
        "import numba\n\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n")
    sys.path.insert(0, str(tmp_path))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(tmp_path))


def test_a_kernel_whose_cache_the_disk_refuses_still_runs(tmp_path, monkeypatch):
    """A full disk or a file-size limit on Numba's cache does not fail the call that compiled
    the kernel (Numba raises the save's OSError out of it); other errors still surface."""
    import errno

    from numba.core import caching

    import rodjit._jit  # noqa: F401  (installs the tolerant save)

    def refuse(self, sig, data):
        raise OSError(errno.EFBIG, "File too large")

    monkeypatch.setattr(caching.Cache, "_save_overload", refuse)
    assert _fresh_kernel(tmp_path, "rodjit_refused_cache_kernel").twice(21) == 42

    def broken(self, sig, data):
        raise OSError(errno.EBADF, "Bad file descriptor")

    monkeypatch.setattr(caching.Cache, "_save_overload", broken)
    with pytest.raises(OSError, match="Bad file descriptor"):
        _fresh_kernel(tmp_path, "rodjit_broken_cache_kernel").twice(21)
