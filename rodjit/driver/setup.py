"""A point's set-up: what a run derives from its configuration alone, the one path for a
single run (``driver.run.Run``), the CPU engine's batches (``sweeps.ensemble``) and the
GPU engine (``gpu.engine``).

``start(config)`` gives a point's ``Start``: the parameter tuples of the compiled loop
(scheme, control, system, rod law, floor law, observer), its initial (u, v) checked admissible, its
clock row and its flight time τ (the ``ev`` row's), or raises what its set-up raised;
``starts(configs)`` gives a list of them, an exception in place of a point that cannot
start.  Here too: the bound and sizes of a run's output buffers (``snapshot_bound``,
``rows_needed``) and the tolerance of its output times (``tolerance``).

Each piece is kept by the values of what it reads (a section's fields with their types
and the sign of a zero, the law registered under its name: one registered again gets new
pieces), for the few thousand most recent: the points of a sweep that agree on the
sections a piece reads share it (one object, packed once by the GPU engine), and a
Config run again, or one ``override`` made from it, finds its pieces.  A piece that
raised raises again, the same error, and the checks run in ``Run``'s order, so a point
fails as it fails alone.  Pieces are read-only by convention: a run copies the initial
state and the clock row.

Measured (µs; medians of eight rounds of fresh processes, the trees in turns, on a loaded
2-core machine), against the three set-ups it replaced (a ``Run`` keeping its rod's values
by section identity, the CPU engine's per point, the GPU engine's per batch) and against
this one with every piece made anew (no cache): a 200-point ``rod.mu`` grid of
paper-mu100, each point's Config made beforehand, its start and packed row as the CPU
engine makes them 66.9 → 36.7 a point (80.0 without the cache), all at once as the GPU
engine does 27.8 → 29.2 (73.5); ``Run`` of a repeated 1 ms paper-mu100 Config 34.0 →
29.5 (99.9), its warm ``simulate`` 116.6 → 113.1 (185.7).  Its values are those made
anew, to the bit: results do not change.
"""
from __future__ import annotations

import itertools
import math
import threading
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ..model.laws import get_law
from ..model.system import check_admissible, initial_state, law_params, rod_system
from ..records.observables import flight_time
from ..records.physics import lift_energy
from ..stepping import control
from ..stepping import layout as L
from ..stepping.observers import params_of
from ..stepping.schemes import make_scheme

if TYPE_CHECKING:
    from ..config import Config

__all__ = ["Start", "start", "starts", "parameters", "positions", "clear", "snapshot_bound",
           "rows_needed", "clock_row", "tolerance"]

CACHE_SIZE = 4096    # entries kept of each piece (the oldest go first)
ARRAY_FLOATS = 2**22  # and of a piece that is an array, at most about this many floats


class Start(NamedTuple):
    """What a point's run starts from (``start``).  Its arrays are shared with the points
    that agree on them: read only."""

    config: Config
    scheme: Any
    ctrl: Any
    system: Any
    rod: Any
    floor: Any
    obs: Any                   # the observer's parameters (``stepping.observers``)
    state: np.ndarray          # (2, N + 1): u, v
    clock: np.ndarray          # the clock row at the start (``clock_row``)
    tau: float                 # the flight time τ, the ``ev`` row's ``FLIGHT_TIME``

    def params(self) -> tuple:
        """The loop's parameter tuples ``(scheme, control, system, rod law, floor law,
        observer)``."""
        return (self.scheme, self.ctrl, self.system, self.rod, self.floor, self.obs)

    def ev(self) -> np.ndarray:
        """A new ``ev`` row at the start: zeros but the flight time."""
        ev = np.zeros(L.EV_SIZE)
        ev[L.FLIGHT_TIME] = self.tau
        return ev


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
    """A run's clock row at its start: t_end, the output intervals and the time below which
    two output times coincide."""
    out = config.output
    clock = np.zeros(L.CLOCK_SIZE)
    clock[L.T_END] = config.time.t_end
    # listed snapshot times (``output.times``): the interval's place says so, the times
    # themselves are the run's ``times`` array (``stepping.outputs``)
    clock[L.SNAP_DT] = -1.0 if out.times else out.snapshot_interval
    clock[L.DIAG_DT] = out.diagnostics_interval
    clock[L.TOL] = tolerance(clock, out.times)
    return clock


