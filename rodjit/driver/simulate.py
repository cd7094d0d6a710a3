"""``simulate``: the one Python entry point for an in-memory run."""
from __future__ import annotations

from ..config import Config
from ..records.result import MemorySink, Result
from ..stepping import layout as L
from .run import Run, SimulationError, warn_config

__all__ = ["simulate"]


def simulate(config=None, *, u0=None, v0=None, progress=None) -> Result:
    """Run ``config`` (default: the built-in run) to ``time.t_end`` and return the Result.

    ``u0``, ``v0`` optionally give initial heights and velocities (length ``rod.N + 1``).
    ``progress(run)`` is called between compiled chunks.  Invalid input raises ValueError;
    a run that cannot continue raises SimulationError carrying the partial ``result``.
    A configuration with known limits (``Config.warnings``) issues ModelWarning.
    """
    if config is None:
        config = Config()
    elif not isinstance(config, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(config).__name__}")
    run = Run(config, u0=u0, v0=v0)
    warn_config(config)
    sink = MemorySink()
    try:
        run.start(sink)
        while run.advance(sink) != L.DONE:
            if progress is not None:
                progress(run)
    except SimulationError as exc:
        exc.result = sink.result(run, status="failed", message=str(exc))
        raise
    return sink.result(run)
