"""Kernels are made on first use (rodjit._jit.Kernel): a process that compiles nothing
never imports Numba, and whoever imports Numba, rodjit's overloads are there for it."""
import os
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from rodjit import _jit
from rodjit.kernels import forces


def _python(code: str, **env) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)],
                          env={**os.environ, **env}, capture_output=True, text=True,
                          timeout=900)


def test_reading_files_and_the_command_line_never_import_numba(tmp_path):
    """Import of the package and of the command line, a configuration, a run file read
    back, its summary: nothing compiled, so no Numba."""
    import rodjit
    path = tmp_path / "run.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.05}), path)
    done = _python(f"""
        import sys
        import rodjit, rodjit.cli
        assert rodjit.load_preset("paper-mu100").rod.mu == 100
        res = rodjit.load_file({str(path)!r})
        assert res.status == "completed" and len(res.t) > 1
        assert res.energy_error() < 1e-3 and "restitution" in res.report()
        print(sorted(m for m in sys.modules if m.partition(".")[0] in ("numba", "llvmlite")))
        """)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_numba_imported_after_rodjit_finds_the_overloads():
    """A user's own Numba function that calls rodjit's generic law functions compiles in a
    fresh process whether Numba was imported before rodjit or after it (the import hook
    registers rodjit's overloads as Numba loads)."""
    body = """
        @numba.njit
        def f(e, p):
            return value(e, p) + deriv(e, p)

        p = AikiKosugiRod(100.0)
        assert f(-0.2, p) == value(-0.2, p) + deriv(-0.2, p), f(-0.2, p)
        print("ok")
        """
    after = "from rodjit.laws import AikiKosugiRod, deriv, value\nimport numba\n"
    before = "import numba\nfrom rodjit.laws import AikiKosugiRod, deriv, value\n"
    for head in (after, before):
        done = _python(head + textwrap.dedent(body))
        assert done.returncode == 0 and done.stdout.strip() == "ok", (head, done.stderr)


def test_a_kernel_is_numbas_dispatcher_once_used():
    v = np.linspace(0.0, 1.0, 6)
    assert forces.momentum(v, 0.2) == forces.momentum.dispatcher(v, 0.2)
    assert forces.momentum.signatures            # the dispatcher's attributes
    assert forces.momentum.py_func.__name__ == "momentum" == forces.momentum.__name__
    from numba.core import types

    assert forces.momentum._numba_type_ == types.Dispatcher(forces.momentum.dispatcher)
    assert _jit.python_function(forces.momentum) is forces.momentum.py_func
    assert _jit.JIT_OPTIONS["cache"] and _jit.JIT_OPTIONS["error_model"] == "numpy"
    assert _jit.STEP_JIT_OPTIONS.items() >= _jit.JIT_OPTIONS.items()


def test_a_kernels_entry_point_is_the_compiled_function_for_those_types():
    """``Kernel.entry_point``: the same values as the dispatcher's call, one compiled
    function per argument types (compiled on demand), kept by the dispatcher."""
    v = np.linspace(0.0, 1.0, 6)
    entry = forces.momentum.entry_point((v, 0.2))
    assert entry is forces.momentum.entry_point((v.copy(), 0.7))   # types, not values
    assert entry(v, 0.2) == forces.momentum(v, 0.2)
    assert entry is not forces.momentum.dispatcher
    v32 = v.astype(np.float32)
    other = forces.momentum.entry_point((v32, 0.2))               # compiled now
    assert other is not entry and other(v32, 0.2) == forces.momentum(v32, 0.2)


def test_a_kernel_pickles_by_name_without_loading_numba():
    assert pickle.loads(pickle.dumps(forces.accel)) is forces.accel
    done = _python("""
        import pickle, sys
        from rodjit.kernels import forces
        blob = pickle.dumps(forces.accel)
        assert pickle.loads(blob) is forces.accel
        print("numba" in sys.modules)
        """)
    assert done.returncode == 0 and done.stdout.strip() == "False", done.stderr


def test_kernels_run_as_python_with_the_jit_disabled():
    done = _python("""
        import numpy as np
        from rodjit.kernels import forces
        from rodjit.laws import AikiKosugiRod, value
        v = np.linspace(0.0, 1.0, 6)
        assert forces.momentum.dispatcher is forces.momentum.py_func
        assert forces.momentum.entry_point((v, 0.2)) is forces.momentum.py_func
        print(forces.momentum(v, 0.2) == forces.momentum.py_func(v, 0.2),
              value(-0.2, AikiKosugiRod(100.0)) < 0)
        """, NUMBA_DISABLE_JIT="1")
    assert done.returncode == 0 and done.stdout.split() == ["True", "True"], done.stderr


@pytest.mark.slow
def test_a_law_of_a_fresh_process_compiles_inside_the_loop():
    """The whole chain in a process whose first compile is the run's: kernels, overloads
    and intrinsics registered on demand (the default on the JIT)."""
    done = _python("""
        import sys, rodjit
        assert "numba" not in sys.modules
        res = rodjit.simulate(rodjit.Config().override({"time.t_end": 0.3}))
        print(res.status, "numba" in sys.modules)
        """, RODJIT_AOT="0")
    assert done.returncode == 0 and done.stdout.split() == ["completed", "True"], done.stderr
