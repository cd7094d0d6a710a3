"""The ``rodjit`` command: a thin layer over ``run_to_file``, ``resume_file``, ``sweep``,
the analyses, the reports and the plots.

One module per verb (``run``, ``sweep``, ``presets``, ``config``, ``info``, ``plot``,
``animate``, ``converge``, ``fit``, ``restitution``); the options several verbs share are defined once in
``options``; ``exits`` holds the exit codes and the two one-line errors, ``say`` the
warning lines, ``wording`` how the command line words the API's typed errors (the API's
messages speak Python, the command line its options), ``group`` the ``rodjit`` group.

``info`` and ``plot`` dispatch on a file's ``rodjit_kind`` root attribute (``run``,
``sweep`` or ``convergence``): ``info`` prints ``reports.info`` (one path for every kind),
``plot`` checks that the figure asked for belongs to the file's kind.  Each command imports what it runs when it
runs, so ``rodjit --help`` and usage errors do not wait for NumPy, h5py and Numba to load.
Exit codes: 0 done, 1 the run failed (or a sweep point did), 2 usage or configuration error
(nothing written), 130/143 interrupted by SIGINT/SIGTERM (checkpoint written).
"""
from __future__ import annotations

from ..output.abandoned import quiet_disk_errors
from .animate import animate_command
from .config import config_command
from .converge import converge_command
from .exits import (EXIT_CODES, EXIT_FAILED, EXIT_OK, EXIT_SIGNAL, EXIT_USAGE, RunFailed,
                    UsageError, one_line)
from .files import CONVERGENCE_KINDS, PLOT_KINDS, RUN_KINDS, SWEEP_KINDS
from .fit import fit_command
from .group import main
from .info import info_command
from .options import DEFAULT_OUTPUT
from .plot import plot_command, plot_run, plot_sweep
from .presets import presets_command
from .restitution import restitution_command
from .run import run_command
from .say import say_warning
from .sweep import sweep_command

__all__ = ["main", "EXIT_OK", "EXIT_FAILED", "EXIT_USAGE", "EXIT_SIGNAL", "EXIT_CODES",
           "UsageError", "RunFailed", "one_line", "say_warning", "plot_run", "plot_sweep",
           "RUN_KINDS", "SWEEP_KINDS", "CONVERGENCE_KINDS", "PLOT_KINDS", "DEFAULT_OUTPUT"]


# h5py's reports of releasing files the disk refused say nothing the one-line error does
# not (``output.abandoned``, which imports no h5py)
quiet_disk_errors()

# the verbs, in the order the original module declared them (``rodjit --help`` sorts them)
for _command in (run_command, sweep_command, presets_command, config_command, info_command,
                 plot_command, animate_command, converge_command, fit_command,
                 restitution_command):
    main.add_command(_command)
del _command
