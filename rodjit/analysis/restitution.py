"""Restitution and contact time against impact speed, for one configuration or several: the
curve experiments on elastomers measure (restitution falling as the impact speed grows).

A curve is a sweep (the batch engine, its file, ``rodjit info``, ``--resume`` and plots)
over ``initial.impact_speed``, and over the keys that tell its lines apart (``compare``,
e.g. ``{"rod.mu": [10, 100, 1000]}``).  Every point starts ``start_height`` above the floor
with the velocity that a free fall needs to reach it at its impact speed
(``model.system.start_velocity``): the same impact as a drop from rest from
V²/(2|g|), without the steps of the fall.
"""
from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any, Callable, Mapping, Sequence

import numpy as np

from .._display import aligned
from ..config import Config
from ..sweeps.grid import Grid

if TYPE_CHECKING:
    from ..sweeps import SweepProgress, SweepTable

__all__ = ["restitution_curve", "curve_grid", "curve_report", "START_HEIGHT", "SPEED_KEY",
           "CURVE_COLUMNS"]

SPEED_KEY = "initial.impact_speed"
# where a point's rod starts above the floor [m]: its impact comes after at most
# √(2·0.01/9.81) = 45 ms of free fall (the rest of the fall is not computed)
START_HEIGHT = 0.01
# the summary columns a curve is read by (its table, its CSV)
CURVE_COLUMNS = ("impact_status", "w_impact", "restitution_first", "contact_time_first",
                 "restitution_apex", "rebound_speed", "min_u0_impact", "impact_reason")


def _positive(name: str, values) -> list[float]:
    out = []
    for v in values:
        x = float(v)
        if not (math.isfinite(x) and x > 0):
            raise ValueError(f"{name}: {v!r} is out of range (finite and > 0)")
        out.append(x)
    if not out:
        raise ValueError(f"{name}: give at least one value")
    return out


def _levels(name: str, values, key: str) -> list[float]:
    """Values as a list, or as ``"linspace(a, b, n)"``/``"logspace(a, b, n)"`` text."""
    if isinstance(values, str):
        if "space" in values:
            values = Grid.from_spec({key: values}).values[0]
        else:
            try:
                values = [float(x) for x in values.split(",") if x.strip()]
            except ValueError:
                raise ValueError(f"{name}: {values!r} is not a list of numbers (2,4,8) nor "
                                 f"linspace(a, b, n) or logspace(a, b, n)") from None
    return _positive(name, values)


def curve_grid(config: Config, speeds: Sequence[float] | str | None = None,
               heights: Sequence[float] | str | None = None,
               compare: Mapping[str, Any] | None = None,
               start_height: float = START_HEIGHT) -> tuple[Config, dict[str, Any]]:
    """The base configuration and the grid of a restitution curve.

    Parameters
    ----------
    config : Config
        The configuration of every point (its ``initial.height``, ``initial.velocity`` and
        ``initial.impact_speed`` are replaced).
    speeds : sequence of float or str, optional
        Impact speeds [m/s] (or ``"linspace(a, b, n)"``).
    heights : sequence of float or str, optional
        Drop heights of the bottom from rest [m] instead: V = √(2|g|h); needs g < 0.
    compare : mapping, optional
        Keys and values whose combinations are the curve's lines.
    start_height : float
        Where each point's bottom starts [m]; lowered to the smallest drop height if that
        is below it.

    Returns
    -------
    (Config, dict)
        The base configuration and the grid (``compare``'s keys, then
        ``initial.impact_speed``).

    Raises
    ------
    ValueError
        Neither or both of ``speeds`` and ``heights``, a value that is not finite and
        positive, heights without a downward gravity, or ``compare`` naming the
        initial keys the curve sets.
    """
    if (speeds is None) == (heights is None):
        raise ValueError("give the impact speeds or the drop heights (one of speeds, "
                         "heights)")
    g = float(config.gravity.g)
    if heights is not None:
        hs = _levels("heights", heights, "initial.height")
        if not g < 0:
            raise ValueError(f"heights need gravity.g < 0 (a fall), not {g!r}: give the "
                             f"impact speeds")
        vs = [math.sqrt(-2.0 * g * h) for h in hs]
    else:
        vs = _levels("speeds", speeds, SPEED_KEY)
    h0 = _positive("start_height", [start_height])[0]
    if g < 0:       # no point may start above its own drop height
        h0 = min(h0, min(vs) ** 2 / (-2.0 * g))
    compare = dict(compare or {})
    taken = [k for k in compare if k in ("initial.height", "initial.velocity", SPEED_KEY)]
    if taken:
        raise ValueError(f"compare: {taken[0]} is set by the curve itself (each point's "
                         f"start); compare other keys")
    base = config.override({"initial.height": h0, "initial.velocity": 0.0,
                            SPEED_KEY: None})
    return base, {**compare, SPEED_KEY: vs}


