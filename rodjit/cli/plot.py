"""``rodjit plot``: a figure of a run, sweep or convergence file."""
from __future__ import annotations

from typing import Any

import click

from . import options
from .exits import UsageError
from .files import (CONVERGENCE_KINDS, PLOT_KINDS, RUN_KINDS, SWEEP_KINDS, draw, file_kind,
                    is_convergence)
from .options import overrides

__all__ = ["plot_command", "plot_run", "plot_sweep", "parse_figsize", "parse_t_range"]


def parse_figsize(text: str | None) -> tuple[float, float] | None:
    """``--figsize W,H`` (inches) as a tuple, or None."""
    if text is None:
        return None
    try:
        w, h = (float(p) for p in text.split(","))
    except ValueError:
        raise UsageError(f"--figsize {text!r}: give WIDTH,HEIGHT in inches, e.g. 8,5") from None
    if not (0 < w <= 100 and 0 < h <= 100):
        raise UsageError(f"--figsize {text!r} is out of range (inches > 0 and <= 100)")
    return (w, h)


def parse_t_range(text: str) -> tuple[float, float] | str:
    """``--t-range T0,T1`` (seconds) as a tuple, or ``"impact"``."""
    if text.strip() == "impact":
        return "impact"
    from ..plotting.run import check_t_range

    try:
        t0, t1 = check_t_range(text.split(","))
    except ValueError:
        raise UsageError(f"--t-range {text!r} is out of range (T0,T1 in seconds with "
                         f"T0 < T1, e.g. 0.4,0.5, or 'impact')") from None
    return (float(t0), float(t1))


@click.command("plot")
@click.argument("file", type=click.Path(dir_okay=True))
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Image to write [default: FILE_KIND.png next to FILE].")
@click.option("--kind", type=click.Choice(PLOT_KINDS),
              help="Run files: heights (all nodes against time, the paper's figures; the "
                   "default), energy (components, and the drift or balance error), bounces "
                   "(restitution per bounce), spacetime (strain over time and x, contact "
                   "marked), contact (u_0 with -beta, and the floor force).  Sweep files: restitution "
                   "(against --x, one line per value of the other keys; the default), heatmap "
                   "(over two keys at --at values).  Convergence files: convergence (error "
                   "against the level, log-log).")
@click.option("--quantity", metavar="COLUMN",
              help="Run files: what spacetime colours (strain, u, v) [default: strain].  "
                   "Sweep files: the summary column drawn [default: restitution_first, the "
                   "first bounce's restitution, 0 without lift-off].")
@click.option("--x", "x_key", metavar="KEY", help="Sweep files: the key along the x axis, as "
              "the key (rod.mu) or its to_xarray dimension name (mu) [restitution: rod.mu "
              "if swept; heatmap: floor.kappa_b, then floor.beta].")
@click.option("--y", "y_key", metavar="KEY", help="Sweep heatmaps: the key along the y axis.")
@click.option("--at", "at", multiple=True, metavar="KEY=VALUE",
              help="Sweep files: fix another swept key (repeatable) [default for a heatmap: "
                   "the first value of each other key].")
@click.option("--panels", "panels", metavar="KEY", help="Sweep files (restitution): one "
              "panel per value of this swept key.")
@click.option("--t-range", "t_range", metavar="T0,T1|impact",
              help="Run files: the time window drawn, in seconds (e.g. 0.4,0.5), or "
                   "'impact' for the first impact [default: the whole run; heights adds a "
                   "panel with the first impact].")
@click.option("--dpi", type=click.IntRange(10, 2400), default=150, show_default=True,
              help="Resolution of PNG images.")
@click.option("--figsize", metavar="W,H", help="Figure size in inches, e.g. 8,5.")
@options.overwrite_option("Replace an existing image.")
def plot_command(file: str, output: str | None, kind: str | None, quantity: str | None,
                 x_key: str | None, y_key: str | None, at: tuple[str, ...],
                 panels: str | None, t_range: str | None, dpi: int, figsize: str | None,
                 overwrite: bool) -> None:
    """Draw a figure of a rodjit file (a run or a sweep) as PNG, PDF or SVG (by the suffix
    of -o)."""
    if is_convergence(file):
        if (kind not in (None, *CONVERGENCE_KINDS) or quantity or x_key or y_key or at
                or t_range):
            raise UsageError("a convergence file takes no --kind but 'convergence' and no "
                             "--quantity, --x, --y, --at or --t-range")
        from ..plotting.convergence import plot_convergence_file

        draw(plot_convergence_file, file, output, "convergence", overwrite)
        return
    kind_of_file = file_kind(file)
    style = {"dpi": dpi, "figsize": parse_figsize(figsize)}
    if kind_of_file == "run":
        if kind is not None and kind not in RUN_KINDS:
            raise UsageError(f"--kind {kind} is for sweep files; a run file takes one of "
                             f"{', '.join(RUN_KINDS)}")
        if x_key or y_key or at or panels:
            raise UsageError("--x, --y, --at and --panels are for sweep files")
        if quantity and kind != "spacetime":
            raise UsageError("--quantity is for --kind spacetime on a run file")
        window = {} if t_range is None else {"t_range": parse_t_range(t_range)}
        plot_run(file, output, kind or "heights",
                 dict(style, **window, **({"quantity": quantity} if quantity else {})),
                 overwrite)
        return
    if t_range is not None:
        raise UsageError("--t-range is for run files")
    if kind is not None and kind not in SWEEP_KINDS:
        raise UsageError(f"--kind {kind} is for run files; a sweep file takes one of "
                         f"{', '.join(SWEEP_KINDS)}")
    try:
        fixed = overrides(at, "--at")
    except ValueError as exc:
        raise UsageError(exc) from None
    plot_sweep(file, output, kind or "restitution",
               {"quantity": quantity, "x": x_key, "y": y_key, "at": fixed, "panels": panels,
                **style}, overwrite)


def plot_run(path: str, output: str | None, kind: str, plot_options: dict[str, Any],
             overwrite: bool = False) -> None:
    """Draw figure ``kind`` of the run file ``path`` into ``output``.

    Parameters
    ----------
    path : str
        The run file.
    output : str or None
        The image (default FILE_KIND.png).
    kind : str
        One of ``RUN_KINDS``.
    plot_options : dict
        Passed to ``plotting.plot_file``.
    overwrite : bool, optional
        Replace an existing image (otherwise refused in one line).
    """
    from ..plotting import plot_file

    draw(plot_file, path, output, kind, overwrite, **plot_options)


def plot_sweep(path: str, output: str | None, kind: str, plot_options: dict[str, Any],
               overwrite: bool = False) -> None:
    """Draw figure ``kind`` of the sweep file ``path`` into ``output``.

    Parameters
    ----------
    path : str
        The sweep file.
    output : str or None
        The image (default FILE_KIND.png).
    kind : str
        One of ``SWEEP_KINDS``.
    plot_options : dict
        Passed to ``plotting.sweep.plot_sweep_file``.
    overwrite : bool, optional
        Replace an existing image (otherwise refused in one line).
    """
    from ..plotting.sweep import plot_sweep_file

    draw(plot_sweep_file, path, output, kind, overwrite, **plot_options)
