"""Every GPU kernel compiles to PTX for sm_90, without a GPU: the real compile of what the
simulator runs as Python (tests/test_gpu_sim.py), where code a GPU cannot run (an
allocation, a NumPy call numba-cuda does not lower, a call it cannot type) fails.

numba-cuda compiles the kernel's device functions for the current GPU's compute
capability, which needs a driver even inside ``compile_ptx``; ``rodjit.gpu.kernel
.compile_ptx`` answers that question with the target's (``_compute_capability``), so the
whole call tree, the CPU's own loop retargeted (``rodjit.gpu.retarget``), is compiled here.
"""
from __future__ import annotations

import os

import pytest

from rodjit.config import Config
from rodjit.driver.run import parameters

if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1":
    pytest.skip("NUMBA_ENABLE_CUDASIM=1: the simulator has no compiler", allow_module_level=True)


def _nvvm_or_skip():
    from rodjit.gpu._cuda import CudaUnavailable, import_cuda

    try:
        import_cuda()
    except CudaUnavailable as exc:
        pytest.skip(str(exc))
    from numba.cuda.cudadrv import nvvm

    if not nvvm.is_available():
        pytest.skip("numba-cuda finds no NVVM (the CUDA compiler): pip install "
                    "'rodjit[cuda]' brings it (numba-cuda[cu12])")


def _ptx(overrides):
    from rodjit.gpu.kernel import compile_ptx, family_of

    _nvvm_or_skip()
    family = family_of(parameters(Config().override(overrides)))
    return compile_ptx(family, cc=(9, 0))


def _check(ptx):
    assert ".target sm_90" in ptx
    assert ".entry" in ptx and "sweep_kernel" in ptx
    # the model's functions are compiled in: the Aiki–Kosugi floor's one division and the
    # loop's libdevice cube root leave their marks (a call left unresolved would not link)
    assert "div.rn.f64" in ptx


@pytest.mark.parametrize("integrator", ["energy", pytest.param("dp54", marks=pytest.mark.slow)])
def test_kernel_compiles_to_ptx(integrator):
    _check(_ptx({"time.integrator": integrator, "rod.N": 5}))


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["verlet", "semi-implicit", "dop853", "radau5"])
def test_other_integrators_compile_to_ptx(integrator):
    _check(_ptx({"time.integrator": integrator, "rod.N": 5}))


@pytest.mark.slow
def test_largest_rod_compiles_to_ptx():
    from rodjit.gpu.kernel import N_MAX

    _check(_ptx({"rod.N": N_MAX}))


@pytest.mark.slow
def test_law_registered_from_outside_compiles_to_ptx():
    """A user's law (tests/custom_law.py: its kernels call math.log1p) is retargeted like
    rodjit's own: no GPU version is written for it."""
    import custom_law  # noqa: F401  (registers "log-test")

    _check(_ptx({"rod.law": "log-test", "time.integrator": "verlet", "rod.N": 5}))


def test_retargeted_functions_are_the_cpu_source():
    """One source: the GPU's step is the CPU kernel's own code object, with its kernels
    mapped to device functions and its compile-time dispatches to CUDA overloads."""
    from rodjit._jit import Kernel
    from rodjit.gpu._cuda import import_cuda
    from rodjit.gpu.retarget import Retarget
    from rodjit.model.laws import aiki_kosugi
    from rodjit.model.laws.base import value
    from rodjit.stepping.integrators import energy

    _nvvm_or_skip()
    r = Retarget(import_cuda())
    step = r.function(energy.step)
    assert step.__code__ is energy.step.py_func.__code__
    # a kernel it calls: the device function of that kernel's own code
    jerk = step.__globals__["jerk"]
    assert jerk.py_func.__code__ is energy.jerk.py_func.__code__
    assert not isinstance(jerk, Kernel)
    # a law's own functions, reached through a generic dispatch, are retargeted too
    floor_value = r.function(aiki_kosugi.floor_value)
    assert floor_value.__globals__["floor_contact"].py_func.__code__ \
        is aiki_kosugi.floor_contact.py_func.__code__
    assert r.value(value) is r.value(value) and r.value(value) is not value


