"""Observables of a run that are always defined (docs/MODEL.md §3), for a ``Result``.

The definitions are plain NumPy over a run's diagnostics, episode and bounce arrays and
live with the records (``rodjit.records.observables``), so that a sweep point can compute
them as its run drains; this module re-exports them and adds ``observables(result)``.
"""
from __future__ import annotations

from ..records.observables import (OBSERVABLES, STATUSES, FirstImpact, Physics,
                                   energy_vibration, first_impact, flight_groups, flight_time,
                                   lift_energy, macroscopic_contacts, merge_episodes,
                                   observables, physics_of, wave_speed)

__all__ = ["Physics", "physics_of", "wave_speed", "lift_energy", "energy_vibration",
           "merge_episodes", "macroscopic_contacts", "FirstImpact", "first_impact",
           "observables", "OBSERVABLES", "STATUSES", "flight_time", "flight_groups"]
