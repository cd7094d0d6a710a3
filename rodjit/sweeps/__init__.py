"""Parameter sweeps: a grid of configurations run on every core or on a Dask cluster, one
summary row per point in one HDF5 file (``rodjit sweep`` on the command line).

The names below are loaded on first use (``rodjit._lazy``): a sweep's worker process
imports ``rodjit.sweeps.pool`` or the Dask task's module and, through this package, only
what running its points needs."""
from typing import TYPE_CHECKING

from .. import _lazy

_WHERE = {
    "BadGridItem": ".errors", "ResumeMismatch": ".errors", "RunsDirUnusable": ".errors",
    "SweepFileTooLarge": ".errors", "SweepWriteFailed": ".errors", "TooManyPoints": ".errors",
    "Grid": ".grid",
    "MissingMainGuard": ".main_guard",
    "SweepPlan": ".plan", "plan_sweep": ".plan",
    "SweepFailed": ".run_sweep", "SweepInterrupted": ".run_sweep",
    "SweepProgress": ".run_sweep", "sweep": ".run_sweep",
    "SweepTable": ".sweep_table", "load_sweep": ".sweep_table",
}

if TYPE_CHECKING:      # what static tools and editors see: the same names, imported
    from .errors import (BadGridItem, ResumeMismatch, RunsDirUnusable, SweepFileTooLarge,
                         SweepWriteFailed, TooManyPoints)
    from .grid import Grid
    from .main_guard import MissingMainGuard
    from .plan import SweepPlan, plan_sweep
    from .run_sweep import SweepFailed, SweepInterrupted, SweepProgress, sweep
    from .sweep_table import SweepTable, load_sweep


# each public name loads from its module on first use; ``dir()`` lists them all before
__getattr__, __dir__ = _lazy.public_names(__name__, _WHERE)

__all__ = ["sweep", "Grid", "SweepTable", "load_sweep", "SweepInterrupted", "SweepProgress",
           "SweepFailed", "MissingMainGuard", "plan_sweep", "SweepPlan", "TooManyPoints",
           "BadGridItem", "SweepFileTooLarge", "RunsDirUnusable", "ResumeMismatch",
           "SweepWriteFailed"]
