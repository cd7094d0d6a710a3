"""Figures of rodjit files: runs (node heights, energies, restitution per bounce) and
sweeps (a summary column against a key, heatmaps over two keys)."""
from .mpl import MissingMatplotlib
from .run import KINDS, MAX_CURVES, MAX_POINTS, figure, plot_file

__all__ = ["KINDS", "MAX_CURVES", "MAX_POINTS", "MissingMatplotlib", "figure", "plot_file"]
