"""What a run derives from its configuration alone, derived once per ``Config`` object.

A ``Config`` is frozen, so everything ``driver.run.Run`` computes from it before stepping
(the run checks, the parameter tuples of the compiled loop, the buffer sizes, the flight
time, the initial values of the clock and event arrays, the default initial state and
its admissibility, the compiled loop's key, the model warnings) is the same for every
run of that object.  Computing it cost a short run most of its set-up (tens of µs of
Python and small NumPy calls: ``benchmarks/bench_fixed_cost.py``), paid again by every
``simulate`` of the same Config, as a benchmark or a loop over repeats does.

``prepare`` keeps it for the few most recent Config objects, by identity, checked through
a weak reference (a new object that reuses a dead one's ``id`` is not mistaken for it; a
dead one's entry is dropped), and only while the registered laws, integrators and the
dense output's cap it was built from are the same (``_stamp``).  The values are exactly
those computed before: a run gets copies of the templates here, made by the same
operations, so results do not change by a bit.  Nothing is kept for a configuration that
fails a check: it raises again at the next run.

A new Config object still shares the values of its ``rod``, ``floor``, ``gravity`` and
``initial`` sections (``Body``) with the configurations it was derived from by
``override`` where those sections are the same objects: a scan over tolerances,
integrators or output keys builds one new Config per run.
"""
from __future__ import annotations

import threading
import weakref

import numpy as np

from ..model.laws import get_law
from ..model.system import build_system, check_admissible, initial_state
from ..records.observables import flight_time
from ..stepping import aot, control, registry
from ..stepping import layout as L
from ..stepping.schemes import make_scheme

__all__ = ["Body", "Prepared", "prepare", "model_warnings", "parameters", "snapshot_bound", "rows_needed", "clock_row",
           "tolerance"]

CACHE_SIZE = 8    # Config objects kept: a sweep's points are new objects, a repeat is one
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
    system, rod, floor = build_system(config)
    scheme = make_scheme(config.time)
    ctrl = control.build(config.time, scheme, config.output.interpolate,
                         snapshot_rows=snapshot_bound(config.rod.N + 1))
    return scheme, ctrl, system, rod, floor


class Body:
    """The values of a configuration's ``rod``, ``floor``, ``gravity`` and ``initial``
    sections alone (with the laws registered under its law names): the system and law
    tuples, the flight time, the nodes' positions and the default initial state.  Kept
    apart from ``Prepared`` because ``Config.override`` keeps the sections it does not
    change as the same objects: configurations that differ in their ``time`` or
    ``output`` keys only (a scan over tolerances, integrators or run lengths) share one."""

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


def _body(config, laws: tuple) -> Body:
    for body in _BODIES:
        if body.matches(config, laws):
            return body
    body = Body(config, laws)
    with _LOCK:
        _BODIES.insert(0, body)
        del _BODIES[CACHE_SIZE:]
    return body


class Prepared:
    """A configuration's run-independent values (module docstring).  Read-only by
    convention: runs copy the arrays before writing to them.  ``stamp``: ``_stamp`` of
    the module state it was built under."""

    def __init__(self, config, stamp: tuple):
        config.check_runnable()     # a tolerance the integrator cannot honour: one line
        self.stamp = stamp
        body = self.body = _body(config, stamp[:2])
        scheme = make_scheme(config.time)
        ctrl = control.build(config.time, scheme, config.output.interpolate,
                             snapshot_rows=snapshot_bound(config.rod.N + 1))
        self.args = (scheme, ctrl, body.system, body.rod, body.floor)
        n1 = config.rod.N + 1
        out, t_end = config.output, config.time.t_end
        snap = min(snapshot_bound(n1), rows_needed(out.snapshot_interval, t_end))
        diag = min(4096, rows_needed(out.diagnostics_interval, t_end))
        if out.snapshot_interval > 0:
            snap = max(snap, ctrl.dense_snapshots)
        if out.diagnostics_interval > 0:
            diag = max(diag, ctrl.dense_diagnostics)
        self.capacities = (snap, diag)
        self.clock = clock_row(config)
        ev = np.zeros(L.EV_SIZE)
        ev[L.FLIGHT_TIME] = body.flight_time
        self.ev = ev
        self.x = body.x
        # the compiled loop's key; the ahead-of-time loop for it is looked up by each run
        # (``aot.loop_for``: whether the extension is in use may change in a process)
        self.key = aot.key(self.args)
        self.warnings = tuple(config.warnings())
        self._config = weakref.ref(config)

    def initial(self) -> np.ndarray:
        """The (3, N + 1) state array of the configuration's initial state (heights,
        velocities, zeros), checked admissible; a new array each call."""
        return self.body.initial(self._config())


_CACHE: dict[int, tuple[weakref.ref, Prepared]] = {}


def prepare(config) -> Prepared:
    """The ``Prepared`` values of ``config``: kept from an earlier run of the same object,
    or computed now (raising, and keeping nothing, where a check fails)."""
    hit = _CACHE.get(id(config))
    stamp = _stamp(config)
    if hit is not None and hit[0]() is config and hit[1].stamp == stamp:
        return hit[1]
    prepared = Prepared(config, stamp)
    key = id(config)
    with _LOCK:
        if len(_CACHE) >= CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)), None)     # the oldest entry
        _CACHE[key] = (weakref.ref(config, lambda ref: _forget(key, ref)), prepared)
    return prepared


def _stamp(config) -> tuple:
    """What the prepared values depend on besides the config's own fields: the laws
    registered under its law names, the integrators' registry (a new tuple at each
    registration) and the dense output's cap.  A kept entry whose stamp differs (a law
    registered again under the same name, as a notebook cell run twice does) is
    prepared anew."""
    return (get_law("rod", config.rod.law), get_law("floor", config.floor.law),
            registry.SCHEMES, control.DENSE_OUTPUTS_MAX)


def _forget(key: int, ref: weakref.ref) -> None:
    """Drop the entry of a Config that no longer exists (its weak reference's callback;
    no lock: it may run inside ``prepare`` itself, when a collection frees a Config)."""
    entry = _CACHE.get(key)
    if entry is not None and entry[0] is ref:
        _CACHE.pop(key, None)


def model_warnings(config) -> tuple[str, ...]:
    """``config.warnings()``, kept where the config has been prepared (its checks alone
    never run here: a config that is only shown, not run, is not refused)."""
    hit = _CACHE.get(id(config))
    if hit is not None and hit[0]() is config:
        return hit[1].warnings
    return tuple(config.warnings())
