"""``rodjit animate``: a movie of a run file."""
from __future__ import annotations

from pathlib import Path

import click

from . import options
from .exits import RunFailed, UsageError
from .files import check_picture, file_kind

__all__ = ["animate_command"]


@click.command("animate")
@click.argument("file", type=click.Path(dir_okay=True))
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Movie to write, .gif or .mp4 (needs ffmpeg) [default: FILE.gif].")
@click.option("--fps", type=click.IntRange(1, 120), default=20, show_default=True,
              help="Frames per second.")
@click.option("--duration", type=click.FloatRange(0, None, min_open=True), default=5.0,
              show_default=True, help="Length of the movie in seconds (frames: fps x "
              "duration, at most 10,000, sampled evenly from the snapshots).")
@click.option("--quantity", type=click.Choice(("strain", "v")), default="strain",
              show_default=True, help="What colours the rod.")
@click.option("--dpi", type=click.IntRange(10, 600), default=100, show_default=True)
@options.overwrite_option("Replace an existing movie.")
def animate_command(file: str, output: str | None, fps: int, duration: float, quantity: str,
                    dpi: int, overwrite: bool) -> None:
    """A movie of a run file: the rod over the floor, coloured by strain."""
    kind = file_kind(file)
    if kind != "run":
        raise UsageError(f"{file!r} is a {kind} file; animate draws run files")
    from ..output.h5files import WriteFailed
    from ..plotting import MissingMatplotlib, NothingToDraw
    from ..plotting.animation import MissingWriter, animate

    out = output or str(Path(file).with_suffix(".gif"))
    check_picture(out, overwrite, file)
    try:
        written = animate(file, out, fps=fps, duration=duration, quantity=quantity, dpi=dpi)
    except MissingMatplotlib as exc:    # the plot extra: a usage error (install it), exit 2
        raise UsageError(exc) from None
    except (MissingWriter, NothingToDraw, WriteFailed) as exc:
        raise RunFailed(exc) from None
    except ValueError as exc:
        raise UsageError(exc) from None
    click.echo(f"wrote {written}")
