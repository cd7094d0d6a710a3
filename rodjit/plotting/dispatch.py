"""``rodjit.plot``: one entry point for every figure, whatever the run or sweep is held in."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..output.h5files import file_kind
from ..records.result import Result
from ..sweeps.sweep_table import SweepTable
from . import run, sweep

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["plot"]


def plot(obj: Result | SweepTable | str | Path, kind: str | None = None, ax: Axes | None = None,
         **style: Any) -> Figure:
    """Draw ``obj`` — a ``Result``, a run file path, a sweep file path or a ``SweepTable``
    — as figure ``kind`` (runs: ``run.KINDS``, default heights; sweeps: ``sweep.KINDS``,
    default restitution) and return the matplotlib Figure (inline in Jupyter).  With
    ``ax``, the figure is drawn into that axes.

    Parameters
    ----------
    obj : Result or SweepTable or str or os.PathLike
        What to draw: a run in memory, a sweep table, or a run or sweep file.
    kind : str, optional
        The figure (runs: ``heights``, ``energy``, ``bounces``, ``spacetime``,
        ``contact``; sweeps: ``restitution``, ``heatmap``).
    ax : matplotlib.axes.Axes, optional
        Draw into this axes instead of a new figure.
    **style
        The figure's options (runs: quantity, t_range, figsize, dense; sweeps: quantity, x, y,
        at, panels, figsize).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if isinstance(obj, SweepTable):
        is_run = False
    elif isinstance(obj, Result):
        is_run = True
    elif isinstance(obj, (str, Path)):
        is_run = file_kind(obj) == "run"
    else:
        raise TypeError(f"rodjit.plot draws a Result, a SweepTable or a run or sweep file "
                        f"path, not {type(obj).__name__}")
    kinds = run.KINDS if is_run else sweep.KINDS
    if kind is not None and kind not in kinds:
        raise ValueError(f"kind = {kind!r} is not allowed for a {'run' if is_run else 'sweep'}"
                         f" (one of {', '.join(kinds)})")
    if is_run:
        return run.figure(obj, kind or "heights", ax=ax, **style)
    return sweep.sweep_figure(obj, kind or "restitution", ax=ax, **style)
