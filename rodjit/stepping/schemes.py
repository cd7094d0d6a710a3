"""The compiled loop's calls into the scheme in use: ``initial`` and ``step`` resolve to
the scheme's module (``registry``) at compile time, from the type of its parameters, so
only the scheme in use is compiled and its parameters stay run-time values.

A scheme module provides
  ``initial(scheme, system, rod, floor, u, v, a, work)`` -> ``StepResult``
  ``step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt)`` -> ``StepResult``
where ``step`` never modifies its inputs (a rejected trial costs nothing to undo) and
``sstats`` is the int64 array of the registry's counters (``registry.SCHEME_STATS``).

A scheme with a dense output (``registry.Scheme.dense``) also provides, for the step of
length dt from (u, v, a) to (u2, v2, a2) that it has just taken,
  ``dense_setup(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt)``
      -> ``(status, value)``: once per step with an output time inside it, before the loop
      accepts it (OK, or a failure code that makes the loop retry the step shorter)
  ``dense(scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo)``: (u, v) at t + θ dt,
      0 < θ ≤ 1, into the caller's rows ``uo``, ``vo``, for each output time of the step
  ``dense_dissipated(scheme, system, floor, u, v, u2, v2, work, dt, theta)`` -> the energy
      dissipated (viscosity and the floor's damping, ``floor`` the law the step took)
      from t to t + θ dt, consistent with the step's own increment at θ = 1
(all may use only ``work`` rows the step leaves alone).  For a scheme without one the loop
never calls them (``control.build`` turns interpolation off); they compile to a failure
code and NaN rows, so a call by mistake cannot pass unnoticed.
"""
from __future__ import annotations

import numpy as np

from . import registry
from .registry import SCHEME_STATS, make_scheme
from ..kernels.forces import NON_FINITE
from .. import _jit
from .._jit import overload

__all__ = ["make_scheme", "initial", "step", "dense_setup", "dense", "dense_dissipated",
           "has_dense", "has_dense_type", "gap_control", "work_rows", "SCHEME_STATS"]


def _module(params_type):
    return registry.load(registry.entry_of(params_type))[0]


def _module_for(numba_type):
    return _module(getattr(numba_type, "instance_class", None))


def has_dense_type(numba_type) -> bool:
    """``has_dense`` of a scheme's Numba type, for an overload choosing its implementation."""
    return registry.entry_of(getattr(numba_type, "instance_class", None)).dense


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


@overload(initial, kind="plain", python_wrapper=True, strict=False)
def _initial_ov(scheme, system, rod, floor, u, v, a, work):
    impl = _module_for(scheme).initial
    if _compiled_with(impl, _jit.JIT_OPTIONS):
        return impl.py_func
    return lambda scheme, system, rod, floor, u, v, a, work: impl(
        scheme, system, rod, floor, u, v, a, work)


# inlined into the loop, like the step
@overload(step, python_wrapper=True, strict=False)
def _step_ov(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    impl = _module_for(scheme).step
    if _compiled_with(impl, _jit.STEP_JIT_OPTIONS):
        return impl.py_func
    return lambda scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt: impl(
        scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt)


def dense_setup(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt):
    return _module(type(scheme)).dense_setup(scheme, system, rod, floor, u, v, a, u2, v2, a2,
                                             work, dt)


def dense(scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo):
    return _module(type(scheme)).dense(scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo)


@overload(dense_setup)
def _dense_setup_ov(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt):
    if not has_dense_type(scheme):
        return lambda scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt: (
            NON_FINITE, np.nan)
    impl = _module_for(scheme).dense_setup
    return lambda scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt: impl(
        scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt)


def _no_dense(scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo):
    for i in range(uo.size):
        uo[i] = np.nan
        vo[i] = np.nan


@overload(dense)
def _dense_ov(scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo):
    if not has_dense_type(scheme):
        return _no_dense
    impl = _module_for(scheme).dense
    return lambda scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo: impl(
        scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo)


def dense_dissipated(scheme, system, floor, u, v, u2, v2, work, dt, theta):
    return _module(type(scheme)).dense_dissipated(scheme, system, floor, u, v, u2, v2, work,
                                                  dt, theta)


@overload(dense_dissipated)
def _dense_dissipated_ov(scheme, system, floor, u, v, u2, v2, work, dt, theta):
    if not has_dense_type(scheme):
        return lambda scheme, system, floor, u, v, u2, v2, work, dt, theta: np.nan
    impl = _module_for(scheme).dense_dissipated
    return lambda scheme, system, floor, u, v, u2, v2, work, dt, theta: impl(
        scheme, system, floor, u, v, u2, v2, work, dt, theta)


def has_dense(scheme) -> bool:
    """Whether the scheme has a dense output (``registry.Scheme.dense``); in compiled code
    a constant, whose branches LLVM removes from the loop of a scheme without one (they are
    still typed: the kernels they call compile to no-ops for such a scheme,
    ``has_dense_type``)."""
    return registry.entry_of(type(scheme)).dense


@overload(has_dense)
def _has_dense_ov(scheme):
    if has_dense_type(scheme):
        return lambda scheme: True
    return lambda scheme: False


def gap_control(scheme) -> bool:
    """Whether the loop limits how fast the scheme's steps approach the barriers."""
    return registry.entry_of(type(scheme)).gap_control


def work_rows(scheme) -> int:
    """Rows of scratch space the scheme's step needs."""
    return registry.entry_of(type(scheme)).work_rows
