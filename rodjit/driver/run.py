"""A run in progress: the arrays the compiled loop works on, and the calls that advance it.

``Run`` owns no output: each call drains the loop's buffers into a *sink*
(``records.sink.Sink``: in memory for ``simulate``, an HDF5 file for the command line).
``checkpoint``/``from_checkpoint`` save and restore everything the stepper needs, so a
resumed run continues bit for bit.

``advance`` is one call and its drain.  Its parts exist apart for ``driver.files``, which
looks at a block before writing it: ``compute`` (the compiled call), ``take`` (the filled
rows as a ``Block``) and ``drain`` (the block into a sink).
"""
from __future__ import annotations

import math
import time
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from .._jit import python_function
from ..config import ModelWarning
from ..kernels.forces import BAD_FLOOR, BAD_STRAIN, INACCURATE, NO_CONVERGENCE, NON_FINITE, TOO_CLOSE
from ..model.laws import lower
from ..records.sink import Sink
from ..records.stats import run_stats

if TYPE_CHECKING:
    from ..records.result import Result
from ..stepping import aot
from ..stepping import layout as L
from ..stepping.events import write_bounce
from ..stepping.loop import advance, start
from ..stepping.arrays import allocate
from ..stepping.observers import state_size, values_of
from .setup import parameters, positions, rows_needed, snapshot_bound, tolerance
from .setup import start as set_up

__all__ = ["Block", "Run", "SimulationError", "Sink", "parameters", "failure_text", "capacities"]

# node-steps per compiled call: long enough that returning to Python costs nothing, short
# enough that signals, progress and checkpoints are seen promptly
NODE_STEPS_PER_CALL = 20_000_000


# the compiled entry points (``_jit.Kernel.entry_point``) of the loop's ``start`` and
# ``advance`` this process has compiled or loaded from the disk cache, by the function's
# name and the run's ``_compiled_key`` (which fixes every argument's type)
_COMPILED: dict[tuple[str, tuple], object] = {}


class SimulationError(RuntimeError):
    """The run could not continue (a step below ``time.dt_min``, a barrier crossed, a
    non-finite state); ``result`` holds everything up to the failure.

    Parameters
    ----------
    message : str
        What failed and where (simulated time, the step), one line.
    result : Result or None
        The run up to the failure, with ``status == "failed"`` (None where no result is
        kept, e.g. a run streamed to a file, which holds it instead).
    """

    summary: Any = None     # a streamed run's ``RunSummary`` (``driver.files``)

    def __init__(self, message: str, result: Result | None = None) -> None:
        super().__init__(message)
        self.result = result


_WRITE_BOUNCE = python_function(write_bounce)

# the counters of rows filled since the last drain, next to each other in ``count``: read
# and reset as one slice
_ROWS = slice(L.N_SNAP, L.N_BOUNCE + 1)
assert (L.N_DIAG, L.N_EP, L.N_BOUNCE) == (L.N_SNAP + 1, L.N_SNAP + 2, L.N_SNAP + 3)


class Block:
    """The rows compiled calls left in one set of output buffers (views of them), and the
    return code of the last call; ``Run.drain`` hands them to a sink."""

    def __init__(self, run, code: int):
        a = run.arrays
        k, n_diag, n_ep, n_bounce = a.count[_ROWS].tolist()
        self.code = code
        self.snapshots = (a.snap_t[:k], a.snap_step[:k], a.snap_u[:k], a.snap_v[:k])
        self.diagnostics = a.diag[:n_diag]
        self.episodes = a.episodes[:n_ep]
        self.bounces = a.bounces[:n_bounce]
        self.finite = _all_finite(self.diagnostics)
        # the loop's contact state at the block's end (``Sink.block``)
        self.in_contact = bool(a.ev[L.IN_CONTACT] != 0.0)
        self.contact_start = float(a.ev[L.EP_START])