def _in_fresh_process(name: str) -> str:
    """Run this module's ``name()`` in a fresh interpreter and return what it prints.  The
    refusal tests compile a law CUDA rejects: in a test worker that has run other files
    first they met Python's recursion limit instead of the cause (seen only in the full
    suite, in whichever worker drew them), so they run where nothing ran before."""
    import subprocess
    import sys
    from pathlib import Path

    _nvvm_or_skip()     # here: a skip inside the fresh interpreter would be its crash
    here = Path(__file__).resolve().parent
    code = (f"import sys; sys.path[:0] = [{str(here)!r}, {str(here.parent)!r}]\n"
            f"import test_gpu_ptx as t\nprint(t.{name}())\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=600, cwd=here.parent)
    assert p.returncode == 0, p.stderr
    return p.stdout.strip().splitlines()[-1]


def _bad_law_reason() -> str:
    """The one-line reason of a law whose kernels use what CUDA cannot compile (here
    NumPy's random numbers, which the CPU compiles)."""
    import gpu_bad_law  # noqa: F401  (registers "gpu-bad-test")
    from rodjit.gpu.engine import reason

    try:
        _ptx({"rod.law": "gpu-bad-test", "time.integrator": "verlet", "rod.N": 5})
    except Exception as exc:
        return reason(exc)
    return "compiled"


def test_law_cuda_cannot_compile_is_one_line():
    """A law whose kernels use what CUDA cannot compile fails its kernel's compile with a
    one-line reason naming it; ``engine.prepare`` gives that line before a sweep writes
    anything."""
    line = _in_fresh_process("_bad_law_reason")
    assert "Unknown attribute 'random'" in line


def _at_depth(frames, fn):
    """``fn()`` called ``frames`` Python frames below here."""
    if frames <= 0:
        return fn()
    return _at_depth(frames - 1, fn)


def _deep_reason() -> str:
    """``_bad_law_reason`` from nearly all of a raised recursion limit used up: a compile
    on the caller's stack would have some hundred frames left, too few for Numba's nested
    typing; and whether the limit is back afterwards."""
    import sys

    from rodjit.gpu.kernel import COMPILE_FRAMES

    import gpu_bad_law  # noqa: F401  (registers "gpu-bad-test")
    from rodjit.gpu.engine import reason

    # numba-cuda imported and the loop retargeted first, as by any earlier GPU sweep of the
    # process: what the deep call must still have room for is the law's own compile
    _ptx({"time.integrator": "verlet", "rod.N": 5})
    depth = 4900
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(depth + 100)
    line = "compiled"
    try:
        _at_depth(depth, lambda: _ptx({"rod.law": "gpu-bad-test",
                                       "time.integrator": "verlet", "rod.N": 5}))
    except Exception as exc:         # worded here, back at the top of the stack
        error = exc
    finally:
        sys.setrecursionlimit(old)
    if line == "compiled" and "error" in locals():
        line = reason(error)
    restored = sys.getrecursionlimit() == old < COMPILE_FRAMES
    return f"{line} | limit restored: {restored}"


@pytest.mark.slow
def test_compile_from_a_deep_stack_names_the_cause():
    """The compile runs on a thread of its own (``kernel.deep_call``): a caller already
    deep in its stack (a test runner's worker, a user's framework) leaves the compile all
    its frames, so the refusal still names the cause, not Python's recursion limit."""
    line = _in_fresh_process("_deep_reason")
    assert "Unknown attribute 'random'" in line and line.endswith("limit restored: True")


@pytest.mark.slow
def test_observer_registered_from_outside_compiles_to_ptx():
    """A user's observer (examples/custom_observer.py: its step calls a kernel of its own)
    is compiled into the GPU kernel like the loop around it."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
    import custom_observer  # noqa: F401  (registers "rebound-apex")

    _check(_ptx({"output.observer": "rebound-apex", "time.integrator": "verlet",
                 "rod.N": 5}))
