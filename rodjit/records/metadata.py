"""What each column of rodjit's tables means and in which unit: one source for the file
attributes (``long_name``, ``units``), ``Result.to_xarray`` and the documentation.

Units (docs/MODEL.md, "Units"): the model is written for a rod of natural length 1 and
mass 1, so every quantity is in the units its parameters are given in.  With the defaults
(``gravity.g = -9.81``) these read as SI for a rod of 1 m and 1 kg: heights in m, times in
s, velocities in m s-1, energies in J, forces (the stresses f and σ_b of a one-dimensional
rod are forces) in N; strains are dimensionless ("1").  The ``units`` strings follow
UDUNITS, as CF conventions ask.
"""
from __future__ import annotations

from typing import NamedTuple

from ..stepping.events import AMBIGUOUS_SPEED

__all__ = ["Meaning", "COLUMN_MEANINGS", "meaning", "UNIT_SYSTEM"]

UNIT_SYSTEM = ("the units of the parameters: SI (m, kg, s) for a rod of natural length 1 m "
               "and mass 1 kg with gravity.g in m s-2")


class Meaning(NamedTuple):
    long_name: str
    units: str


# by table ("snapshots", "diagnostics", "episodes", "bounces", "grid") and column name
COLUMN_MEANINGS: dict[str, dict[str, Meaning]] = {
    "grid": {
        "x": Meaning("natural position along the rod (0: bottom end, 1: top end)", "m"),
    },
    "snapshots": {
        "t": Meaning("time", "s"),
        "step": Meaning("number of accepted steps taken", "1"),
        "u": Meaning("height of the material point", "m"),
        "v": Meaning("velocity of the material point", "m s-1"),
    },
    "diagnostics": {
        "t": Meaning("time", "s"),
        "dt": Meaning("proposed next time step", "s"),
        "energy_kinetic": Meaning("kinetic energy", "J"),
        "energy_stretch": Meaning("elastic (stretch) energy of the rod", "J"),
        "energy_bend": Meaning("bending energy of the rod", "J"),
        "energy_floor": Meaning("elastic energy stored in the floor", "J"),
        "energy_gravity": Meaning("gravitational potential energy", "J"),
        "energy_total": Meaning("total discrete energy", "J"),
        "dissipated": Meaning("energy dissipated (viscosity, floor damping) since the start",
                              "J"),
        "u_bottom": Meaning("height of the bottom end u_0", "m"),
        "floor_force": Meaning("elastic upward floor force sigma_b(u_0) (floor.damping "
                               "not included)", "N"),
        "min_strain": Meaning("smallest segment strain", "1"),
        "cm_height": Meaning("height of the centre of mass", "m"),
        "cm_velocity": Meaning("velocity of the centre of mass", "m s-1"),
    },
    "episodes": {
        "t_start": Meaning("start of the contact episode (u_0 < 0)", "s"),
        "t_end": Meaning("end of the contact episode", "s"),
    },
    "bounces": {
        "t_impact": Meaning("start of the bounce's first contact episode", "s"),
        "t_release": Meaning("end of the bounce's last contact episode", "s"),
        "n_episodes": Meaning("contact episodes in the bounce", "1"),
        "w_impact": Meaning("centre-of-mass velocity at impact", "m s-1"),
        "w_release": Meaning("centre-of-mass velocity at release", "m s-1"),
        "restitution": Meaning("coefficient of restitution -w_release/w_impact", "1"),
        "min_u0": Meaning("lowest bottom height during the bounce", "m"),
        "max_floor_force": Meaning("largest elastic floor force during the bounce", "N"),
        "min_strain": Meaning("smallest segment strain during the bounce", "1"),
        "energy_vibration_impact": Meaning("vibration energy about the centre of mass at "
                                           "impact", "J"),
        "restitution_energy": Meaning("energy restitution w_release / sqrt(w_impact^2 + "
                                      "2 energy_vibration_impact)", "1"),
        "ambiguous": Meaning("restitution not an impact's (open, unfinished, not falling "
                             f"or approach slower than {AMBIGUOUS_SPEED:g} of the vibration "
                             "speed)", "1"),
        "open": Meaning("bounce still in contact when the run stopped", "1"),
    },
}


def meaning(table: str, column: str) -> Meaning:
    """The long name and unit of one column; KeyError names the table and column."""
    try:
        return COLUMN_MEANINGS[table][column]
    except KeyError:
        raise KeyError(f"no description of column {column!r} of table {table!r}") from None


# the sweep file's summary columns after the swept keys (whose unit is the key's own,
# ``config.field_spec``); their longer descriptions are ``sweeps.point.SUMMARY_COLUMNS``
COLUMN_MEANINGS["summary"] = {
    "status": Meaning("status of the point (completed, failed, pending)", ""),
    "message": Meaning("why the point failed", ""),
    "n_bounces": Meaning("bounces recorded", "1"),
    "n_complete_bounces": Meaning("bounces whose last contact episode ended", "1"),
    "restitution_mean": Meaning("mean restitution over the bounces not marked ambiguous",
                                "1"),
    "restitution_energy_mean": Meaning("mean energy restitution over the bounces not "
                                       "marked ambiguous", "1"),
    "min_u0": Meaning("lowest bottom height u_0", "m"),
    "max_floor_force": Meaning("largest elastic floor force sigma_b(u_0)", "N"),
    "min_strain": Meaning("smallest segment strain", "1"),
    "energy_error": Meaning("relative energy error", "1"),
    "steps": Meaning("accepted steps", "1"),
    "rejected_steps": Meaning("rejected trial steps", "1"),
    "wall_time": Meaning("wall time of the point in its worker", "s"),
    "compile_time": Meaning("wall time compiling or loading kernels", "s"),
    "run_time": Meaning("wall time stepping in compiled code", "s"),
    "t_final": Meaning("simulated time reached", "s"),
    "run_file": Meaning("the point's run file", ""),
    # the first bounce (records.impact.IMPACT_COLUMNS)
    "restitution_first": Meaning("restitution of the first bounce, the first physical "
                                 "impact (0: no lift-off)", "1"),
    "impact_status": Meaning("outcome of the first bounce (lift-off, no lift-off, open, no "
                             "impact, undefined)", ""),
    "impact_reason": Meaning("why restitution_first is 0 or missing", ""),
    "restitution_apex": Meaning("apex-height restitution of the first bounce", "1"),
    "contact_time_first": Meaning("contact time of the first bounce", "s"),
    "w_impact": Meaning("centre-of-mass velocity at the first impact", "m s-1"),
    "rebound_speed": Meaning("largest centre-of-mass velocity after the first impact",
                             "m s-1"),
    "min_u0_impact": Meaning("deepest penetration in the first bounce", "m"),
    "vibration_ratio": Meaning("vibration energy over the rigid-body kinetic energy at the "
                               "first impact", "1"),
}