def _all_finite(rows: np.ndarray) -> bool:
    """Whether every value of ``rows`` is finite.  A finite sum says so (an inf or a NaN
    makes the sum inf or NaN) in one pass without a temporary; only a sum that is not
    finite (a non-finite value, or finite ones whose sum overflows) needs the test of
    each value."""
    return math.isfinite(rows.sum()) or bool(np.isfinite(rows).all())


def capacities(config, ctrl, snapshot_capacity=None, diag_capacity=None) -> tuple[int, int]:
    """The rows of a run's snapshot and diagnostics buffers (``Run``): by default what the
    run needs, up to a memory bound, and always at least what a dense-output step writes
    in one call (``control.DENSE_OUTPUTS_MAX``)."""
    n1 = config.rod.N + 1
    out, t_end = config.output, config.time.t_end
    if snapshot_capacity is None:
        # listed times: one row each, and one for the row of a run stopped between them
        wanted = (len(out.times) + 1 if out.times else
                  rows_needed(out.snapshot_interval, t_end))
        snapshot_capacity = min(snapshot_bound(n1), wanted)
    if diag_capacity is None:
        diag_capacity = min(4096, rows_needed(out.diagnostics_interval, t_end))
    if out.snapshot_interval > 0 or out.times:
        snapshot_capacity = max(snapshot_capacity, ctrl.dense_snapshots)
    if out.diagnostics_interval > 0:
        diag_capacity = max(diag_capacity, ctrl.dense_diagnostics)
    return snapshot_capacity, diag_capacity


def warn_config(config, stacklevel: int = 3) -> None:
    """Issue the configuration's ``warnings()`` as ModelWarning (from the caller's caller)."""
    for text in config.warnings():
        warnings.warn(text, ModelWarning, stacklevel=stacklevel)


def failure_text(fail, t_end: float, ctrl, config, rod, floor) -> str:
    """The one-line message of a run that failed with the loop's ``fail`` row
    (``Run.failure_message``; also the ensemble engine's, for a point of a batch)."""
    f = fail
    code = int(f[L.F_CODE])
    t = f[L.F_T]
    if code == L.NO_PROGRESS:
        return (f"time stopped advancing at t = {float(t)!r}: {int(f[L.F_VALUE])} steps of "
                f"dt = {f[L.F_DT]:.3g} each left t unchanged (the resolution of t there "
                f"is {math.ulp(t):.3g}): time.t_end = {t_end:g} cannot be "
                f"reached with steps this short")
    if code == BAD_STRAIN:
        why = (f"the strain of segment {int(f[L.F_INDEX])} reached {f[L.F_VALUE]:.6g}, at or "
               f"below the rod's compression limit {lower(rod):g} (rod.law = "
               f"{config.rod.law!r})")
    elif code == BAD_FLOOR:
        why = (f"the bottom height u_0 reached {f[L.F_VALUE]:.6g}, at or below the floor's "
               f"bending limit -beta = {lower(floor):g}")
    elif code == NON_FINITE:
        why = "a non-finite value appeared in the state"
    elif code == NO_CONVERGENCE:
        why = (f"the implicit step's Newton iteration did not converge (last update "
               f"{f[L.F_VALUE]:.3g})")
    elif code == TOO_CLOSE:
        why = (f"the state approaches a barrier (smallest strain {f[L.F_VALUE]:.6g}, "
               f"bottom height limit -beta = {lower(floor):g}) faster than steps "
               f"can resolve")
    elif code == INACCURATE:
        why = (f"the local error estimate is {f[L.F_VALUE]:.3g} × the tolerance "
               f"(time.rtol = {config.time.rtol:g}, time.atol = "
               f"{config.time.atol:g})")
    else:
        why = f"unknown failure code {code}"
    if ctrl.dt_fixed > 0:
        return (f"fixed step time.dt = {ctrl.dt_fixed:g} failed at t = {t:.9g}: {why}; "
                f"unset time.dt for adaptive steps or choose a smaller time.dt")
    return (f"step size fell below time.dt_min = {ctrl.dt_min:g} at t = {t:.9g} "
            f"(last trial step {f[L.F_DT]:.3g}): {why}")


