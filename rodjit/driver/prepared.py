"""What a run derives from its configuration alone: the parameter tuples of the compiled
loop (``parameters``), the values of the rod, floor, gravity and initial sections
(``Body``), the bound and sizes of its output buffers (``snapshot_bound``,
``rows_needed``) and its clock row at the start (``clock_row``, ``tolerance``).  The run
driver (``driver.run.Run``), the ensemble engine and the GPU engine share these.

A ``Body`` is kept for the few most recent sets of section objects: ``Config.override``
keeps the sections it does not change as the same objects, so the configurations of a
scan over time or output keys (tolerances, integrators, run lengths, as
``benchmarks/bench_peers.py`` makes them) share one, and a Config run again reuses its
own.  Measured against building it for every run (a warm ``simulate`` of a new Config
from ``override`` per call, median of 150 calls in each of six alternating processes on
a loaded 2-core machine): paper-mu0 ``dp54`` at 1e-4 557 → 508 µs, paper-mu100
``radau5`` at 1e-3 371 → 321 µs, a 1 ms ``energy`` run 158 → 114 µs.  Its values are
the same as those built anew, so results do not change by a bit.
"""
from __future__ import annotations

import threading

import numpy as np

from ..model.laws import get_law
from ..model.system import build_system, check_admissible, initial_state
from ..records.observables import flight_time
from ..stepping import control
from ..stepping import layout as L
from ..stepping.schemes import make_scheme

__all__ = ["Body", "body", "parameters", "snapshot_bound", "rows_needed", "clock_row",
           "tolerance"]

CACHE_SIZE = 8    # sets of sections kept: a scan over time keys shares one
_LOCK = threading.Lock()


def snapshot_bound(n1: int) -> int:
    """The most snapshot rows a run's buffers hold (a memory bound, 2 MiB of floats)."""
    return int(min(1024, max(1, 2**21 // n1)))


def rows_needed(interval: float, span: float) -> int:
    """Output rows a run over ``span`` writes every ``interval`` (both ends and a rounding
    row included; 1 when the output is off).  A buffer of this size is never FULL, and a
    short run does not allocate (and page in) buffers for thousands of rows it never writes;
    a run extended later (``set_t_end``) fills its buffers and drains them, as any long run
    does, with the same steps."""
    return int(min(2**31, span / interval)) + 2 if interval > 0 else 1


def clock_row(config) -> np.ndarray:
    """A run's clock row at its start (``Run.__init__``): t_end, the output intervals and
    the time below which two output times coincide."""
    out = config.output
    clock = np.zeros(L.CLOCK_SIZE)
    clock[L.T_END] = config.time.t_end
    clock[L.SNAP_DT] = out.snapshot_interval
    clock[L.DIAG_DT] = out.diagnostics_interval
    clock[L.TOL] = tolerance(clock)
    return clock


def tolerance(clock: np.ndarray) -> float:
    """The time below which two output times coincide, for the intervals and the remaining
    run in ``clock`` (``control.output_tolerance``)."""
    spans = [x for x in (clock[L.SNAP_DT], clock[L.DIAG_DT], clock[L.T_END] - clock[L.T])
             if x > 0]
    return control.output_tolerance(spans)


def parameters(config) -> tuple:
    """``(scheme, control, system, rod law, floor law)``: the parameter tuples the compiled
    loop takes for ``config``."""
    b = body(config)
    system, rod, floor = b.system, b.rod, b.floor
    scheme = make_scheme(config.time)
    ctrl = control.build(config.time, scheme, config.output.interpolate,
                         snapshot_rows=snapshot_bound(config.rod.N + 1))
    return scheme, ctrl, system, rod, floor


class Body:
    """The values of a configuration's ``rod``, ``floor``, ``gravity`` and ``initial``
    sections alone (with the laws registered under its law names): the system and law
    tuples, the flight time, the nodes' positions and the default initial state.  Read-only
    by convention: a run copies the initial state (``initial``)."""

    def __init__(self, config, laws: tuple):
        self.sections = (config.rod, config.floor, config.gravity, config.initial)
        self.laws = laws
        self.system, self.rod, self.floor = build_system(config)
        self.flight_time = flight_time(config)
        self.x = np.arange(config.rod.N + 1) / self.system.n   # reference positions
        self._state: np.ndarray | None = None

    def matches(self, config, laws: tuple) -> bool:
        s = self.sections
        return (s[0] is config.rod and s[1] is config.floor and s[2] is config.gravity
                and s[3] is config.initial and self.laws == laws)

    def initial(self, config) -> np.ndarray:
        """The (3, N + 1) state array of the initial state of ``config`` (whose sections
        are this body's): heights, velocities, zeros, checked admissible; a new array."""
        if self._state is None:
            u, v = initial_state(config)
            check_admissible(u, self.rod, self.floor, "initial state")
            state = np.zeros((3, u.size))
            state[0] = u
            state[1] = v
            self._state = state
        return self._state.copy()


_BODIES: list[Body] = []     # the most recent first


def body(config) -> Body:
    """The ``Body`` of ``config``'s sections: kept from a configuration that shares those
    section objects and laws, or built now.  A law registered again under the same name (a
    notebook cell run twice) gets a new one."""
    laws = (get_law("rod", config.rod.law), get_law("floor", config.floor.law))
    for b in _BODIES:
        if b.matches(config, laws):
            return b
    b = Body(config, laws)
    with _LOCK:
        _BODIES.insert(0, b)
        del _BODIES[CACHE_SIZE:]
    return b
