"""Headline numbers of a run, accumulated block by block from its diagnostics and bounces.

One definition serves the end-of-run report (read back from a file), ``Result`` and every
row of a sweep's summary, so the three always agree.
"""
from __future__ import annotations

import math
from typing import Mapping

import numpy as np

__all__ = ["RunMeasures"]


class RunMeasures:
    """Running energy-balance error and extremes (strain, bottom height, floor force).

    ``energy_error`` is max |E + dissipated − E0| / max(|E0|, max kinetic energy) over the
    diagnostics samples: the drift at μ = 0, the balance error at μ > 0 (MODEL.md §4).
    Values nothing was sampled for are NaN.
    """

    def __init__(self, energy0: float):
        self.energy0 = float(energy0)
        self.samples = 0
        self._err = 0.0
        self._kmax = 0.0
        self._min_strain = math.inf
        self._min_u0 = math.inf
        self._max_force = -math.inf

    def add_diagnostics(self, cols: Mapping[str, np.ndarray]) -> None:
        """A block of diagnostics rows, as columns (``energy_total``, ``u_bottom``, ...)."""
        n = len(cols["energy_total"])
        if n == 0:
            return
        self.samples += n
        self._err = max(self._err, float(np.max(np.abs(
            cols["energy_total"] + cols["dissipated"] - self.energy0))))
        self._kmax = max(self._kmax, float(np.max(cols["energy_kinetic"])))
        self._min_strain = min(self._min_strain, float(np.min(cols["min_strain"])))
        self._min_u0 = min(self._min_u0, float(np.min(cols["u_bottom"])))
        self._max_force = max(self._max_force, float(np.max(cols["floor_force"])))

    def add_bounces(self, cols: Mapping[str, np.ndarray]) -> None:
        """Bounce records: their extremes are taken between samples, at step resolution."""
        if len(cols["min_strain"]) == 0:
            return
        for values, name, pick in ((cols["min_strain"], "_min_strain", min),
                                   (cols["min_u0"], "_min_u0", min),
                                   (cols["max_floor_force"], "_max_force", max)):
            finite = values[np.isfinite(values)]
            if finite.size:
                extreme = float(np.min(finite) if pick is min else np.max(finite))
                setattr(self, name, pick(getattr(self, name), extreme))

    @property
    def energy_error(self) -> float:
        if self.samples == 0:
            return math.nan
        return self._err / max(abs(self.energy0), self._kmax, 1e-300)

    @property
    def min_strain(self) -> float:
        return self._min_strain if math.isfinite(self._min_strain) else math.nan

    @property
    def min_u0(self) -> float:
        return self._min_u0 if math.isfinite(self._min_u0) else math.nan

    @property
    def max_floor_force(self) -> float:
        return self._max_force if math.isfinite(self._max_force) else math.nan
