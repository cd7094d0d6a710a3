"""rodjit: an elastic rod bouncing on a floor (Aiki & Kosugi), simulated fast and verified.

>>> import rodjit
>>> result = rodjit.simulate(rodjit.Config().override({"time.t_end": 1.0}))
>>> summary = rodjit.run_to_file(rodjit.Config(), "run.h5", overwrite=True)  # streamed to HDF5
>>> table = rodjit.sweep(rodjit.Config(), {"rod.mu": [0, 1, 10]}, output="sweep.h5")
"""
import os as _os
import sys as _sys

# being located by ``python -m rodjit``, or imported by the installed ``rodjit`` command:
# handle SIGINT/SIGTERM before the heavy imports below
if _sys.argv[:1] == ["-m"] or _os.path.basename(_sys.argv[0] if _sys.argv else "") in (
        "rodjit", "rodjit.exe"):
    from .driver.signals import install_early_handlers
    install_early_handlers(exit_now=True)

from . import laws
from .analysis import (Convergence, FitError, FitResult, TableFit, converge, fit, fit_table,
                       load_convergence, observables)
from .config import Config
from .driver.files import (OutputExists, RunInterrupted, RunPlan, plan_run, resume_file,
                           run_to_file)
from .driver.run import SimulationError
from .driver.simulate import simulate
from .output.hdf5 import load_file
from .output.run_view import open_run
from .plotting.animation import animate
from .plotting.dispatch import plot
from .presets import load_preset, preset_names
from .records.result import Result
from .sweeps import (MissingMainGuard, SweepFailed, SweepInterrupted, SweepPlan, SweepTable,
                     load_sweep, plan_sweep, sweep)
from .version import __version__

__all__ = ["Config", "simulate", "Result", "SimulationError", "run_to_file", "resume_file",
           "load_file", "RunInterrupted", "OutputExists", "sweep", "load_sweep", "SweepTable",
           "load_preset", "preset_names", "SweepInterrupted", "SweepFailed", "MissingMainGuard",
           "open_run", "plot", "animate", "laws", "converge", "fit", "fit_table", "observables",
           "Convergence", "FitResult", "FitError", "TableFit", "load_convergence", "plan_run",
           "RunPlan", "plan_sweep", "SweepPlan", "__version__"]
