"""The one reading of what the per-point driver leaves (``stepping.trajectory.run_one``):
a batch's ``fout``, ``iout`` and bounce rows turned into a sweep's summary columns and
bounce tables, for the CPU engine (``sweeps.ensemble``) and the GPU engine (``gpu.engine``)
alike, so the two cannot disagree on what a column means.

It works on columns, not points: Python runs per point only where a point needs text (a
failure message, the reason of a first contact without lift-off, whose lift-off energy is
computed for those points only) and for the means over each point's bounce rows (NumPy's
``mean``, so they equal the per-point path's, ``point.bounce_values``, to the bit).
"""
from __future__ import annotations

from itertools import chain

import numpy as np

from ..driver.run import failure_text
from ..records.columns import BOUNCE_COLUMNS, columns_of
from ..records.impact import impact_columns
from ..records.observables import lift_energy
from ..stepping import impact_stream as S
from ..stepping import layout as L
from ..stepping import trajectory as T
from ..stepping.observers import observer_of

__all__ = ["summarize", "stopped", "take_rows", "bounce_tables", "point_lift_energy",
           "NONFINITE_MESSAGE"]

NONFINITE_MESSAGE = "a non-finite diagnostic value was computed; refusing to write it"


def stopped(iout) -> np.ndarray:
    """Which points (rows of ``iout``) stopped with their bounce rows full, to go on."""
    return iout[:, T.I_STOPPED] != 0


def summarize(values: dict, at, starts, fout, iout) -> None:
    """Fill the summary columns ``values`` at positions ``at`` (all but the timings and the
    bounce table's) from the rows of ``fout`` and ``iout`` of points that ended;
    ``starts[j]`` is the set-up (``driver.setup.Start``) of row ``j``."""
    at = np.asarray(at, dtype=np.int64)
    code = iout[:, T.I_CODE]
    values["steps"][at] = iout[:, T.I_STEPS]
    values["rejected_steps"][at] = iout[:, T.I_REJECTED]
    values["min_u0"][at] = fout[:, T.F_MIN_U0]
    values["max_floor_force"][at] = fout[:, T.F_MAX_FF]
    values["min_strain"][at] = fout[:, T.F_MIN_STRAIN]
    values["energy_error"][at] = fout[:, T.F_ENERGY_ERROR]
    values["t_final"][at] = fout[:, T.F_T_FINAL]
    values["status"][at] = np.where(code == L.DONE, "completed", "failed")
    if len(starts):       # the observer's values (the points share it: one family)
        ob = observer_of(starts[0].obs)
        for j, column in enumerate(ob.columns):
            values[column][at] = fout[:, T.F_OBSERVED + ob.size + j]
    impact_columns(values, at, fout[:, T.F_IMPACT:T.F_IMPACT + S.OUT_SIZE],
                   iout[:, T.I_IMPACT],
                   lambda j: point_lift_energy(starts[j].config, starts[j].rod))
    for j in map(int, np.flatnonzero(code != L.DONE)):
        s = starts[j]
        if code[j] == T.BAD_DIAGNOSTICS:
            text = NONFINITE_MESSAGE
        else:
            text = failure_text(fout[j, T.F_FAIL:T.F_FAIL + L.FAIL_SIZE],
                                float(fout[j, T.F_T_END]), s.ctrl, s.config, s.rod, s.floor)
        values["message"][at[j]] = text


def take_rows(rows_of: list, at, bout, iout, first=None) -> None:
    """Append to ``rows_of[at[j]]`` the bounce rows the last call wrote for row ``j`` of
    ``iout``: ``iout[j, I_BOUNCES]`` rows of ``bout`` from ``first[j]`` (by default
    ``iout[j, I_BSTART]``, where the CPU engine's batch kernel put them)."""
    if first is None:
        first = iout[:, T.I_BSTART]
    for j, k in enumerate(at):
        c = int(iout[j, T.I_BOUNCES])
        if c:
            s = int(first[j])
            rows_of[int(k)].append(bout[s:s + c])


def bounce_tables(values: dict, rows_of: list) -> tuple[dict, np.ndarray]:
    """The batch's bounce columns (``BOUNCE_COLUMNS``, point after point) from each point's
    blocks of rows ``rows_of[k]``, and each point's row count; the summary columns of the
    bounce tables (``point.bounce_values``) filled in ``values``."""
    counts = np.array([sum(map(len, rows)) for rows in rows_of], dtype=np.int64)
    blocks = list(chain.from_iterable(rows_of))
    rows = np.concatenate(blocks) if blocks else np.zeros((0, T.BOUT_SIZE))
    out = columns_of(rows, BOUNCE_COLUMNS)
    out["n_episodes"] = out["n_episodes"].astype(np.int64)
    out["open"] = out["open"] != 0.0
    out["ambiguous"] = out["ambiguous"] != 0.0
    _bounce_values(values, out, counts)
    return out, counts


def _bounce_values(values, bounces, counts) -> None:
    """``point.bounce_values`` of every point from the batch's bounce columns."""
    starts = np.cumsum(counts) - counts
    done = ~bounces["open"]
    sure = ~bounces["ambiguous"]
    e, e_energy = bounces["restitution"], bounces["restitution_energy"]
    for k in range(counts.size):
        s, c = int(starts[k]), int(counts[k])
        sl = slice(s, s + c)
        ok = sure[sl]
        values["n_bounces"][k] = c
        values["n_complete_bounces"][k] = int(done[sl].sum())
        if ok.any():
            values["restitution_mean"][k] = float(np.mean(e[sl][ok]))
            values["restitution_energy_mean"][k] = float(np.mean(e_energy[sl][ok]))
        if values["impact_status"][k] == "undefined" and c and not bounces["open"][s]:
            values["restitution_first"][k] = float(e[s])
            values["contact_time_first"][k] = float(bounces["t_release"][s]
                                                    - bounces["t_impact"][s])


_LIFT: dict = {}


def point_lift_energy(cfg, rod) -> float:
    """``lift_energy`` of a point of configuration ``cfg`` and rod law parameters ``rod``
    (a bisection in Python), cached by what it depends on: the rod law and its
    parameters, gravity and N."""
    key = (cfg.rod.law, rod, float(cfg.gravity.g), cfg.rod.N)
    try:
        return _LIFT[key]
    except (KeyError, TypeError):
        value = lift_energy(cfg)
        try:
            _LIFT[key] = value
        except TypeError:
            pass
        return value
