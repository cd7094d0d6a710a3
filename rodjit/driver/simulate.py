"""``simulate``: the one Python entry point for an in-memory run."""
from __future__ import annotations

from ..config import Config
from ..records.result import MemorySink, Result
from ..stepping import layout as L
from .progress import close as close_progress
from .progress import run_progress
from .run import Run, SimulationError

__all__ = ["simulate"]


def simulate(config=None, *, u0=None, v0=None, progress=None) -> Result:
    """Run ``config`` (default: the built-in run) to ``time.t_end`` and return the Result.

    ``u0``, ``v0`` optionally give initial heights and velocities (length ``rod.N + 1``).
    ``progress``: True for a progress bar (tqdm; a widget in notebooks, saying when the
    kernels are first compiled), or a callable, ``progress(run)``, called between
    compiled chunks.  Invalid input raises ValueError;
    a run that cannot continue raises SimulationError carrying the partial ``result``.
    """
    if config is None:
        config = Config()
    elif not isinstance(config, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(config).__name__}")
    run = Run(config, u0=u0, v0=v0)
    sink = MemorySink()
    progress = run_progress(progress)
    try:
        run.start(sink)
        while run.advance(sink) != L.DONE:
            if progress is not None:
                progress(run)
    except SimulationError as exc:
        exc.result = sink.result(run, status="failed", message=str(exc))
        raise
    finally:
        close_progress(progress, run)
    return sink.result(run)
