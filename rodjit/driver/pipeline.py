"""Where a run's compiled calls execute: inline, or in a worker thread while the caller
drains the block before (the kernels release the GIL, so on two cores writing the file
hides behind the loop instead of adding to it).

Both classes keep one protocol.  ``launch()`` starts the next call, ``wait()`` returns the
``Block`` it filled, ``busy`` is True between the two, ``drain(block, sink)`` hands a block
to the sink, ``close()`` waits for a call still in flight.  Between ``wait`` and the next
``launch`` nothing touches the run: that is where the caller looks at it, stops it, or
checkpoints it (once the block is drained).  How calls are placed never changes what they
compute, so both give the same file bit for bit.
"""
from __future__ import annotations

import concurrent.futures
import math
import threading
import time

from .run import Block, Run

__all__ = ["InlineCalls", "Pipeline"]

# A handoff to the worker and back costs a few thread wake-ups; overlapping saves at most
# the shorter of a call and a drain.  Calls shorter than this run inline, so many tiny
# blocks (small rods, dense output) cost no more than serial calls.
HANDOFF = 5e-4    # seconds


class InlineCalls:
    """The call runs inside ``wait``, in the caller's thread: the same events, serially."""

    def __init__(self, run: Run, max_steps: int | None = None):
        self.run = run
        self.max_steps = max_steps
        self.busy = False

    def launch(self) -> None:
        self.busy = True

    def wait(self) -> Block:
        self.busy = False
        return self.run.take(self.run.compute(self.max_steps))

    def drain(self, block: Block, sink) -> None:
        self.run.drain(block, sink)

    def close(self) -> None:
        self.busy = False


class Pipeline:
    """The call runs in a worker thread from ``launch`` on, into the run's spare buffers, so
    the block ``wait`` returned before stays intact while the caller drains it.  A call
    runs inline instead when the last call or the last drain took less than ``HANDOFF``."""

    def __init__(self, run: Run, max_steps: int | None = None):
        run.double_buffer()
        self.run = run
        self.max_steps = max_steps
        self._pool = concurrent.futures.ThreadPoolExecutor(
            max_workers=1, thread_name_prefix="rodjit-loop")
        self._future: concurrent.futures.Future | None = None
        self._inline = False                           # the next call runs in ``wait``
        self._started = threading.Event()
        self._call_time = self._drain_time = math.inf  # of the last call and drain

    @property
    def busy(self) -> bool:
        return self._future is not None or self._inline

    def launch(self) -> None:
        """Start the next call and return once the worker runs it (the caller's next Python
        work, a drain, would otherwise hold the GIL the worker needs to begin); or leave it
        to ``wait`` if overlapping would not pay."""
        if self.busy:
            raise RuntimeError("a compiled call is already in flight")
        if min(self._call_time, self._drain_time) < HANDOFF:
            self._inline = True
            return
        self._started.clear()
        self._future = self._pool.submit(self._compute)
        self._started.wait()

    def _compute(self) -> int:
        self._started.set()
        return self.run.compute(self.max_steps)

    def wait(self) -> Block:
        before = self.run.run_time
        if self._inline:
            self._inline = False
            code = self.run.compute(self.max_steps)
        else:
            assert self._future is not None   # launched by the last ``launch``
            code = self._future.result()      # a signal handler runs while this waits
            self._future = None
        self._call_time = self.run.run_time - before
        return self.run.take(code)

    def drain(self, block: Block, sink) -> None:
        t0 = time.perf_counter()
        self.run.drain(block, sink)
        self._drain_time = time.perf_counter() - t0

    def close(self) -> None:
        """Wait for a call still in flight (its rows stay in the buffers, so the run is not
        ``drained`` and gets no checkpoint), then stop the worker."""
        if self._future is not None:
            concurrent.futures.wait([self._future])
            self._future = None
        self._inline = False
        self._pool.shutdown(wait=True)
