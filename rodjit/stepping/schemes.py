"""Integrators as types: each scheme's parameters are its own NamedTuple, and the compiled
loop calls ``initial``/``step`` below, which resolve to the scheme's module at compile
time (only the scheme in use is compiled; its parameters stay run-time values).

A scheme module provides
  ``initial(scheme, system, rod, floor, u, v, a, work)``
      -> (status, value, min_strain, floor_force, dt_suggest)
  ``step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt)``
      -> (status, value, min_strain, floor_force, dt_suggest, w, dissipated)
where ``step`` never modifies its inputs (a rejected trial costs nothing to undo) and
``sstats`` is an int64 array for scheme-specific counters.  Besides the failure codes of
``kernels.forces``, ``step`` may return INACCURATE (valid state, error estimate too large:
the loop retries with ``dt_suggest``) and NO_CONVERGENCE (a shorter step is tried).  Optional
module attributes: ``WORK_ROWS`` (scratch rows), ``GAP_CONTROL`` (default True).
"""
from __future__ import annotations

from typing import NamedTuple

from numba.extending import overload

from . import semi_implicit, verlet
from .._jit import JIT_OPTIONS, STEP_JIT_OPTIONS

__all__ = ["Verlet", "SemiImplicit", "make_scheme", "register_scheme", "initial", "step",
           "SCHEME_STATS"]

# names of the sstats counters, in order (reported in Result.stats)
SCHEME_STATS = ("newton_iterations", "newton_failures")


class Verlet(NamedTuple):
    cfl: float


class SemiImplicit(NamedTuple):
    cfl: float


_MODULES: dict[type, object] = {}
_BUILDERS: dict[str, object] = {}


def register_scheme(name: str, params: type, module, build) -> None:
    """Make ``time.integrator = name`` use ``module``; ``build(time_config)`` -> params."""
    _MODULES[params] = module
    _BUILDERS[name] = build


register_scheme("verlet", Verlet, verlet, lambda tc: Verlet(float(tc.cfl)))
register_scheme("semi-implicit", SemiImplicit, semi_implicit, lambda tc: SemiImplicit(float(tc.cfl)))


def make_scheme(time_config):
    """The scheme parameters for a ``TimeConfig``."""
    name = time_config.integrator
    if name not in _BUILDERS:
        # imported lazily so the basic schemes never pay for it
        from . import energy  # noqa: F401  (registers "energy")
    if name not in _BUILDERS:
        raise ValueError(f"time.integrator = {name!r} is not available; choose one of "
                         f"{sorted(_BUILDERS)}")
    return _BUILDERS[name](time_config)


def _module_for(numba_type):
    cls = getattr(numba_type, "instance_class", None)
    if cls not in _MODULES:
        raise TypeError(f"{numba_type} is not a registered integrator")
    return _MODULES[cls]


def initial(scheme, system, rod, floor, u, v, a, work):
    return _MODULES[type(scheme)].initial(scheme, system, rod, floor, u, v, a, work)


def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    return _MODULES[type(scheme)].step(scheme, system, rod, floor, u, v, a, u2, v2, a2,
                                       work, sstats, dt)


@overload(initial, jit_options=JIT_OPTIONS)
def _initial_ov(scheme, system, rod, floor, u, v, a, work):
    impl = _module_for(scheme).initial
    return lambda scheme, system, rod, floor, u, v, a, work: impl(
        scheme, system, rod, floor, u, v, a, work)


@overload(step, jit_options=STEP_JIT_OPTIONS)   # inlined into the loop, like the step
def _step_ov(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    impl = _module_for(scheme).step
    return lambda scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt: impl(
        scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt)


def gap_control(scheme) -> bool:
    """Whether the loop limits how fast steps approach the barriers ε = −1 and u_0 = −β
    (``Control.gap``).  Explicit schemes need it; a scheme that is admissible by
    construction (``energy``) sets ``GAP_CONTROL = False`` in its module."""
    return bool(getattr(_MODULES[type(scheme)], "GAP_CONTROL", True))


def work_rows(scheme) -> int:
    """Rows of scratch space the scheme's step needs (see ``workspace``)."""
    from .workspace import WORK_ROWS
    return getattr(_MODULES[type(scheme)], "WORK_ROWS", WORK_ROWS)


def sstats_size() -> int:
    return len(SCHEME_STATS)
