"""Where a run's compiled calls execute: inline, or in a worker thread while the caller
drains the block before (the kernels release the GIL, so on two cores writing the file
hides behind the loop instead of adding to it).

Both classes keep one protocol.  ``launch()`` starts the next call, ``wait()`` returns the
``Block`` it filled, ``busy`` is True between the two, ``close()`` waits for a call still in
flight.  Between ``wait`` and the next ``launch`` nothing touches the run: that is where the
caller looks at it, stops it, or checkpoints it (once the block is drained).  How calls are
placed never changes what they compute, so both give the same file bit for bit.
"""
from __future__ import annotations

import concurrent.futures
import threading

from .run import Block, Run

__all__ = ["Inline", "Pipeline"]


class Inline:
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

    def close(self) -> None:
        self.busy = False


class Pipeline:
    """The call runs in a worker thread from ``launch`` on, into the run's spare buffers, so
    the block ``wait`` returned before stays intact while the caller drains it."""

    def __init__(self, run: Run, max_steps: int | None = None):
        run.double_buffer()
        self.run = run
        self.max_steps = max_steps
        self._pool = concurrent.futures.ThreadPoolExecutor(
            max_workers=1, thread_name_prefix="rodjit-loop")
        self._future: concurrent.futures.Future | None = None
        self._started = threading.Event()

    @property
    def busy(self) -> bool:
        return self._future is not None

    def launch(self) -> None:
        """Start the next call and return once the worker runs it: the caller's next Python
        work (a drain) would otherwise hold the GIL the worker needs to begin."""
        if self._future is not None:
            raise RuntimeError("a compiled call is already in flight")
        self._started.clear()
        self._future = self._pool.submit(self._compute)
        self._started.wait()

    def _compute(self) -> int:
        self._started.set()
        return self.run.compute(self.max_steps)

    def wait(self) -> Block:
        code = self._future.result()      # a signal handler runs while this waits
        self._future = None
        return self.run.take(code)

    def close(self) -> None:
        """Wait for a call still in flight (its rows stay in the buffers, so the run is not
        ``drained`` and gets no checkpoint), then stop the worker."""
        if self._future is not None:
            concurrent.futures.wait([self._future])
            self._future = None
        self._pool.shutdown(wait=True)
