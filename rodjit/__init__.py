"""rodjit: an elastic rod bouncing on a floor (Aiki & Kosugi), simulated fast and verified.

>>> import rodjit
>>> result = rodjit.simulate(rodjit.Config().override({"time.t_end": 1.0}))
>>> summary = rodjit.run_to_file(rodjit.Config(), "run.h5", overwrite=True)  # streamed to HDF5
>>> table = rodjit.sweep(rodjit.Config(), {"rod.mu": [0, 1, 10]}, output="sweep.h5")
"""
import os as _os
import sys as _sys
from typing import TYPE_CHECKING

from . import _lazy

# being located by ``python -m rodjit``, or imported by the installed ``rodjit`` command:
# handle SIGINT/SIGTERM before anything heavy is imported
if _sys.argv[:1] == ["-m"] or _os.path.basename(_sys.argv[0] if _sys.argv else "") in (
        "rodjit", "rodjit.exe"):
    from .driver.signals import install_early_handlers
    install_early_handlers(exit_now=True)

# Every public name is loaded on first use (PEP 562): ``import rodjit`` and the command
# line (a sweep's worker processes above all, each of which imports it) load only the
# modules their work needs; ``rodjit.X`` and ``from rodjit import X`` read as if all were
# imported here.
_WHERE = {
    "laws": ".laws", "observers": ".observers",
    "Convergence": ".analysis", "FitError": ".analysis", "FitResult": ".analysis",
    "TableFit": ".analysis", "converge": ".analysis", "fit": ".analysis",
    "fit_table": ".analysis", "load_convergence": ".analysis", "observables": ".analysis",
    "restitution_curve": ".analysis", "compare_laws": ".analysis",
    "LawComparison": ".analysis",
    "Config": ".config",
    "OutputExists": ".driver.files", "RunInterrupted": ".driver.files",
    "RunPlan": ".driver.files", "plan_run": ".driver.files", "resume_file": ".driver.files",
    "run_to_file": ".driver.files",
    "SimulationError": ".driver.run",
    "simulate": ".driver.simulate",
    "load_file": ".output.hdf5",
    "open_run": ".output.run_view",
    "animate": ".plotting.animation",
    "plot": ".plotting.dispatch",
    "load_preset": ".presets", "preset_names": ".presets",
    "Result": ".records.result",
    "MissingMainGuard": ".sweeps", "SweepFailed": ".sweeps", "SweepInterrupted": ".sweeps",
    "SweepPlan": ".sweeps", "SweepTable": ".sweeps", "load_sweep": ".sweeps",
    "plan_sweep": ".sweeps", "sweep": ".sweeps",
    "__version__": ".version",
}

if TYPE_CHECKING:      # what static tools and editors see: the same names, imported
    from . import laws, observers
    from .analysis import (Convergence, FitError, FitResult, TableFit, load_convergence)
    from .analysis.converge import converge
    from .analysis.fit import fit
    from .analysis.fit_table import fit_table
    from .analysis.observables import observables
    from .analysis.fit_table import LawComparison, compare_laws
    from .analysis.restitution import restitution_curve
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


# each public name loads from its module on first use; ``dir()`` lists them all before
__getattr__, __dir__ = _lazy.public_names(__name__, _WHERE)

__all__ = ["Config", "simulate", "Result", "SimulationError", "run_to_file", "resume_file",
           "load_file", "RunInterrupted", "OutputExists", "sweep", "load_sweep", "SweepTable",
           "load_preset", "preset_names", "SweepInterrupted", "SweepFailed", "MissingMainGuard",
           "open_run", "plot", "animate", "laws", "observers", "converge", "fit", "fit_table", "observables",
           "Convergence", "FitResult", "FitError", "TableFit", "load_convergence", "plan_run",
           "RunPlan", "plan_sweep", "SweepPlan", "restitution_curve", "compare_laws", "LawComparison",
           "__version__"]
