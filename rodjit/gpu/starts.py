"""What each GPU thread starts from: a point's parameter tuples, its initial u and v, clock
and ``ev`` rows, exactly as the driver's ``Run`` makes them (``start_of``, one ``Run`` a
point), made for a whole batch at once (``starts``).

``Run.__init__`` costs about 0.1 ms a point (its buffers, the ahead-of-time loop's key, the
laws' parameters, the wave speed), which caps the host at some 1e4 points a second, below
what one GPU runs.  But each piece depends on one or two sections of the configuration, and
a sweep varies a few keys over a grid: ``starts`` makes each piece once per distinct value
of the sections it reads (the parameter tuples and the rod's start are shared objects
between points that agree on them) and repeats only the checks of each point.  The values
are those of ``Run`` to the bit, the failures too (the same checks in the same order,
raising the same error): tests/test_gpu_starts.py compares them.
"""
from __future__ import annotations

import math
import warnings
from typing import NamedTuple

import numpy as np

from ..config import ModelWarning
from ..driver.prepared import clock_row, snapshot_bound
from ..driver.run import Run
from ..config.checks import RUN_CHECKS
from ..model.system import check_admissible, initial_state, law_params, rod_system
from ..records.physics import flight_time
from ..stepping import control
from ..stepping import layout as L
from ..stepping.registry import make_scheme
from ..sweeps.point import pass_on

__all__ = ["Start", "start_of", "starts"]


class Start(NamedTuple):
    """What a thread starts from (``Run``'s arrays; the ``Run`` itself is not kept: a batch
    holds many thousand points)."""

    config: object
    scheme: object
    ctrl: object
    system: object
    rod: object
    floor: object
    state: np.ndarray          # u, v rows
    clock: np.ndarray
    ev: np.ndarray

    def params(self):
        """The loop's parameter tuples (``driver.run.parameters``)."""
        return (self.scheme, self.ctrl, self.system, self.rod, self.floor)


def start_of(config) -> tuple[Start, tuple]:
    """``(Start, ModelWarning texts)`` of a point by the driver's own ``Run``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ModelWarning)
        run = Run(config, snapshot_capacity=1, diag_capacity=1, event_capacity=1)
    start = Start(config, run.scheme, run.ctrl, run.system, run.rod, run.floor,
                  run.state[:2].copy(), run.clock.copy(), run.ev.copy())
    return start, pass_on(caught)


def _value_key(vals) -> tuple:
    """Values as a dictionary key that tells apart what ``==`` does not: their types (1 and
    1.0) and the sign of a zero (0.0 and -0.0)."""
    return (vals, tuple(map(type, vals)),
            tuple(math.copysign(1.0, v) for v in vals if type(v) is float and v == 0.0))


class _Batch:
    """The caches of one ``starts`` call: per piece, its value or the exception it raised,
    by the key of what it reads.  The points of a grid share the objects of the sections
    they agree on (``Grid.config``), so a section's key is made once per object (``key``);
    the objects live as long as the call's configs."""

    def __init__(self):
        self.keys: dict = {}
        self.made: dict = {name: {} for name in _PIECES}
        # the sections the run checks read (``Config.check_runnable``)
        self.checked = tuple(dict.fromkeys(k.split(".", 1)[0] for keys, _ in RUN_CHECKS
                                           for k in keys))

    def key(self, obj) -> tuple:
        got = self.keys.get(id(obj))
        if got is None:
            vals = tuple(obj.__dict__.values()) if hasattr(obj, "__dict__") else tuple(obj)
            got = self.keys[id(obj)] = (type(obj), *_value_key(vals))
        return got

    def get(self, name, key, make, *args):
        cache = self.made[name]
        try:
            hit = cache[key]
        except KeyError:
            try:
                hit = (True, make(*args))
            except Exception as exc:        # the same point-level failure for each point
                hit = (False, exc)
            cache[key] = hit
        except TypeError:                   # a law's parameters that are not plain values
            return make(*args)
        if hit[0]:
            return hit[1]
        raise hit[1]


_PIECES = ("runnable", "system", "rod", "floor", "scheme", "ctrl", "state", "admissible",
           "tau", "clock")


def starts(configs) -> tuple[list, tuple]:
    """``(starts, ModelWarning texts)`` of ``configs``: per point its ``Start``, or the
    exception its set-up raised (the point fails with it, as ``start_of`` would)."""
    out: list = []
    batch = _Batch()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ModelWarning)
        for config in configs:
            try:
                out.append(_start(config, batch))
            except Exception as exc:
                out.append(exc)
    return out, pass_on(caught)


def _start(config, b: _Batch) -> Start:
    """``Run.__init__``'s steps for one point, in its order, each piece from a cache keyed
    by what it reads."""
    b.get("runnable", tuple(b.key(getattr(config, s)) for s in b.checked),
          config.check_runnable)
    rod_k, floor_k, time_k = b.key(config.rod), b.key(config.floor), b.key(config.time)
    system = b.get("system", (rod_k, b.key(config.gravity)), rod_system, config.rod,
                   config.gravity)
    rod = b.get("rod", rod_k, law_params, "rod", config.rod)
    floor = b.get("floor", floor_k, law_params, "floor", config.floor)
    scheme = b.get("scheme", time_k, make_scheme, config.time)
    out = config.output
    n1 = config.rod.N + 1
    ctrl = b.get("ctrl", (time_k, n1, *_value_key((out.interpolate,))), _control, config,
                 scheme)
    ini_k = (b.key(config.initial), n1)
    state = b.get("state", ini_k, _state, config)
    b.get("admissible", (ini_k, b.key(rod), b.key(floor)), check_admissible, state[0], rod,
          floor, "initial state")
    # τ reads the rod law's parameters and N only (``physics.flight_time``)
    tau = b.get("tau", (config.rod.law, b.key(rod), n1), flight_time, config)
    clock = b.get("clock", (time_k, b.key(out)), _clock, config)
    ev = np.zeros(L.EV_SIZE)
    ev[L.FLIGHT_TIME] = tau
    return Start(config, scheme, ctrl, system, rod, floor, state, clock, ev)


def _control(config, scheme):
    """``parameters``' control tuple for a scheme already made."""
    return control.build(config.time, scheme, config.output.interpolate,
                         snapshot_rows=snapshot_bound(config.rod.N + 1))


def _state(config) -> np.ndarray:
    u, v = initial_state(config)
    state = np.empty((2, u.size))
    state[0] = u
    state[1] = v
    return state


def _clock(config) -> np.ndarray:
    """``Run.__init__``'s clock row."""
    return clock_row(config)

