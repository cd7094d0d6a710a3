"""Progress bars (tqdm; ``tqdm.auto`` gives a widget in notebooks, text on a terminal) for
runs and sweeps, and the one-time notice that the kernels are being compiled.

``progress`` arguments accept True (a bar), False/None (nothing) or a callable, which is
called as before (``progress(run)`` for runs, ``progress(SweepProgress)`` for sweeps).
"""
from __future__ import annotations

import os

__all__ = ["COMPILING", "kernels_cold", "RunBar", "SweepBar", "run_progress",
           "sweep_progress", "close"]

COMPILING = "compiling kernels (first run of an integrator only, about half a minute)…"


def kernels_cold(config=None) -> bool:
    """Whether the compiled time loop is not yet in Numba's disk cache (a fresh install):
    the first run then compiles for a while.  False for a ``config`` that runs on the loop
    the install compiled ahead of time (``stepping.aot``: nothing to compile), and when it
    cannot tell."""
    try:
        from ..stepping import aot, loop
        from .run import parameters

        if config is not None and aot.loop_for(parameters(config)) is not None:
            return False

        return not os.path.exists(loop.advance._cache._cache_file._index_path)
    except Exception:          # a Numba without these internals: say nothing
        return False


def _tqdm():
    from tqdm.auto import tqdm

    return tqdm


class RunBar:
    """A bar over simulated time, with the bounces and the compiled loop's step rate."""

    def __init__(self, file=None, leave: bool = True, cold: bool | None = None):
        cold = kernels_cold() if cold is None else cold
        self.bar = _tqdm()(total=1.0, desc=COMPILING if cold else "run",
                           unit="", file=file, leave=leave,
                           bar_format="{desc}{percentage:3.0f}%|{bar}|{postfix}")
        self.started = False

    def __call__(self, run) -> None:
        if not self.started:
            self.started = True
            self.bar.set_description("run", refresh=False)
        frac = min(1.0, max(0.0, run.t / run.t_end)) if run.t_end > 0 else 1.0
        rate = run.steps / run.run_time if run.run_time > 0 else 0.0
        self.bar.n = frac
        self.bar.set_postfix_str(f"t = {run.t:.4g} / {run.t_end:g} s, {run.bounces_total} "
                                 f"bounces, {rate:.3g} steps/s", refresh=False)
        self.bar.refresh()

    def close(self) -> None:
        self.bar.close()


class SweepBar:
    """A bar over a sweep's points, with the failures so far."""

    def __init__(self, file=None, leave: bool = True, cold: bool | None = None):
        cold = kernels_cold() if cold is None else cold
        self.bar = _tqdm()(total=None, desc=COMPILING if cold else "sweep",
                           file=file, leave=leave,
                           bar_format="{desc}{n_fmt}/{total_fmt} points |{bar}| "
                                      "{percentage:3.0f}%{postfix}")

    def __call__(self, p) -> None:
        if self.bar.total != p.total:
            self.bar.reset(total=p.total)
            self.bar.set_description("sweep", refresh=False)
        self.bar.n = p.done
        eta = "-" if p.eta != p.eta else duration(p.eta)
        self.bar.set_postfix_str(f"{p.failed} failed  {duration(p.elapsed)} elapsed, "
                                 f"{eta} left", refresh=False)
        self.bar.refresh()

    def close(self) -> None:
        self.bar.close()


def duration(seconds: float) -> str:
    """``m:ss`` or ``h:mm:ss``."""
    seconds = int(round(seconds))
    h, rem = divmod(seconds, 3600)
    m, s = divmod(rem, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


def run_progress(progress):
    """The callback for a run's ``progress`` argument (True: a RunBar)."""
    return RunBar() if progress is True else (progress or None)


def sweep_progress(progress):
    """The callback for a sweep's ``progress`` argument (True: a SweepBar)."""
    return SweepBar() if progress is True else (progress or None)


def close(callback, run=None) -> None:
    """Close ``callback`` if it is a bar, first showing where ``run`` ended (a user's
    callable is left alone)."""
    if isinstance(callback, RunBar) and run is not None:
        callback(run)
    if isinstance(callback, (RunBar, SweepBar)):
        callback.close()
