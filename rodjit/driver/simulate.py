"""``simulate``: the one Python entry point for an in-memory run."""
from __future__ import annotations

from typing import Any, Callable

from numpy.typing import ArrayLike

from ..config import Config
from ..output.estimate import MAX_OUTPUT, MAX_STEPS, check_run
from ..records.result import MemorySink, Result
from ..stepping import layout as L
from .progress import close as close_progress
from .progress import run_progress
from .run import Run, SimulationError, warn_config

__all__ = ["simulate"]


def simulate(config: Config | None = None, *, u0: ArrayLike | None = None,
             v0: ArrayLike | None = None,
             progress: bool | Callable[[Any], object] | None = None,
             max_output: float = MAX_OUTPUT, max_steps: float = MAX_STEPS) -> Result:
    """Run ``config`` (default: the built-in run) to ``time.t_end`` and return the Result.

    Parameters
    ----------
    config : Config, optional
        The run; ``None`` is ``Config()``, the built-in default.
    u0, v0 : array_like, optional
        Initial heights and velocities of the nodes (length ``rod.N + 1``); by default
        the uniform state of ``config.initial``.
    progress : bool or callable, optional
        True for a progress bar (tqdm; a widget in notebooks, saying when the kernels are
        first compiled), or a callable: ``progress(run)`` is called between compiled chunks.
    max_output : float, optional
        Refuse a run whose tables (snapshots, diagnostics) are estimated above this many
        bytes of memory: the estimate and the default limit of ``run_to_file``'s file
        (``output.estimate.check_run``), so a run too large for a file is too large here.
    max_steps : float, optional
        Refuse a fixed step that needs more steps than this (as ``run_to_file``).

    Returns
    -------
    Result
        Snapshots, diagnostics, contact episodes, bounces and run statistics, in memory.

    Raises
    ------
    ValueError
        Invalid input (before anything runs), a fixed ``time.dt`` below the resolution of
        t, one that does not divide the output intervals or needs more than ``max_steps``
        steps, or tables above ``max_output`` bytes.
    SimulationError
        A run that cannot continue; it carries the partial ``result``.

    Warns
    -----
    ModelWarning
        A configuration with known limits (``Config.warnings``).
    """
    if config is None:
        config = Config()
    elif not isinstance(config, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(config).__name__}")
    config = config.resolve()       # "auto": the integrator this run takes
    # the one estimate of every run (``rodjit run``'s): refused before anything is allocated
    check_run(config, None, max_output=max_output, max_steps=max_steps,
              what="the run's result (in memory)")
    run = Run(config, u0=u0, v0=v0)
    warn_config(config)
    sink = MemorySink(views=True)   # the run is ours: its last block needs no copy
    bar = run_progress(progress)
    try:
        run.start(None)   # the outputs at t0 wait in the buffers: one block
        while run.advance(sink) != L.DONE:
            sink.settle()     # the next call refills the buffers
            if bar is not None:
                bar(run)
    except SimulationError as exc:
        exc.result = sink.result(run, status="failed", message=str(exc))
        raise
    finally:
        close_progress(bar, run)
    return sink.result(run)
