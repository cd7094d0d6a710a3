"""Running extremes of a run's diagnostics, updated block by block: by the writer as it
writes rows, by ``summarize`` as it reads them back, by a sweep point as its run drains, by
``Result.energy_error``: one definition, so all of them report the same numbers.

The energy error max |E + dissipated − E0| needs E0, which a new file learns only after its
first rows; it is kept as the largest and smallest E + dissipated instead.  Rounding is
monotone and symmetric, so max_i |fl(x_i − E0)| = max(fl(max x − E0), fl(E0 − min x))
exactly.
"""
from __future__ import annotations

import copy
import math

import numpy as np

from .columns import DIAG_COLUMNS

__all__ = ["Extremes"]


class Extremes:
    """Largest and smallest E + dissipated, largest kinetic energy and floor force,
    smallest strain and bottom height over the diagnostics rows seen (``samples``)."""

    COLUMNS = ("energy_total", "dissipated", "energy_kinetic", "min_strain", "u_bottom",
               "floor_force")
    ROW_INDICES = tuple(DIAG_COLUMNS.index(c) for c in COLUMNS)   # in a diagnostics row
    BLOCK_ROWS = 1 << 16     # rows read at a time from a file

    def __init__(self):
        self.samples = 0
        self.balance_max = -math.inf
        self.balance_min = math.inf
        self.kinetic_max = 0.0
        self.strain_min = math.inf
        self.u0_min = math.inf
        self.force_max = -math.inf

    def update(self, total, dissipated, kinetic, min_strain, u_bottom, floor_force) -> None:
        """Fold in a block of diagnostics columns (arrays of equal length, COLUMNS order)."""
        if len(total) == 0:
            return
        self.samples += len(total)
        balance = total + dissipated
        self.balance_max = max(self.balance_max, float(np.max(balance)))
        self.balance_min = min(self.balance_min, float(np.min(balance)))
        self.kinetic_max = max(self.kinetic_max, float(np.max(kinetic)))
        self.strain_min = min(self.strain_min, float(np.min(min_strain)))
        self.u0_min = min(self.u0_min, float(np.min(u_bottom)))
        self.force_max = max(self.force_max, float(np.max(floor_force)))

    def update_rows(self, rows) -> None:
        """Fold in a block of diagnostics rows as the run drains them (``DIAG_COLUMNS``)."""
        self.update(*(rows[:, j] for j in self.ROW_INDICES))

    def read(self, group, n: int) -> None:
        """Fold in the first ``n`` rows of a diagnostics group of a run file, in blocks."""
        for i in range(0, n, self.BLOCK_ROWS):
            sel = slice(i, min(i + self.BLOCK_ROWS, n))
            self.update(*(group[c][sel] for c in self.COLUMNS))

    def with_bounces(self, bounces) -> "Extremes":
        """A copy that also counts the extremes of the bounce records (taken at step
        resolution, between samples); NaN entries (an open bounce's release) are skipped."""
        out = copy.copy(self)
        for attr, col, pick in (("strain_min", "min_strain", min), ("u0_min", "min_u0", min),
                                ("force_max", "max_floor_force", max)):
            values = np.asarray(bounces[col], float)
            values = values[np.isfinite(values)]
            if values.size:
                best = float(values.min() if pick is min else values.max())
                setattr(out, attr, pick(getattr(out, attr), best))
        return out

    def energy_deviation(self, e0: float) -> float:
        """max |E + dissipated − e0| over the rows seen (0 if none)."""
        return max(0.0, self.balance_max - e0, e0 - self.balance_min)

    def energy_error(self, e0: float) -> float:
        """max |E + dissipated − E0| / max(|E0|, max kinetic energy): the drift at μ = 0, the
        balance error at μ > 0 (MODEL.md §4); NaN if no row was seen."""
        if self.samples == 0:
            return math.nan
        return self.energy_deviation(e0) / max(abs(e0), self.kinetic_max, 1e-300)
