"""Parameter sweeps: a grid of configurations run on every core or on a Dask cluster, one
summary row per point in one HDF5 file (``rodjit sweep`` on the command line)."""
from .errors import (BadGridItem, ResumeMismatch, RunsDirUnusable, SweepFileTooLarge,
                     SweepWriteFailed, TooManyPoints)
from .grid import Grid
from .main_guard import MissingMainGuard
from .plan import SweepPlan, plan_sweep
from .run_sweep import SweepFailed, SweepInterrupted, SweepProgress, sweep
from .sweep_table import SweepTable, load_sweep

__all__ = ["sweep", "Grid", "SweepTable", "load_sweep", "SweepInterrupted", "SweepProgress",
           "SweepFailed", "MissingMainGuard", "plan_sweep", "SweepPlan", "TooManyPoints",
           "BadGridItem", "SweepFileTooLarge", "RunsDirUnusable", "ResumeMismatch",
           "SweepWriteFailed"]
