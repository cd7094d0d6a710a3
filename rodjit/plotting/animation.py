"""An animation of a run: the rod drawn as it is, a vertical bar over the floor coloured
by its strain (or velocity), the floor's bending band down to −β, the time shown.

Frames are snapshots sampled evenly over the run and read one at a time as they are
drawn, so memory stays bounded however long the run.  GIF through Pillow, MP4 through
ffmpeg (when it is installed).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..records.datasets import strain_of
from .mpl import NothingToDraw, discard, need_matplotlib, new_figure, write_whole
from .source import RunSource

__all__ = ["animate", "FORMATS", "MissingWriter"]

FORMATS = (".gif", ".mp4")
QUANTITIES = ("strain", "v")


class MissingWriter(RuntimeError):
    """The movie format needs a program that is not installed (ffmpeg for MP4)."""


def frame_rows(n_snapshots: int, n_frames: int) -> np.ndarray:
    """Snapshot indices of ``n_frames`` frames spread evenly over ``n_snapshots``."""
    return np.unique(np.round(np.linspace(0, n_snapshots - 1, n_frames)).astype(int))


def animate(source, output, *, fps: int = 20, duration: float = 5.0,
            quantity: str = "strain", dpi: int = 100) -> Path:
    """Write an animation of the run ``source`` to ``output``: ``fps * duration`` frames
    (at most one per snapshot), read one snapshot at a time.

    Parameters
    ----------
    source : Result or str or os.PathLike
        The run, in memory or a run file.
    output : str or os.PathLike
        The movie: ``.gif`` (Pillow) or ``.mp4`` (ffmpeg, when installed).
    fps : int
        Frames per second, 1 to 120.
    duration : float
        Length of the movie in seconds.
    quantity : str
        What colours the rod: ``strain``, ``u`` or ``v``.
    dpi : int
        Resolution of the frames.

    Returns
    -------
    Path
        The file written.
    """
    output = Path(output)
    if output.suffix.lower() not in FORMATS:
        raise ValueError(f"output {str(output)!r}: the movie type is taken from the suffix, "
                         f"one of {', '.join(FORMATS)}")
    if not (isinstance(fps, int) and 1 <= fps <= 120):
        raise ValueError(f"fps = {fps!r} is out of range (whole number from 1 to 120)")
    if not (duration > 0):
        raise ValueError(f"duration = {duration!r} is out of range (seconds > 0)")
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity = {quantity!r} is not allowed (one of "
                         f"{', '.join(QUANTITIES)})")
    need_matplotlib()
    from matplotlib import animation
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    if output.suffix.lower() == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise MissingWriter("MP4 needs ffmpeg, which is not installed; write a .gif "
                                "instead or install ffmpeg")
        writer = animation.FFMpegWriter(fps=fps)
    else:
        writer = animation.PillowWriter(fps=fps)
    with RunSource(source) as src:
        n = src.n_snapshots()
        if n == 0:
            raise NothingToDraw("the run has no snapshots (output.snapshot_interval = 0); "
                                "nothing to animate")
        rows = frame_rows(n, max(1, int(round(fps * duration))))
        t = src.snapshot_times()
        c = src.config
        N = c.rod.N
        beta = c.floor.beta
        # the height range, from the frames' two ends only (one small read per frame)
        ends = np.array([src.snapshot_row("u", int(i))[[0, N]] for i in rows])
        top = float(ends.max()) * 1.05 + 0.05
        bottom = min(-1.6 * beta, float(ends.min()) - 0.2 * beta)
        fig = new_figure(figsize=(3.2, 5.0), layout="constrained")
        ax = fig.add_subplot()
        ax.axhspan(-beta, 0.0, color="0.75", label=f"floor's bending band (−β = {-beta:g})")
        ax.axhspan(bottom, -beta, color="0.45")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xlim(-0.5, 0.5)
        ax.set_ylim(bottom, top)
        ax.set_xticks([])
        ax.set_ylabel("height [m]")
        def frame_values(i):
            u = src.snapshot_row("u", int(i))
            values = strain_of(u, N) if quantity == "strain" else \
                (lambda v: (v[:-1] + v[1:]) / 2)(src.snapshot_row("v", int(i)))
            return u, values

        # the colour scale fitted to the frames (one row per frame, read once more): a
        # fixed scale made strains of a few per cent look white
        lim = max(float(np.nanmax(np.abs(frame_values(i)[1]), initial=0.0)) for i in rows)
        lim = lim * 1.05 if np.isfinite(lim) and lim > 0 else 1.0
        if quantity == "strain":
            cmap, label = "RdBu_r", "strain ε [1]"
        else:
            cmap, label = "PuOr", "velocity v [m s-1]"
        bar = LineCollection([], linewidths=14, cmap=cmap, norm=Normalize(-lim, lim),
                             capstyle="butt")
        ax.add_collection(bar)
        fig.colorbar(bar, ax=ax, label=label, shrink=0.8)
        # the time stamp is the axes' title, the legend below the axes: neither covers
        # the other nor the rod
        clock = ax.set_title("", fontsize=9)
        fig.legend(loc="outside lower center", fontsize=6)
        fig.suptitle(f"N = {N}, μ = {c.rod.mu:g}", fontsize=9)

        def draw(i):
            u, values = frame_values(i)
            segments = np.stack([np.stack([np.zeros(N), u[:-1]], 1),
                                 np.stack([np.zeros(N), u[1:]], 1)], 1)
            bar.set_segments(segments)
            bar.set_array(values)
            clock.set_text(f"t = {t[int(i)]:.3f} s")
            return bar, clock

        movie = animation.FuncAnimation(fig, draw, frames=rows, blit=False,
                                        cache_frame_data=False)
        try:
            write_whole(output, lambda path: movie.save(path, writer=writer, dpi=dpi))
        finally:
            discard(fig)
    return output