def tolerance(clock: np.ndarray, times=()) -> float:
    """The time below which two output times coincide, for the intervals, the gaps between
    the listed snapshot ``times`` and the remaining run in ``clock``
    (``control.output_tolerance``)."""
    spans = [x for x in (clock[L.SNAP_DT], clock[L.DIAG_DT], clock[L.T_END] - clock[L.T])
             if x > 0]
    spans += [b - a for a, b in zip(times, times[1:])]
    return control.output_tolerance(spans)


# ---- the cache ---------------------------------------------------------------------------
_LOCK = threading.Lock()
_TOKENS = itertools.count()
# an object's token by its id, the object kept (so that its id is not another's meanwhile)
_OBJECTS: dict[int, tuple[object, int]] = {}
_BY_VALUE: dict[tuple, int] = {}      # the token of a value key (``_value_key``)
_PIECES = ("runnable", "system", "rod", "floor", "tau", "rest", "scheme", "ctrl", "state",
           "admissible", "clock", "x")
_MADE: dict[str, dict] = {name: {} for name in _PIECES}


def _keep(cache: dict, key, value, limit: int = CACHE_SIZE) -> None:
    """Keep ``value`` under ``key``, forgetting the oldest entries beyond ``limit``."""
    with _LOCK:
        cache[key] = value
        while len(cache) > limit:
            del cache[next(iter(cache))]


def _value_key(vals: tuple) -> tuple:
    """Values as a dictionary key that tells apart what ``==`` does not: their types (1 and
    1.0) and the sign of a zero (0.0 and -0.0)."""
    return (vals, tuple(map(type, vals)),
            tuple(math.copysign(1.0, v) for v in vals if type(v) is float and v == 0.0))


def _token(obj) -> int | None:
    """A small number for the values of ``obj`` (a section, a parameter tuple): equal for
    objects of one class and the same values; None where a value cannot be a key (a law's
    parameter that is an array): what reads it is made anew."""
    got = _OBJECTS.get(id(obj))
    if got is not None:
        return got[1]
    vals = tuple(obj.__dict__.values()) if hasattr(obj, "__dict__") else tuple(obj)
    key = (type(obj), *_value_key(vals))
    try:
        token = _BY_VALUE.get(key)
    except TypeError:
        return None
    if token is None:
        token = next(_TOKENS)
        _keep(_BY_VALUE, key, token)
    _keep(_OBJECTS, id(obj), (obj, token))
    return token


def _identity(obj) -> int:
    """A small number for ``obj`` itself (a registered law: one registered again under the
    same name is another)."""
    got = _OBJECTS.get(id(obj))
    if got is not None:
        return got[1]
    token = next(_TOKENS)
    _keep(_OBJECTS, id(obj), (obj, token))
    return token


