"""Observers, the public way to watch a run from compiled code: ``Observer``, ``register``
and ``observer_kernel`` (``rodjit.stepping.observers`` documents the four functions an
observer is made of, and docs/extending.md walks through ``examples/custom_observer.py``).

A registered observer is chosen by ``output.observer``; its values are
``Result.observed``, columns of a sweep's summary (CPU and GPU engines) and entries of the
run file's checkpoint, and its ``stop`` ends a run on a condition of one's own.
"""
from ._jit import kernel as observer_kernel
from .stepping.observers import (NoObserver, Observer, get_observer, observer_names,
                                 register)

__all__ = ["Observer", "register", "observer_kernel", "get_observer", "observer_names",
           "NoObserver"]
