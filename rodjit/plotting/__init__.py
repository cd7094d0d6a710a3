"""Figures of runs and sweeps (``rodjit.plot``): node heights, energies, restitution per
bounce, space-time maps, the floor contact, animations of the rod; a summary column against
a key, heatmaps over two keys."""

from .dense import SparseSnapshots
from .mpl import MissingMatplotlib, NothingToDraw
from .run import KINDS, MAX_CURVES, MAX_POINTS, QUANTITIES, figure, plot_file

__all__ = ["KINDS", "MAX_CURVES", "MAX_POINTS", "QUANTITIES", "MissingMatplotlib",
           "NothingToDraw", "SparseSnapshots", "figure", "plot_file"]