class Run:
    """One simulation: build it from a config (or a checkpoint), ``start``, then ``advance``
    until it returns ``layout.DONE``.

    The output buffers hold ``snapshot_capacity`` and ``diag_capacity`` rows (by default
    what the run needs, up to a memory bound), and always at least the rows a dense-output
    step may write in one call (``Control.dense_snapshots``, ``dense_diagnostics``).
    """

    def __init__(self, config, *, u0=None, v0=None, snapshot_capacity=None,
                 diag_capacity=None, event_capacity=1024):
        # its configuration (``Config.resolve``: an "auto" integrator chosen), parameter
        # tuples, initial state (checked admissible), clock row at the start and flight
        # time (``driver.setup``): the arrays are copied, the tuples shared
        s = set_up(config, u0, v0)
        self.config = config = s.config
        self.scheme, self.ctrl, self.system, self.rod, self.floor, self.obs = s.params()
        n1 = config.rod.N + 1
        snapshot_capacity, diag_capacity = capacities(config, self.ctrl, snapshot_capacity,
                                                      diag_capacity)
        # the loop's arrays and buffers (``stepping.arrays``): zeros, then the state's u and
        # v rows, the clock row (t_end, the output intervals and tolerance set) and ``ev``
        # (the flight time)
        self.arrays = a = allocate(n1, self.scheme, snapshot_capacity, diag_capacity,
                                   event_capacity, config.output.times,
                                   state_size(self.obs))
        a.state[:2] = s.state
        a.clock[:] = s.clock
        a.ev[:] = s.ev()
        self._undrained = 0         # blocks taken but not drained yet
        self.max_steps = max(1, NODE_STEPS_PER_CALL // n1)
        self.compile_time = 0.0
        self.run_time = 0.0
        self._warm = False
        self._advance = None        # the compiled entry of ``advance`` (``warm_up``)
        self.x = positions(n1 - 1)  # reference positions x_i = i/N (shared: read only)
        self._key = aot.key(self._args())
        # the loop compiled at install for the default run's types, or None: the JIT
        self._aot = aot.loop_for(self._args(), self._key)

    # ---- properties --------------------------------------------------------------------
    @property
    def t(self) -> float:
        return float(self.arrays.clock[L.T])

    @property
    def t_end(self) -> float:
        return float(self.arrays.clock[L.T_END])

    @property
    def steps(self) -> int:
        return int(self.arrays.count[L.STEP])

    @property
    def rejected(self) -> int:
        return int(self.arrays.count[L.REJECTED])

    @property
    def bounces_total(self) -> int:
        return int(self.arrays.count[L.BOUNCES_TOTAL])

    @property
    def dissipated(self) -> float:
        return float(self.arrays.clock[L.DISSIPATED])

    @property
    def energy0(self) -> float:
        return float(self.arrays.clock[L.E0])

    @property
    def drained(self) -> bool:
        """Every row computed so far has gone to the sink: the state a checkpoint matches."""
        return self._undrained == 0 and not any(
            self.arrays.count[i] for i in (L.N_SNAP, L.N_DIAG, L.N_EP, L.N_BOUNCE))

    @property
    def observed(self) -> dict:
        """The observer's values now (``output.observer``; empty without one)."""
        return values_of(self.obs, self.arrays.observed)

    @property
    def u(self) -> np.ndarray:
        return self.arrays.state[0]

    @property
    def v(self) -> np.ndarray:
        return self.arrays.state[1]

    def set_t_end(self, t_end: float) -> None:
        """Move the end of the run (e.g. to extend a resumed run)."""
        if not (math.isfinite(t_end) and t_end > self.t):
            raise ValueError(f"time.t_end = {t_end!r} is out of range (must be > the current "
                             f"time {self.t!r})")
        self.arrays.clock[L.T_END] = t_end
        self._set_tolerance()

    def _set_tolerance(self):
        self.arrays.clock[L.TOL] = tolerance(self.arrays.clock, self.config.output.times)

    # ---- stepping ----------------------------------------------------------------------
    def _args(self):
        return (self.scheme, self.ctrl, self.system, self.rod, self.floor, self.obs)

    def start(self, sink: Sink | None) -> None:
        """Compile (or load from cache) the kernels, then evaluate the initial state; its
        outputs (at t0) are drained into ``sink``, or stay in the buffers if it is None.
        A run resumed from a checkpoint only compiles."""
        if self.arrays.count[L.STARTED]:
            if not self._warm:
                self.warm_up()
            return
        if self._aot is not None:
            call, args = self._aot.start, (self.arrays,)
        else:
            args = (*self._args(), self.arrays)
            call = self._entry("start", start, args)    # its compile time counted there
        t0 = time.perf_counter()
        code = call(*args)
        # the initial evaluation is no step: it counts with the start-up, once
        self.compile_time += time.perf_counter() - t0
        self.warm_up()
        if code == L.FAILED:
            raise SimulationError(self.failure_message())
        if sink is not None:
            self.drain(self.take(), sink)

    def warm_up(self) -> None:
        """Compile ``advance`` without stepping, so its compile time is measured apart.

        Once per process and argument types (``_compiled_key``): a later run of the same
        types takes the compiled entry point kept then (``_jit.Kernel.entry_point``),
        whose calls skip the dispatcher's typing of two dozen arguments, which a sweep of
        short rods would pay at every point.  The ahead-of-time loop needs none."""
        if self._aot is None:
            self._advance = self._entry("advance", advance, (*self._args(),
                                                             *self._advance_arrays(0)))
        self._warm = True

    def _entry(self, name: str, function, args: tuple):
        """The compiled entry of the loop's ``function`` for this run's argument types
        ``args``, from ``_COMPILED`` or compiled now (its time added to ``compile_time``)."""
        k = (name, self._compiled_key())
        entry = _COMPILED.get(k)
        if entry is None:
            t0 = time.perf_counter()
            entry = _COMPILED[k] = function.entry_point(args)
            self.compile_time += time.perf_counter() - t0
        return entry

    def _compiled_key(self) -> tuple:
        """What Numba's signature of ``advance`` depends on beyond the fixed array types
        (``stepping.aot.key``: the parameter tuples' classes and their fields' types)."""
        return self._key

    def _advance_arrays(self, max_steps: int) -> tuple:
        """The arguments of ``advance`` after the parameter tuples.  Always the arrays the
        run allocated itself (``__init__``) and an int: the compiled entry point relies on
        these types."""
        return (self.arrays, int(max_steps))

    def _call(self, max_steps):
        arrays = self._advance_arrays(max_steps)
        if self._aot is not None:
            return self._aot.advance(*arrays)
        return self._advance(*self._args(), *arrays)

    def advance(self, sink: Sink, max_steps: int | None = None) -> int:
        """One compiled call (up to ``max_steps`` steps), then drain into ``sink``.

        Returns layout.DONE, FULL or PAUSED (call again); raises SimulationError on failure
        after draining everything computed up to it.
        """
        if not self.arrays.count[L.STARTED]:
            self.start(sink)
        code = self.compute(max_steps)
        self.drain(self.take(code), sink)
        if code == L.FAILED:
            raise SimulationError(self.failure_message())
        return code

    def compute(self, max_steps: int | None = None) -> int:
        """One compiled call into the current buffers, without draining; returns its code
        (layout.FAILED included).  Needs ``start``; releases the GIL while it runs."""
        if not self._warm:
            self.warm_up()
        clock, count = self.arrays.clock, self.arrays.count
        t0 = time.perf_counter()
        t, steps = clock[L.T], count[L.STEP]
        code = self._call(self.max_steps if max_steps is None else max_steps)
        self.run_time += time.perf_counter() - t0
        if code in (L.PAUSED, L.FULL) and count[L.STEP] > steps and clock[L.T] <= t:
            # every step of the call left t where it was (a step below the resolution of
            # t): calling again would loop for ever
            f = self.arrays.fail
            f[L.F_CODE], f[L.F_T], f[L.F_DT] = L.NO_PROGRESS, t, clock[L.DT]
            f[L.F_VALUE] = count[L.STEP] - steps
            code = L.FAILED
        return code

    def take(self, code: int = L.PAUSED) -> Block:
        """The rows in the buffers as a Block (``code``: that of the call that filled them);
        the loop starts the next block empty, in the same buffers (drain the block first)."""
        block = Block(self, code)
        self.arrays.count[_ROWS] = 0
        self._undrained += 1
        return block

    def drain(self, block: Block, sink: Sink) -> None:
        """Hand ``block`` to ``sink``: snapshots, diagnostics (refused, with SimulationError,
        if any value is not finite), episodes, bounces, then all of it at once
        (``Sink.block``).  The run stays not ``drained`` if
        this raises."""
        if block.snapshots[0].size:
            sink.snapshots(*block.snapshots)
        if block.diagnostics.shape[0]:
            if not block.finite:
                raise SimulationError("a non-finite diagnostic value was computed; refusing "
                                      "to write it")
            sink.diagnostics(block.diagnostics)
        if block.episodes.shape[0]:
            sink.episodes(block.episodes)
        if block.bounces.shape[0]:
            sink.bounces(block.bounces)
        sink.block(block.diagnostics, block.episodes, block.bounces, block.in_contact,
                   block.contact_start)
        self._undrained -= 1

    def pending_bounce(self):
        """``(row, open)`` for the bounce still collecting episodes at this time, or None.

        It is *open* if its last episode has not ended (the rod is on the floor).
        """
        if self.arrays.ev[L.B_NEP] <= 0:
            return None
        row = np.zeros(len(L.BOUNCE_ROW_COLUMNS))
        is_open = bool(self.arrays.ev[L.IN_CONTACT])
        # copies and one division: the kernel's Python function (``_jit.python_function``)
        _WRITE_BOUNCE(row, self.arrays.ev, is_open)
        return row, is_open

    def stats(self) -> dict:
        """``Result.stats`` of the run so far (``records.stats.run_stats``)."""
        return run_stats(steps=self.steps, rejected=self.rejected,
                         compile_time=self.compile_time, run_time=self.run_time,
                         nodes=self.system.n + 1, scheme_counts=self.arrays.sstats)

    # ---- failure -------------------------------------------------------------------------
    def failure_message(self) -> str:
        return failure_text(self.arrays.fail, float(self.arrays.clock[L.T_END]), self.ctrl,
                            self.config, self.rod, self.floor)

    # ---- checkpoint ------------------------------------------------------------------------
    _CHECKPOINT_ARRAYS = ("state", "clock", "count", "ev", "sstats", "observed")

    def checkpoint(self) -> dict[str, np.ndarray]:
        """Copies of everything needed to continue (taken when the run is ``drained``)."""
        ck = {name: getattr(self.arrays, name).copy()
              for name in self._CHECKPOINT_ARRAYS}
        ck["compile_time"] = np.float64(self.compile_time)
        ck["run_time"] = np.float64(self.run_time)
        return ck

    @classmethod
    def from_checkpoint(cls, config, ck: dict, **kwargs) -> "Run":
        """A run that continues exactly where ``ck`` (from ``checkpoint``) left off."""
        run = cls(config, u0=np.asarray(ck["state"])[0], v0=np.asarray(ck["state"])[1], **kwargs)
        for name in cls._CHECKPOINT_ARRAYS:
            if name == "observed" and name not in ck:
                continue    # a file's run without an observer: its array is zeros
            src = np.asarray(ck[name])
            dst = getattr(run.arrays, name)
            if src.shape != dst.shape:
                raise ValueError(f"checkpoint array {name!r} has shape {src.shape}, expected "
                                 f"{dst.shape} for this configuration")
            dst[...] = src
        run.run_time = float(ck.get("run_time", 0.0))
        run.compile_time = 0.0
        return run
