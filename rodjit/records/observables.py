"""Observables of a run that are always defined (docs/MODEL.md §3): the public module.

``observables(result)`` gives the scalar ``OBSERVABLES`` of a Result, with the status of
its first macroscopic contact (one of ``STATUSES``).  The definitions it rests on live in
modules of one job each, and every public name of theirs is importable from here too:

- ``records.physics``: the configuration's physical numbers, ``Physics``, ``physics_of``,
  ``physics_for``, ``wave_speed``, ``flight_time``, ``lift_energy``;
- ``records.contacts``: macroscopic contacts and the first impact from a run's arrays,
  ``energy_vibration``, ``merge_episodes``, ``flight_groups``, ``macroscopic_contacts``,
  ``FirstImpact``, ``first_impact``, ``STATUSES``;
- ``records.impact``: the first-impact columns of a sweep row, a run file's summary and a
  Result, from the one implementation of them (``stepping.impact_stream``):
  ``TRACK_COLUMNS``, ``IMPACT_COLUMNS``, ``NO_SAMPLES``, ``ImpactStream``, ``run_impact``,
  ``impact_columns``, ``impact_values``, ``impact_line``;
- here: ``observables``, ``OBSERVABLES``.
"""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from .contacts import (STATUSES, FirstImpact, energy_vibration, first_impact, flight_groups,
                       macroscopic_contacts, merge_episodes)
from .impact import (IMPACT_COLUMNS, NO_SAMPLES, TRACK_COLUMNS, ImpactStream, impact_columns,
                     impact_line, impact_values, run_impact)
from .physics import Physics, flight_time, lift_energy, physics_for, physics_of, wave_speed

if TYPE_CHECKING:
    from .result import Result

__all__ = ["Physics", "physics_of", "physics_for", "ImpactStream", "run_impact",
           "impact_columns", "impact_values", "flight_time", "IMPACT_COLUMNS", "NO_SAMPLES",
           "impact_line", "wave_speed", "lift_energy", "energy_vibration",
           "merge_episodes", "flight_groups", "macroscopic_contacts", "FirstImpact",
           "first_impact", "observables", "OBSERVABLES", "STATUSES", "TRACK_COLUMNS"]

# name -> description of the scalar observables ``observables`` returns
OBSERVABLES: dict[str, str] = {
    "restitution_first": "-w_release/w_impact of the first bounce (the first physical "
                         "impact); 0 if the rod never leaves the floor",
    "restitution_apex_first": "sqrt of rebound over drop apex height of the centre of mass "
                              "above 1/2 (g < 0; kinetic-energy ratio at g = 0)",
    "contact_time_first": "t_release - t_impact of the first macroscopic contact (inf: no "
                          "lift-off)",
    "rebound_speed_first": "largest centre-of-mass velocity from the first impact to its "
                           "release (to the end of the run without lift-off)",
    "min_u0_first": "deepest penetration min u_0 during the first macroscopic contact",
    "max_floor_force_first": "largest floor force during the first macroscopic contact",
    "vibration_share_first": "energy_vibration / (energy_vibration + w^2/2) at release of "
                             "the first macroscopic contact",
    "restitution_second": "-w_release/w_impact of the second macroscopic contact (0 if the "
                          "rod never leaves the floor again, NaN if there is none)",
    "contact_time_second": "t_release - t_impact of the second macroscopic contact",
    "min_u0": "lowest bottom height u_0 of the run",
    "max_floor_force": "largest floor force of the run",
}


def observables(result: Result, merge_time: float | None = None) -> dict[str, Any]:
    """The scalar OBSERVABLES of a Result, with ``status`` and ``reason`` of the first
    macroscopic contact.

    Parameters
    ----------
    result : Result
        A run, from ``simulate`` or ``load_file``.
    merge_time : float, optional
        The flight time τ [s] that ends a macroscopic contact; by default π h/c, the one
        the bounce table uses (``physics_of``).
    """
    phys = physics_of(result, merge_time)
    d = result.diagnostics
    rows = macroscopic_contacts(d, result.episodes, result.bounces, phys)
    fi = first_impact(d, result.episodes, result.bounces, phys, rows=rows)
    second = first_impact(d, result.episodes, result.bounces, phys, 1, rows=rows)
    ev, w = fi.energy_vibration_release, fi.w_release
    share = ev / (ev + 0.5 * w * w) if fi.status == "lift-off" else math.nan
    b = result.bounces
    min_u0 = min([float(np.min(d["u_bottom"]))] +
                 [float(x) for x in np.asarray(b["min_u0"])]) if d["t"].size else math.nan
    max_ff = max([float(np.max(d["floor_force"]))] +
                 [float(x) for x in np.asarray(b["max_floor_force"])]) if d["t"].size else math.nan
    return {"restitution_first": fi.restitution, "restitution_apex_first": fi.restitution_apex,
            "contact_time_first": fi.contact_time, "rebound_speed_first": fi.rebound_speed,
            "min_u0_first": fi.min_u0, "max_floor_force_first": fi.max_floor_force,
            "vibration_share_first": share, "restitution_second": second.restitution,
            "contact_time_second": second.contact_time, "min_u0": min_u0,
            "max_floor_force": max_ff,
            "status": fi.status, "reason": fi.reason}
