"""matplotlib on demand (it lives in the ``plot`` extra): figures go through pyplot when a
program uses it (so Jupyter shows them inline), and are plain Figures otherwise (the
command line: no display, no backend)."""
from __future__ import annotations

import os
import sys
import zlib
from pathlib import Path

from .._extras import MissingExtra
from ..output.h5files import WriteFailed, disk_cause

__all__ = ["MissingMatplotlib", "NothingToDraw", "need_matplotlib", "new_figure", "discard", "save",
           "write_whole", "IMAGE_SUFFIXES"]

IMAGE_SUFFIXES = (".png", ".pdf", ".svg")


class MissingMatplotlib(MissingExtra):
    """matplotlib (the ``plot`` extra) is not installed; the message says how to install
    it."""


class NothingToDraw(ValueError):
    """The data hold nothing the figure could show (no samples, every value NaN)."""


def need_matplotlib() -> None:
    """MissingMatplotlib (naming the extra) unless matplotlib can be imported."""
    try:
        import matplotlib  # noqa: F401
        import matplotlib.figure  # noqa: F401
    except ImportError:
        raise MissingMatplotlib("plotting needs matplotlib; install it with: "
                                "pip install 'rodjit[plot]'") from None


def new_figure(**kwargs):
    """A matplotlib Figure: from pyplot when it is imported (inline in notebooks), else a
    plain Figure; MissingMatplotlib without matplotlib."""
    need_matplotlib()
    from matplotlib.figure import Figure

    if "matplotlib.pyplot" in sys.modules:
        return sys.modules["matplotlib.pyplot"].figure(**kwargs)
    return Figure(**kwargs)


def discard(fig) -> None:
    """Let pyplot forget ``fig`` (a figure drawn only into a file, like an animation's):
    otherwise a notebook's inline backend draws it again after the cell, after the data it
    read from are gone."""
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close(fig)            # a no-op for a figure pyplot does not manage


def write_whole(output, write) -> Path:
    """``write(path)`` into a temporary file beside ``output``, then renamed onto it: a disk
    that refuses the write (full, a file-size limit, an I/O error) leaves neither a partial
    picture nor a changed old one, and ends in WriteFailed with one line.  The temporary
    name keeps the suffix, from which matplotlib and Pillow take the format."""
    output = Path(output)
    part = output.with_name(f".{output.stem}.{os.getpid()}.part{output.suffix}")
    try:
        write(part)
        os.replace(part, output)
    except (OSError, zlib.error) as exc:       # zlib: a PDF stream cut by the failed write
        part.unlink(missing_ok=True)
        cause = disk_cause(exc) or str(exc)
        raise WriteFailed(f"writing {str(output)!r} failed: {cause}; nothing was written",
                          cause) from None
    except BaseException:
        part.unlink(missing_ok=True)
        raise
    return output


def save(fig, output, dpi: int = 150) -> Path:
    """Write ``fig`` to ``output`` (PNG, PDF or SVG by its suffix)."""
    output = Path(output)
    if output.suffix.lower() not in IMAGE_SUFFIXES:
        raise ValueError(f"output {str(output)!r}: the image type is taken from the suffix, "
                         f"one of {', '.join(IMAGE_SUFFIXES)}")
    if not (isinstance(dpi, int) and 10 <= dpi <= 2400):
        raise ValueError(f"dpi = {dpi!r} is out of range (whole number from 10 to 2400)")
    return write_whole(output, lambda path: fig.savefig(path, dpi=dpi))
