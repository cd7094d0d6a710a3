"""An animation of a run: the rod drawn as it is, a vertical bar over the floor coloured
by its strain (or velocity), the floor's bending band down to −β, the time shown.

Frames are snapshots sampled evenly over the run, except around impacts: each contact
gets ``FRAMES_PER_CONTACT`` frames spread over it (the movie runs in slow motion there;
the time stamp says so), so frames 50 ms apart do not skip a 12 ms impact.  Where the
snapshots are too sparse inside a contact, its frames are re-simulated from the snapshot
before (``plotting.dense``; a ``SparseSnapshots`` warning naming
``output.snapshot_interval`` where that is impossible).  Contacts take at most half the
frames: where ``FRAMES_PER_CONTACT`` each do not fit (a run of many bounces), they share
that half, ``MIN_FRAMES_PER_CONTACT`` each at least; where even that does not fit, a
``SparseSnapshots`` warning names the ``duration`` that shows them.  Snapshots are read one at a time as they are drawn, so memory stays bounded
however long the run.  GIF through Pillow, MP4 through ffmpeg (when it is installed).
"""
from __future__ import annotations

import math
import os
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..records.datasets import strain_of
from .dense import SparseSnapshots, contacts, samples
from .mpl import NothingToDraw, discard, need_matplotlib, new_figure, write_whole
from .source import RunSource

if TYPE_CHECKING:
    from ..records.result import Result

__all__ = ["animate", "FORMATS", "MissingWriter", "FRAMES_PER_CONTACT", "MAX_FRAMES"]

FORMATS = (".gif", ".mp4")
QUANTITIES = ("strain", "v")
FRAMES_PER_CONTACT = 12   # frames spread over each contact (from its start to its end)
MIN_FRAMES_PER_CONTACT = 4   # fewer than this each in half the movie: the contacts skipped
# the most frames a movie may ask for (8 min 20 s at 20 fps): the frame times are laid out
# before any is drawn, so ``fps * duration`` frames are arrays of that length (a duration
# of 1e9 s asked for 149 GiB), and a GIF's frames are held until it is written
MAX_FRAMES = 10_000


class MissingWriter(RuntimeError):
    """The movie format needs a program that is not installed (ffmpeg for MP4)."""


def frame_rows(n_snapshots: int, n_frames: int) -> np.ndarray:
    """Snapshot indices of ``n_frames`` frames spread evenly over ``n_snapshots``."""
    return np.unique(np.round(np.linspace(0, n_snapshots - 1, n_frames)).astype(int))


