"""The first-impact summary of a run as it drains: the sweep row's and the run file's side.

``ImpactTrack`` keeps the few diagnostics columns (``TRACK_COLUMNS``) and the episode rows
the first-impact observables need while a run's blocks go by (a sweep point, a run
writer) or reads them back from a file (``summarize``); ``impact_values`` turns them into
the ``IMPACT_COLUMNS`` of a sweep row or a run file's summary (``contacts.first_impact``
under ``physics.physics_for``), and ``impact_line`` into one line of a report.
"""
from __future__ import annotations

import math

import numpy as np

from .contacts import first_impact
from .physics import physics_for

__all__ = ["TRACK_COLUMNS", "ImpactTrack", "IMPACT_COLUMNS", "impact_values", "impact_line"]

# the diagnostics columns the first-impact observables read: a few floats per sample,
# whatever N is
TRACK_COLUMNS = ("t", "cm_velocity", "cm_height", "energy_kinetic", "energy_stretch",
                 "energy_bend", "u_bottom", "floor_force", "energy_total")


class ImpactTrack:
    """What the first-impact observables need of a run, kept as its blocks drain: the
    TRACK_COLUMNS of every diagnostics sample (9 floats, 72 bytes a sample, independent of
    N: 0.36 MB for the 5 s of the paper's runs at the default 1 ms interval) and the
    episode rows (2 floats each).  A sweep point and a run writer keep one beside their
    Extremes, ``summarize`` fills one from a file: the same numbers either way."""

    def __init__(self):
        from .columns import DIAG_COLUMNS

        self._idx = [DIAG_COLUMNS.index(c) for c in TRACK_COLUMNS]
        self._diag: list[np.ndarray] = []
        self._episodes: list[np.ndarray] = []

    def diagnostics(self, rows) -> None:
        """Keep the TRACK_COLUMNS of a block of diagnostics rows (``DIAG_COLUMNS``)."""
        rows = np.asarray(rows)
        if rows.shape[0]:
            self._diag.append(np.array(rows[:, self._idx], dtype=float))

    def episodes(self, rows) -> None:
        rows = np.asarray(rows)
        if rows.shape[0]:
            self._episodes.append(np.array(rows[:, :2], dtype=float))

    def read(self, f, n_diag: int, n_episodes: int) -> None:
        """Fill from the first rows of an open run file's diagnostics and episodes."""
        g = f["diagnostics"]
        if n_diag:
            self._diag.append(np.stack([np.asarray(g[c][:n_diag], float)
                                        for c in TRACK_COLUMNS], axis=1))
        e = f["episodes"]
        if n_episodes:
            self._episodes.append(np.stack([np.asarray(e[c][:n_episodes], float)
                                            for c in ("t_start", "t_end")], axis=1))

    def arrays(self) -> tuple[dict, dict]:
        """(diagnostics columns, episode columns) kept so far."""
        d = (np.concatenate(self._diag) if self._diag
             else np.zeros((0, len(TRACK_COLUMNS))))
        e = np.concatenate(self._episodes) if self._episodes else np.zeros((0, 2))
        return ({c: d[:, j] for j, c in enumerate(TRACK_COLUMNS)},
                {"t_start": e[:, 0], "t_end": e[:, 1]})


# the sweep summary columns of the first bounce: name -> (dtype, description)
IMPACT_COLUMNS: dict[str, tuple[str, str]] = {
    "restitution_first": ("float", "-w_release/w_impact of the first bounce (the first "
                                   "physical impact); 0 for no lift-off, NaN if open or no "
                                   "impact"),
    "impact_status": ("str", "first bounce: lift-off | no lift-off | open | no impact | "
                             "undefined"),
    "impact_reason": ("str", "why restitution_first is 0 or missing ('' for lift-off)"),
    "restitution_apex": ("float", "sqrt of rebound over drop apex height of the centre of "
                                  "mass above 1/2 for the first bounce"),
    "contact_time_first": ("float", "t_release - t_impact of the first bounce (inf: no "
                                    "lift-off)"),
    "w_impact": ("float", "centre-of-mass velocity at the first impact"),
    "rebound_speed": ("float", "largest centre-of-mass velocity from the first impact to "
                               "its release (to the end of the run without lift-off)"),
    "min_u0_impact": ("float", "deepest penetration min u_0 in the first bounce"),
    "vibration_ratio": ("float", "energy_vibration / (w_impact^2/2) at the first impact"),
}


def impact_values(config, t_final: float, u_final, track: ImpactTrack, bounces) -> dict:
    """The IMPACT_COLUMNS of a run from what ``track`` kept and its bounce table; status
    ``undefined`` with the reason when they cannot be evaluated (no diagnostics)."""
    out = {"restitution_first": math.nan, "impact_status": "undefined",
           "impact_reason": "", "restitution_apex": math.nan,
           "contact_time_first": math.nan, "w_impact": math.nan, "rebound_speed": math.nan,
           "min_u0_impact": math.nan, "vibration_ratio": math.nan}
    diag, episodes = track.arrays()
    try:
        phys = physics_for(config, t_final, u_final, diag, episodes, bounces)
        fi = first_impact(diag, episodes, bounces, phys)
    except ValueError as exc:
        out["impact_reason"] = str(exc)
        return out
    ratio = math.nan
    if fi.status != "no impact" and fi.w_impact:
        ratio = fi.energy_vibration_impact / (0.5 * fi.w_impact * fi.w_impact)
    out.update(restitution_first=fi.restitution, impact_status=fi.status,
               impact_reason=fi.reason, restitution_apex=fi.restitution_apex,
               contact_time_first=fi.contact_time, w_impact=fi.w_impact, rebound_speed=fi.rebound_speed,
               min_u0_impact=fi.min_u0, vibration_ratio=ratio)
    return out


def impact_line(values: dict) -> str:
    """One line for a report: 'first impact: e = 0.126 (lift-off), contact 0.0121 s, ...'
    or 'first impact: no lift-off (rebound speed 0.17 of impact)'."""
    st = values["impact_status"]
    if st == "lift-off":
        return (f"e = {values['restitution_first']:.4g} (lift-off), contact "
                f"{values['contact_time_first']:.4g} s, apex e = "
                f"{values['restitution_apex']:.4g}, penetration "
                f"{-values['min_u0_impact']:.4g}")
    if st == "no lift-off":
        ratio = values["rebound_speed"] / abs(values["w_impact"])
        return (f"e = 0 (no lift-off: rebound speed of the centre of mass {ratio:.3g} of "
                f"impact), penetration {-values['min_u0_impact']:.4g}")
    return f"{st}: {values['impact_reason']}"
