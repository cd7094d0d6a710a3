"""Running extremes of the diagnostics a run summary reports, updated block by block: by the
writer as it writes rows, by ``summarize`` as it reads them back, with the same numbers.

The energy error max |E + dissipated − E0| needs E0, which a new file learns only after its
first rows; it is kept as the largest and smallest E + dissipated instead.  Rounding is
monotone and symmetric, so max_i |fl(x_i − E0)| = max(fl(max x − E0), fl(E0 − min x))
exactly.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["Extremes"]


class Extremes:
    """Largest and smallest E + dissipated, largest kinetic energy, smallest strain and
    bottom height over the diagnostics rows seen."""

    COLUMNS = ("energy_total", "dissipated", "energy_kinetic", "min_strain", "u_bottom")
    BLOCK_ROWS = 1 << 16     # rows read at a time from a file

    def __init__(self):
        self.balance_max = -math.inf
        self.balance_min = math.inf
        self.kinetic_max = 0.0
        self.strain_min = math.inf
        self.u0_min = math.inf

    def update(self, total, dissipated, kinetic, min_strain, u_bottom) -> None:
        """Fold in a block of diagnostics columns (arrays of equal length)."""
        if len(total) == 0:
            return
        balance = total + dissipated
        self.balance_max = max(self.balance_max, float(np.max(balance)))
        self.balance_min = min(self.balance_min, float(np.min(balance)))
        self.kinetic_max = max(self.kinetic_max, float(np.max(kinetic)))
        self.strain_min = min(self.strain_min, float(np.min(min_strain)))
        self.u0_min = min(self.u0_min, float(np.min(u_bottom)))

    def read(self, group, n: int) -> None:
        """Fold in the first ``n`` rows of a diagnostics group of a run file, in blocks."""
        for i in range(0, n, self.BLOCK_ROWS):
            sel = slice(i, min(i + self.BLOCK_ROWS, n))
            self.update(*(group[c][sel] for c in self.COLUMNS))

    def energy_deviation(self, e0: float) -> float:
        """max |E + dissipated − e0| over the rows seen (0 if none)."""
        return max(0.0, self.balance_max - e0, e0 - self.balance_min)
