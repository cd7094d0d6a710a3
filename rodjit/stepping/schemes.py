"""The compiled loop's calls into the scheme in use: ``initial`` and ``step`` resolve to
the scheme's module (``registry``) at compile time, from the type of its parameters, so
only the scheme in use is compiled and its parameters stay run-time values.

A scheme module provides
  ``initial(scheme, system, rod, floor, u, v, a, work)`` -> ``StepResult``
  ``step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt)`` -> ``StepResult``
where ``step`` never modifies its inputs (a rejected trial costs nothing to undo) and
``sstats`` is the int64 array of the registry's counters (``registry.SCHEME_STATS``).
"""
from __future__ import annotations

from numba.extending import overload

from . import registry
from .registry import SCHEME_STATS, make_scheme
from .._jit import JIT_OPTIONS, STEP_JIT_OPTIONS

__all__ = ["make_scheme", "initial", "step", "gap_control", "work_rows", "SCHEME_STATS"]


def _module(params_type):
    return registry.load(registry.entry_of(params_type))[0]


def _module_for(numba_type):
    return _module(getattr(numba_type, "instance_class", None))


def initial(scheme, system, rod, floor, u, v, a, work):
    return _module(type(scheme)).initial(scheme, system, rod, floor, u, v, a, work)


def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    return _module(type(scheme)).step(scheme, system, rod, floor, u, v, a, u2, v2, a2,
                                      work, sstats, dt)


def _compiled_with(impl, options) -> bool:
    """Whether the scheme's kernel ``impl`` is compiled with ``options``.  An overload with
    those options then compiles the kernel's own Python source instead of a wrapper calling
    it: a wrapper is one more function that LLVM optimises and code-generates with the whole
    step inlined into it.  Under the same options the two compiles are one function and
    share one cache entry (so the overloads keep the Python entry wrapper, which Numba's
    overloads leave out by default)."""
    own = {k: v for k, v in impl.targetoptions.items() if k not in ("nopython", "boundscheck")}
    return own == {k: v for k, v in options.items() if k != "cache"}


@overload(initial, jit_options={**JIT_OPTIONS, "no_cpython_wrapper": False}, strict=False)
def _initial_ov(scheme, system, rod, floor, u, v, a, work):
    impl = _module_for(scheme).initial
    if _compiled_with(impl, JIT_OPTIONS):
        return impl.py_func
    return lambda scheme, system, rod, floor, u, v, a, work: impl(
        scheme, system, rod, floor, u, v, a, work)


# inlined into the loop, like the step
@overload(step, jit_options={**STEP_JIT_OPTIONS, "no_cpython_wrapper": False}, strict=False)
def _step_ov(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    impl = _module_for(scheme).step
    if _compiled_with(impl, STEP_JIT_OPTIONS):
        return impl.py_func
    return lambda scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt: impl(
        scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt)


def gap_control(scheme) -> bool:
    """Whether the loop limits how fast the scheme's steps approach the barriers."""
    return registry.entry_of(type(scheme)).gap_control


def work_rows(scheme) -> int:
    """Rows of scratch space the scheme's step needs."""
    return registry.entry_of(type(scheme)).work_rows
