"""matplotlib on demand (it lives in the ``plot`` extra): figures go through pyplot when a
program uses it (so Jupyter shows them inline), and are plain Figures otherwise (the
command line: no display, no backend)."""
from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["MissingMatplotlib", "NothingToDraw", "new_figure", "discard", "save",
           "IMAGE_SUFFIXES"]

IMAGE_SUFFIXES = (".png", ".pdf", ".svg")


class MissingMatplotlib(ImportError):
    pass


class NothingToDraw(ValueError):
    """The data hold nothing the figure could show (no samples, every value NaN)."""


def new_figure(**kwargs):
    """A matplotlib Figure: from pyplot when it is imported (inline in notebooks), else a
    plain Figure; MissingMatplotlib without matplotlib."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingMatplotlib("plotting needs matplotlib; install it with: "
                                "pip install 'rodjit[plot]'") from None
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


def save(fig, output, dpi: int = 150) -> Path:
    """Write ``fig`` to ``output`` (PNG, PDF or SVG by its suffix)."""
    output = Path(output)
    if output.suffix.lower() not in IMAGE_SUFFIXES:
        raise ValueError(f"output {str(output)!r}: the image type is taken from the suffix, "
                         f"one of {', '.join(IMAGE_SUFFIXES)}")
    if not (isinstance(dpi, int) and 10 <= dpi <= 2400):
        raise ValueError(f"dpi = {dpi!r} is out of range (whole number from 10 to 2400)")
    fig.savefig(output, dpi=dpi)
    return output
