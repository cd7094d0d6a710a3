"""A clean stop on SIGINT/SIGTERM for long calls (a streamed run, a sweep): the signal is
recorded and the call stops at its next safe point instead of dying mid-write."""
from __future__ import annotations

import os
import signal
import sys
import threading
from contextlib import contextmanager
from typing import Any

__all__ = ["StopFlag", "Interrupted", "raise_interrupted", "install_early_handlers",
           "hold_on_exit", "pending_signal", "deferred_signals"]


class Interrupted(BaseException):
    """SIGINT/SIGTERM outside a run or sweep (start-up, loading): the command ends at once.
    A BaseException, so that neither ``except Exception`` nor click's handling of
    KeyboardInterrupt swallows it."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _in_llvm_callback(frame) -> bool:
    """Whether ``frame`` runs inside llvmlite's Python code, among it the callbacks that
    LLVM calls through ctypes while Numba compiles or loads a kernel (the object cache's
    notify and getbuffer): ctypes prints an exception raised there as "Exception ignored"
    with its traceback, and drops it."""
    engine = sys.modules.get("llvmlite.binding.executionengine")
    if engine is None or engine.__file__ is None:
        return False
    binding = os.path.dirname(engine.__file__)
    while frame is not None:
        if os.path.dirname(frame.f_code.co_filename) == binding:
            return True
        frame = frame.f_back
    return False


_REDELIVER_S = 0.005   # retry of a signal that came inside llvmlite (``raise_interrupted``)
_PENDING: list[int] = []
_ALARM_BEFORE: list = []   # the SIGALRM handler to put back once the signal is raised


def _redeliver(_alarm, frame):
    if _in_llvm_callback(frame):
        signal.setitimer(signal.ITIMER_REAL, _REDELIVER_S)
        return
    signal.signal(signal.SIGALRM, _ALARM_BEFORE.pop() if _ALARM_BEFORE else signal.SIG_DFL)
    raise Interrupted(_PENDING.pop(0))


def raise_interrupted(signum, frame):
    """Signal handler: raise Interrupted; inside llvmlite (``_in_llvm_callback``) a few
    milliseconds later instead, once the interpreter is out of it (SIGALRM retries), so
    the interrupt is neither lost nor printed as a traceback."""
    if not _in_llvm_callback(frame):
        raise Interrupted(signum)
    if not _PENDING:
        _PENDING.append(signum)
        _ALARM_BEFORE.append(signal.signal(signal.SIGALRM, _redeliver))
        signal.setitimer(signal.ITIMER_REAL, _REDELIVER_S)


_HOLD = [False]        # set by ``hold_on_exit``


class StopFlag:
    """While active (main thread only), SIGINT and SIGTERM record the signal instead of
    killing the process; the run stops cleanly at the next return from compiled code.
    A second signal aborts at once (KeyboardInterrupt), unless ``abort`` was set False
    (a teardown that must not be cut; ``count`` still counts it, for a teardown that waits
    and gives up on a signal).  Inside ``hold_on_exit`` the signals stay recorded when it
    ends."""

    def __init__(self, install: bool):
        self.install = install and threading.current_thread() is threading.main_thread()
        self.signum: int | None = None
        self.count = 0          # signals received
        self.abort = True
        self._old: dict[int, Any] = {}

    def _handler(self, signum, frame):
        self.count += 1
        if self.signum is not None and self.abort:
            raise KeyboardInterrupt
        if self.signum is None:
            self.signum = signum

    def __enter__(self):
        if self.install:
            for s in (signal.SIGINT, signal.SIGTERM):
                self._old[s] = signal.signal(s, self._handler)
        return self

    def __exit__(self, *exc):
        held = bool(self._old) and _HOLD[0]
        for s, old in self._old.items():
            signal.signal(s, _record if held else old)
        self._old = {}


_LATE: list[int] = []     # signals recorded after a StopFlag ended inside hold_on_exit


def _record(signum, frame):
    _LATE.append(signum)


@contextmanager
def hold_on_exit():
    """``with hold_on_exit():`` a StopFlag ending inside leaves SIGINT and SIGTERM recorded
    (``pending_signal``) instead of putting the previous handlers back: the command line,
    once a sweep has closed its file, prints its table without a signal cutting it, then
    reports a signal that came meanwhile.  For a process that ends after its command."""
    _HOLD[0] = True
    try:
        yield
    finally:
        _HOLD[0] = False


def pending_signal() -> int | None:
    """The first SIGINT or SIGTERM recorded since a StopFlag ended (``hold_on_exit``)."""
    return _LATE[0] if _LATE else None


@contextmanager
def deferred_signals():
    """``with deferred_signals():`` SIGINT and SIGTERM are recorded, not acted on, and the
    first one is delivered again (to the handlers of before) when the block ends.

    For writing a file's layout: a handler that raises inside h5py's C callbacks comes out
    as an unrelated ``TypeError``, and would cut the layout at an arbitrary point.  The
    caller removes the file when the re-delivered signal raises.  Main thread only
    (elsewhere a no-op, as Python delivers signals to the main thread)."""
    got: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield got
        return
    old = {s: signal.signal(s, lambda signum, frame: got.append(signum))
           for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield got
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
        if got:
            signal.raise_signal(got[0])


def _exit_at_once(signum, frame):
    if not in_worker():     # a worker stopped by its parent says nothing: the parent does
        os.write(2, f"Error: interrupted by {signal.Signals(signum).name}\n".encode())
    os._exit(128 + signum)


def in_worker() -> bool:
    """Whether this process is a worker started by another one (``multiprocessing``: a
    sweep's pool), whose parent reports for it.  A ``multiprocessing`` still being imported
    (a signal can land inside that import) lacks ``parent_process``: this process is then
    the one importing it, not a worker, which has it whole before running any of ours."""
    parent_process = getattr(sys.modules.get("multiprocessing"), "parent_process", None)
    return parent_process is not None and parent_process() is not None


def install_early_handlers(exit_now: bool = False) -> None:
    """SIGINT and SIGTERM raise Interrupted (the command line's entry point turns it into
    one line and exit code 128 + signal); ``exit_now``: while the package itself is being
    imported (nothing is open yet, and no handler of ours could catch the exception), they
    end the process at once with that line and code."""
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, _exit_at_once if exit_now else raise_interrupted)
