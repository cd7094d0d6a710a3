"""The statistics of a run (``Result.stats``): steps, timings and the scheme's counters,
built from a live run or from a checkpoint by the same function."""
from __future__ import annotations

import numpy as np

from ..stepping.registry import SCHEME_STATS

__all__ = ["run_stats", "node_steps_per_second"]


def node_steps_per_second(steps: int, nodes: int, run_time: float) -> float:
    """Accepted steps times nodes per second of stepping (0 before any was timed)."""
    return steps * nodes / run_time if run_time > 0 else 0.0


def run_stats(*, steps: int, rejected: int, compile_time: float, run_time: float,
              nodes: int, scheme_counts) -> dict:
    """The stats dict: ``steps``, ``rejected_steps``, ``wall_time`` (compiling and
    stepping), ``compile_time``, ``run_time``, ``node_steps_per_second`` and one entry per
    scheme counter (``SCHEME_STATS``) from ``scheme_counts`` (the run's ``sstats``)."""
    stats = {"steps": steps, "rejected_steps": rejected,
             "wall_time": compile_time + run_time, "compile_time": compile_time,
             "run_time": run_time,
             "node_steps_per_second": node_steps_per_second(steps, nodes, run_time)}
    if isinstance(scheme_counts, np.ndarray):
        scheme_counts = scheme_counts.tolist()   # Python ints in one call, not one per entry
    stats.update({name: int(v) for name, v in zip(SCHEME_STATS, scheme_counts)})
    return stats