def _get(name: str, key: tuple, make, *args):
    """Piece ``name`` by ``key``: kept, or made now (its value or the exception it raised
    kept); a key with a None (``_token``) is made every time."""
    if None in key:
        return make(*args)
    cache = _MADE[name]
    hit = cache.get(key)
    if hit is None:
        try:
            value = make(*args)
        except Exception as exc:        # the same failure for every point that reads it
            _keep(cache, key, (False, exc))
            raise
        hit = (True, value)
        # the initial states of long rods: a bound on their memory too
        size = value.size if isinstance(value, np.ndarray) else 1
        _keep(cache, key, hit, min(CACHE_SIZE, max(16, ARRAY_FLOATS // size)))
    if hit[0]:
        return hit[1]
    raise hit[1].with_traceback(None)


# ---- the set-up --------------------------------------------------------------------------
def start(config, u0=None, v0=None) -> Start:
    """A point's ``Start`` (module docstring), raising what its set-up raises, in the order
    of its checks: the run checks (``Config.check_runnable``), the laws' parameters, the
    flight time, the scheme and control, the initial state (from ``u0``/``v0`` where given,
    checked admissible under the name ``u0`` then, and not kept), the clock row.  A
    configuration with ``time.integrator = "auto"`` starts as ``Config.resolve`` makes it
    (``Start.config``): a study resolves its base before, so its points agree."""
    config = config.resolve()
    n = config.rod.N
    rod_t, time_t = _token(config.rod), _token(config.time)
    _get("runnable", (time_t, rod_t), config.check_runnable)
    system, rod, floor, laws = _body(config, rod_t)
    # τ reads the rod law's parameters and N only (``records.physics.flight_time``)
    rod_p = _token(rod)
    tau = _get("tau", (laws[0], rod_p, n), flight_time, config)
    scheme, ctrl = _stepping(config, time_t, _rest(config, laws, rod_p))
    if u0 is None and v0 is None:
        # the initial velocity reads g too (``initial.impact_speed``)
        ini = (_token(config.initial), n, _token(config.gravity))
        state = _get("state", ini, _state, config)
        _get("admissible", (*ini, *laws, rod_p, _token(floor)), check_admissible,
             state[0], rod, floor, "initial state")
    else:
        state = _state(config, u0, v0)
        check_admissible(state[0], rod, floor, "u0" if u0 is not None else "initial state")
    clock = _get("clock", (time_t, _token(config.output)), clock_row, config)
    return Start(config, scheme, ctrl, system, rod, floor, params_of(config), state, clock,
                 tau)


def _body(config, rod_t) -> tuple:
    """``(system, rod law, floor law, law tokens)`` of ``config``."""
    rod_law, floor_law = get_law("rod", config.rod.law), get_law("floor", config.floor.law)
    laws = (_identity(rod_law), _identity(floor_law))
    floor_t = _token(config.floor)
    system = _get("system", (rod_t, _token(config.gravity), floor_t), rod_system, config.rod,
                  config.gravity, config.floor)
    rod = _get("rod", (rod_t, laws[0]), law_params, "rod", config.rod)
    floor = _get("floor", (floor_t, laws[1]), law_params, "floor", config.floor)
    return system, rod, floor, laws


def _rest(config, laws, rod_p) -> float:
    """The energy below which ``time.stop_at_rest`` ends a run in contact: the lift-off
    energy, which reads the rod law, N and g (-inf when the key is off)."""
    if not config.time.stop_at_rest:
        return -math.inf
    return _get("rest", (laws[0], rod_p, config.rod.N, _token(config.gravity)),
                lift_energy, config)


def _stepping(config, time_t, rest: float = -math.inf) -> tuple:
    """``(scheme, control)`` of ``config`` (``rest``: the energy of ``time.stop_at_rest``)."""
    scheme = _get("scheme", (time_t,), make_scheme, config.time)
    interpolate = config.output.interpolate      # a bool: its type tells 1 from True
    ctrl = _get("ctrl", (time_t, config.rod.N, type(interpolate), interpolate, rest),
                _control, config, scheme, rest)
    return scheme, ctrl


def parameters(config) -> tuple:
    """``(scheme, control, system, rod law, floor law, observer)``: the parameter tuples the
    compiled loop takes for ``config`` (no run checks, no initial state)."""
    config = config.resolve()
    system, rod, floor, laws = _body(config, _token(config.rod))
    rest = _rest(config, laws, _token(rod))
    return (*_stepping(config, _token(config.time), rest), system, rod, floor,
            params_of(config))


def starts(configs) -> list:
    """Per point of ``configs`` its ``Start``, or the exception its set-up raised (the
    point fails with it, as it would alone)."""
    out: list = []
    for config in configs:
        try:
            out.append(start(config))
        except Exception as exc:
            out.append(exc)
    return out


def positions(n: int) -> np.ndarray:
    """The nodes' reference positions x_i = i/N of a rod of ``n`` segments (read only)."""
    return _get("x", (n,), _positions, n)


def _positions(n: int) -> np.ndarray:
    return np.arange(n + 1) / n


def _control(config, scheme, rest: float = -math.inf):
    return control.build(config.time, scheme, config.output.interpolate,
                         snapshot_rows=snapshot_bound(config.rod.N + 1), rest_energy=rest)


def _state(config, u0=None, v0=None) -> np.ndarray:
    u, v = initial_state(config, u0, v0)
    state = np.empty((2, u.size))
    state[0] = u
    state[1] = v
    return state


def clear() -> None:
    """Forget every kept piece (a test's or benchmark's fresh start)."""
    with _LOCK:
        _OBJECTS.clear()
        _BY_VALUE.clear()
        for cache in _MADE.values():
            cache.clear()