def restitution_curve(config: Config | None = None, *,
                      speeds: Sequence[float] | str | None = None,
                      heights: Sequence[float] | str | None = None,
                      compare: Mapping[str, Any] | None = None,
                      start_height: float = START_HEIGHT,
                      output: str | os.PathLike[str] | None = None, overwrite: bool = False,
                      jobs: int | None = None, scheduler: str | None = None,
                      progress: bool | Callable[[SweepProgress], object] | None = None,
                      command: str | None = None, device: str | None = None,
                      **limits: Any) -> SweepTable:
    """Restitution and contact time of the first bounce against impact speed, one line per
    combination of ``compare``'s values, on the sweep engine.

    ``table["initial.impact_speed"]`` is each point's impact speed, ``w_impact`` the
    centre of mass's velocity measured at the impact (−V to rounding),
    ``restitution_first``, ``contact_time_first`` and ``impact_status`` (``lift-off``;
    ``no lift-off``: the rod never leaves the floor, restitution 0, contact time inf;
    ``open``: still in contact at ``time.t_end``, run longer) as for any sweep;
    ``curve_report`` prints them, ``table.to_csv`` writes them,
    ``rodjit.plot(table, x="initial.impact_speed")`` draws them.

    Parameters
    ----------
    config : Config or None
        The configuration of every point; None is ``Config()``.  Its ``time.t_end`` must
        cover the contact and a flight after it.
    speeds, heights, compare, start_height
        As for ``curve_grid``.
    output : str or os.PathLike, optional
        The sweep file to write.
    overwrite, jobs, scheduler, progress, command, device
        As for ``rodjit.sweep``.
    **limits
        ``max_output``, ``max_steps``, ``max_points``, as for ``rodjit.sweep``.

    Returns
    -------
    SweepTable
    """
    from ..sweeps import sweep

    base, grid = curve_grid(Config() if config is None else config, speeds, heights,
                            compare, start_height)
    return sweep(base, grid, output=output, overwrite=overwrite, jobs=jobs,
                 scheduler=scheduler, progress=progress, device=device,
                 command=command or "rodjit.restitution_curve(...)", **limits)


def curve_report(table: SweepTable, columns: Sequence[str] = ("restitution_first",
                                                               "contact_time_first")) -> str:
    """The curve as text: per line (``compare``'s values), each impact speed's
    ``columns`` and its impact status, and the drop height the speed equals (g < 0).

    Parameters
    ----------
    table : SweepTable
        A curve, from ``restitution_curve`` or ``load_sweep`` of its file.
    columns : sequence of str
        The summary columns shown beside each speed.

    Returns
    -------
    str
        A header line and one line per point.
    """
    keys = [k for k in table.grid.keys if k != SPEED_KEY]
    g = float(table.base.gravity.g)
    head = [*keys, "impact_speed", *(["drop_height"] if g < 0 else []), *columns,
            "impact_status"]
    rows = []
    for i in range(len(table)):
        v = float(table[SPEED_KEY][i])
        cells = [f"{table[k][i]:g}" if isinstance(table[k][i], (float, np.floating))
                 else str(table[k][i]) for k in keys]
        cells.append(f"{v:.6g}")
        if g < 0:
            cells.append(f"{v * v / (-2.0 * g):.6g}")
        for c in columns:
            x = table[c][i]
            cells.append(f"{float(x):.6g}" if isinstance(x, (float, np.floating)) else str(x))
        status = str(table["impact_status"][i]) if table["status"][i] == "completed" \
            else str(table["status"][i])
        cells.append(status)
        rows.append(cells)
    return "\n".join(aligned(head, rows))
