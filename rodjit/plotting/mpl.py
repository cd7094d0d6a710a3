"""matplotlib on demand: it lives in the ``plot`` extra, and figures are drawn without
pyplot, so nothing depends on a display or a backend."""
from __future__ import annotations

__all__ = ["MissingMatplotlib", "new_figure"]


class MissingMatplotlib(ImportError):
    pass


def new_figure(**kwargs):
    """A matplotlib Figure (not registered with pyplot), or MissingMatplotlib."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingMatplotlib("plotting needs matplotlib; install it with: "
                                "pip install 'rodjit[plot]'") from None
    return Figure(**kwargs)