def frame_times(times: np.ndarray, spans: list, n_frames: int,
                per_contact: int = FRAMES_PER_CONTACT) -> tuple[np.ndarray, list, int]:
    """The times of ``n_frames`` frames of a run with snapshot ``times`` and contacts
    ``spans`` ``(t_impact, t_release)``, the contacts that needed frames of their own,
    and 0: ``per_contact`` frames over each contact shorter than ``per_contact`` even
    frames, the rest at snapshots spread evenly.  Where those contacts would take more
    than half the frames: half the frames shared among them, at least
    ``MIN_FRAMES_PER_CONTACT`` each; fewer than that: the even frames alone, the contacts
    skipped, and the number of frames that would show them with ``per_contact`` each."""
    even_only = times[frame_rows(times.size, n_frames)]
    gap = (times[-1] - times[0]) / max(1, n_frames - 1)
    short = [(a, b) for a, b in spans if b - a < (per_contact - 1) * gap]
    if not short:
        return even_only, [], 0
    need = per_contact * len(short)
    if need > n_frames // 2:
        # half the frames shared among the contacts, if that gives each a few (a run of
        # many bounces at the default length: fewer frames per contact, none skipped)
        fewer = (n_frames // 2) // len(short)
        if fewer < MIN_FRAMES_PER_CONTACT:
            return even_only, short, 2 * need
        short = [(a, b) for a, b in short if b - a < (fewer - 1) * gap]
        if not short:
            return even_only, [], 0
        per_contact, need = fewer, fewer * len(short)
    even = times[frame_rows(times.size, n_frames - need)]
    inside = np.concatenate([np.linspace(a, b, per_contact) for a, b in short])
    return np.sort(np.concatenate([even, inside])), short, 0


def movie_frames(src, n_frames: int, *, fps: int = 20, dense: bool = True):
    """``(samples, indices)``: the states a movie of ``n_frames`` frames of the run
    ``src`` (a ``RunSource``) draws, ``samples.t[indices]`` its frames' times (increasing;
    fewer than ``n_frames`` where two frames would show the same state).  ``fps`` only
    words the warning of a movie too short for its contacts."""
    t_all = src.snapshot_times()
    lo, hi = float(t_all[0]), float(t_all[-1])
    wanted, short, skipped = frame_times(t_all, contacts(src, lo, hi), n_frames)
    if skipped:
        gap = (hi - lo) / max(1, n_frames - 1)
        shortest = min(b - a for a, b in short)
        several = "s" if len(short) != 1 else ""
        warnings.warn(f"animate: {n_frames} frames {gap:.3g} s apart skip contacts as short "
                      f"as {shortest:.3g} s; {len(short)} such contact{several} with "
                      f"{FRAMES_PER_CONTACT} frames each need {skipped} frames or more: "
                      f"duration = {math.ceil(10 * skipped / fps) / 10:g} s or more at "
                      f"fps = {fps} shows them", SparseSnapshots, stacklevel=3)
    # the snapshots, with the states of sparse contacts re-simulated; each frame shows the
    # sample nearest its time
    s = samples(src, np.arange(t_all.size), lo, hi, dense=dense, what="animate",
                per_contact=FRAMES_PER_CONTACT, window=False,
                impacts=[] if skipped else short)
    if s.t.size == 1:
        return s, np.zeros(1, np.int64)
    k = np.clip(np.searchsorted(s.t, wanted), 1, s.t.size - 1)
    k = np.where(np.abs(s.t[k - 1] - wanted) <= np.abs(s.t[k] - wanted), k - 1, k)
    return s, np.unique(k)


def animate(source: Result | str | os.PathLike[str], output: str | os.PathLike[str], *,
            fps: int = 20, duration: float = 5.0,
            quantity: str = "strain", dpi: int = 100, dense: bool = True) -> Path:
    """Write an animation of the run ``source`` to ``output``: ``fps * duration`` frames
    (at most one per snapshot or re-simulated state), ``FRAMES_PER_CONTACT`` of them over
    each contact, read one snapshot at a time.

    Parameters
    ----------
    source : Result or str or os.PathLike
        The run, in memory or a run file.
    output : str or os.PathLike
        The movie: ``.gif`` (Pillow) or ``.mp4`` (ffmpeg, when installed).
    fps : int
        Frames per second, 1 to 120.
    duration : float
        Length of the movie in seconds, > 0; at most ``MAX_FRAMES`` frames.
    quantity : str
        What colours the rod: ``strain``, ``u`` or ``v``.
    dpi : int
        Resolution of the frames.
    dense : bool
        Re-simulate a contact whose snapshots are too sparse for its frames
        (``plotting.dense``); False uses the snapshots and warns.

    Returns
    -------
    Path
        The file written.

    Warns
    -----
    SparseSnapshots
        Frames that skip contacts (too few frames: the message names the number that
        shows them) or snapshots too sparse for a contact that could not be
        re-simulated (the message names ``output.snapshot_interval``).
    """
    output = Path(output)
    if output.suffix.lower() not in FORMATS:
        raise ValueError(f"output {str(output)!r}: the movie type is taken from the suffix, "
                         f"one of {', '.join(FORMATS)}")
    if not (isinstance(fps, int) and 1 <= fps <= 120):
        raise ValueError(f"fps = {fps!r} is out of range (whole number from 1 to 120)")
    if not (duration > 0) or not fps * duration <= MAX_FRAMES:
        raise ValueError(f"duration = {duration!r} is out of range (seconds > 0, at most "
                         f"{MAX_FRAMES / fps:g} at fps = {fps}: a movie has at most "
                         f"{MAX_FRAMES:,} frames)")
    if quantity not in QUANTITIES:
        raise ValueError(f"quantity = {quantity!r} is not allowed (one of "
                         f"{', '.join(QUANTITIES)})")
    need_matplotlib()
    from matplotlib import animation
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize

    writer: animation.AbstractMovieWriter
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
        s, rows = movie_frames(src, max(1, int(round(fps * duration))), fps=fps, dense=dense)
        t = s.t
        c = src.config
        N = c.rod.N
        beta = c.floor.beta
        # the height range, from the frames' two ends only (one small read per frame)
        ends = np.array([s.state(src, "u", int(i))[[0, N]] for i in rows])
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
            u = s.state(src, "u", int(i))
            values = strain_of(u, N) if quantity == "strain" else \
                (lambda v: (v[:-1] + v[1:]) / 2)(s.state(src, "v", int(i)))
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
            clock.set_text(f"t = {t[int(i)]:.4f} s")
            return bar, clock

        movie = animation.FuncAnimation(fig, draw, frames=rows, blit=False,
                                        cache_frame_data=False)
        try:
            write_whole(output, lambda path: movie.save(path, writer=writer, dpi=dpi))
        finally:
            discard(fig)
    return output
