"""``gpu.kernel.deep_call``: a GPU compile's deep call chains get their room however the
machine schedules the compile thread."""
from __future__ import annotations

import sys
import threading

from rodjit.gpu import kernel


def _depth(n: int) -> int:
    return 0 if n == 0 else 1 + _depth(n - 1)


class _RunsAtOnce(threading.Thread):
    """A thread that has run to its end by the time ``start`` returns: the worst schedule
    for a caller that raises the recursion limit only after the start."""

    def start(self) -> None:
        super().start()
        self.join()


def test_the_recursion_limit_is_raised_before_the_compile_thread_runs(monkeypatch):
    monkeypatch.setattr(kernel.threading, "Thread", _RunsAtOnce)
    limit = sys.getrecursionlimit()
    deep = min(kernel.COMPILE_FRAMES - 500, 3 * limit)
    assert deep > limit
    assert kernel.deep_call(_depth, deep) == deep
    assert sys.getrecursionlimit() == limit         # restored


def test_an_error_on_the_compile_thread_is_raised_in_the_caller():
    def fails():
        raise ValueError("the cause")

    try:
        kernel.deep_call(fails)
    except ValueError as exc:
        assert str(exc) == "the cause"
    else:
        raise AssertionError("deep_call swallowed the error")
