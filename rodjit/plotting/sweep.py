"""Figures of a sweep file: a summary column against one swept key (one line per value of
the others), and a heatmap over two swept keys with the rest held fixed."""
from __future__ import annotations

import itertools
import textwrap
from pathlib import Path

import numpy as np

from ..config import field_spec, parse_value
from ..output.cf import column_attrs
from ..sweeps.grid import format_value
from ..sweeps.point import SUMMARY_COLUMNS
from ..sweeps.sweep_table import SweepTable, dimension_names, load_sweep
from .mpl import NothingToDraw, new_figure, save
from .sweep_options import BadPlotOption

__all__ = ["KINDS", "sweep_figure", "plot_sweep_file"]

KINDS = ("restitution", "heatmap")
DEFAULT_QUANTITY = "restitution_first"
MAX_LINES = 24
MAX_PANELS = 6
MARKERS = "osD^vP*X"   # one per line, so lines can be told apart without colour
MAX_ANNOTATED = 15     # cells per side up to which a heatmap prints its values
_SYMBOLS = {"rod.mu": "μ", "rod.kappa": "κ", "rod.gamma": "γ", "floor.kappa_b": "κ_b",
            "floor.beta": "β", "gravity.g": "g", "rod.N": "N", "initial.height": "height",
            "initial.velocity": "v0", "initial.impact_speed": "impact speed"}


def _name(key: str) -> str:
    return _SYMBOLS.get(key, key)


def _unit(text: str | None) -> str:
    """`` [unit]`` for an axis label ('' for a key or column without one: text, flags)."""
    return f" [{text}]" if text else ""


def _key_label(key: str) -> str:
    """A swept key's axis label: its symbol, the key and its unit (``μ (rod.mu) [N s]``)."""
    name = _name(key)
    return (name if name == key else f"{name} ({key})") + _unit(field_spec(key).unit)


def _quantity_label(quantity: str) -> str:
    """A summary column's axis label with its unit, as the sweep file carries it."""
    return quantity + _unit(column_attrs("summary", quantity).get("units"))


def _title(ax, text: str) -> None:
    """The axes title, wrapped to the axes' width (a long description would run past the
    figure's edges)."""
    fig = ax.figure
    width_in = fig.get_figwidth() * ax.get_position().width
    chars = max(30, int(width_in * 72 / (9 * 0.6)))     # 9 pt characters, ~0.6 em wide
    lines = [textwrap.fill(part, chars, break_on_hyphens=False) for part in text.split("\n")]
    ax.set_title("\n".join(lines), fontsize=9)


def _check_quantity(quantity: str | None) -> str:
    quantity = quantity or DEFAULT_QUANTITY
    numeric = [c for c, (kind, _) in SUMMARY_COLUMNS.items() if kind != "str"]
    if quantity not in numeric:
        raise BadPlotOption("quantity", "quantity", quantity, ", ".join(numeric))
    return quantity


def _check_key(grid, key: str, option: str) -> str:
    """The swept key ``key`` (given for ``option``) names: the key itself (``rod.mu``) or
    its dimension name in ``SweepTable.to_xarray`` (``mu``)."""
    if key in grid.keys:
        return key
    by_dimension = {dim: k for k, dim in dimension_names(grid.keys).items()}
    if key in by_dimension:
        return by_dimension[key]
    raise BadPlotOption("not_swept", option, key,
                        ", ".join(f"{k} or {d}" if d != k else k
                                  for k, d in dimension_names(grid.keys).items()))


def _fixed(grid, at: dict, free: tuple[str, ...], default_first: bool) -> dict:
    """The value each non-free swept key is held at: from ``at`` (matched against the grid's
    values), else its first value when ``default_first``; keys left over vary."""
    out = {}
    for key, text in (at or {}).items():
        key = _check_key(grid, key, "at")
        if key in free:
            raise BadPlotOption("fixes_free", "at", key)
        values = grid.values[grid.keys.index(key)]
        value = parse_value(key, text) if isinstance(text, str) else text
        match = [v for v in values if v == value or (isinstance(v, float) and
                                                      isinstance(value, (int, float)) and
                                                      np.isclose(v, value, rtol=1e-12))]
        if not match:
            raise BadPlotOption("off_grid", "at", f"{key}={text}",
                                f"{key} = {', '.join(format_value(v) for v in values)}")
        out[key] = match[0]
    if default_first:
        for key, values in zip(grid.keys, grid.values):
            if key not in free and key not in out:
                out[key] = values[0]
    return out


def _select(table, fixed: dict) -> np.ndarray:
    mask = np.ones(len(table), bool)
    for key, value in fixed.items():
        mask &= table[key] == value
    return mask


def _scale(ax_set, values) -> None:
    """Log axis for positive values spanning two decades or more; symlog if 0 is among
    otherwise such values."""
    v = np.asarray(values, float)
    pos = v[v > 0]
    if pos.size >= 2 and pos.max() / pos.min() >= 100:
        if np.all(v > 0):
            ax_set("log")
        elif np.all(v >= 0):
            ax_set("symlog", linthresh=float(pos.min()))


def _label(quantity: str) -> str:
    return f"{quantity}: {SUMMARY_COLUMNS[quantity][1]}"


def _check_values(table, quantity, mask) -> None:
    """NothingToDraw when every value the figure would show is NaN."""
    values = np.asarray(table[quantity], float)[mask]
    if not np.any(np.isfinite(values)):
        failed = int(np.sum(table["status"][mask] == "failed"))
        raise NothingToDraw(f"every value of {quantity} in this figure is NaN ({values.size} "
                            f"points, {failed} failed); nothing to draw")


def _restitution(fig, table, quantity, x, at, ax=None, panels=None) -> None:
    grid = table.grid
    x = _check_key(grid, x, "x") if x else ("rod.mu" if "rod.mu" in grid.keys else grid.keys[0])
    if panels is not None:             # one panel per value of that key, side by side
        panels = _check_key(grid, panels, "panels")
        if panels == x or panels in (at or {}):
            raise BadPlotOption("panels_taken", "panels", panels)
        if ax is not None:
            raise ValueError("panels need a figure of their own (drop ax)")
        values = grid.values[grid.keys.index(panels)]
        if len(values) > MAX_PANELS:
            raise BadPlotOption("too_many_panels", "panels", panels,
                                f"{len(values)} values are too many panels (at most "
                                f"{MAX_PANELS})")
        axes = fig.subplots(1, len(values), sharey=True, squeeze=False)[0]
        for a, value in zip(axes, values):
            _restitution(fig, table, quantity, x, {**(at or {}), panels: value}, a)
        return
    fixed = _fixed(grid, at, (x,), default_first=False)
    others = [k for k in grid.keys if k != x and k not in fixed]
    combos = list(itertools.product(*(grid.values[grid.keys.index(k)] for k in others)))
    if len(combos) > MAX_LINES:
        raise BadPlotOption("too_many_lines", "",
                            f"{len(combos)} lines (one per value of {', '.join(others)})")
    ax = ax or fig.add_subplot()
    xs = np.asarray(grid.values[grid.keys.index(x)])
    base = _select(table, fixed)
    _check_values(table, quantity, base)
    import matplotlib

    colors = matplotlib.colormaps["viridis"](np.linspace(0.0, 0.85, max(1, len(combos))))
    marked = marked_stay = False
    for j, combo in enumerate(combos):
        mask = base & _select(table, dict(zip(others, combo)))
        order = np.argsort(table[x][mask])
        xv = np.asarray(table[x][mask])[order]
        yv = np.asarray(table[quantity][mask], float)[order]
        label = ", ".join(f"{_name(k)} = {format_value(v)}" for k, v in zip(others, combo))
        # a point whose rod never leaves the floor (restitution 0, contact time inf) is
        # marked as such, at its value or, infinite, at the top of the axes, and breaks
        # its line (no bounce to join to the bounces beside it)
        status = table.columns.get("impact_status")     # absent from format-1 files
        stays = (np.asarray(status[mask])[order] == "no lift-off" if status is not None
                 else np.zeros(xv.size, bool))
        ax.plot(xv, np.where(stays, np.nan, yv), MARKERS[j % len(MARKERS)] + "-", ms=5,
                lw=1.0, color=colors[j], label=label or None)
        if stays.any():
            top = ~np.isfinite(yv[stays])
            at_value = np.where(top, np.nan, yv[stays])
            ax.plot(xv[stays], at_value, "v", ms=8, mfc="none", mew=1.5, color=colors[j],
                    label=None if marked_stay else "no lift-off")
            if top.any():
                ax.plot(xv[stays][top], np.full(int(top.sum()), 0.97), "^", ms=8,
                        mfc="none", mew=1.5, color=colors[j],
                        transform=ax.get_xaxis_transform(), clip_on=False)
            marked_stay = True
        missing = ~np.isfinite(yv) & ~stays
        if missing.any():   # a point without a value is marked at the foot of the axes
            ax.plot(xv[missing], np.full(int(missing.sum()), 0.03), "x", ms=7, mew=1.5,
                    color=colors[j], transform=ax.get_xaxis_transform(), clip_on=False,
                    label=None if marked else "no value (NaN: failed, not run or undefined)")
            marked = True
    _scale(ax.set_xscale, xs)
    ax.set_xlabel(_key_label(x))
    ax.set_ylabel(_quantity_label(quantity))
    title = ", ".join(f"{_name(k)} = {format_value(v)}" for k, v in fixed.items())
    _title(ax, _label(quantity) + (f"\n{title}" if title else ""))
    if quantity.startswith("restitution"):
        ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
    if others or marked or marked_stay:
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)


def _heatmap(fig, table, quantity, x, y, at, ax=None) -> None:
    grid = table.grid
    varied = [k for k, v in zip(grid.keys, grid.values) if len(v) > 1 and k not in (at or {})]
    prefer = [k for k in ("floor.kappa_b", "floor.beta") if k in varied]
    rest = [k for k in varied if k not in prefer]
    pick = prefer + rest
    x = _check_key(grid, x, "x") if x else None
    y = _check_key(grid, y, "y") if y else None
    x = x or next((k for k in pick if k != y), None)
    y = y or next((k for k in pick if k != x), None)
    if x is None or y is None or x == y:
        raise BadPlotOption("no_heatmap_keys", "", "", ", ".join(grid.keys))
    fixed = _fixed(grid, at, (x, y), default_first=True)
    xs = list(grid.values[grid.keys.index(x)])
    ys = list(grid.values[grid.keys.index(y)])
    z = np.full((len(ys), len(xs)), np.nan)
    status = np.full((len(ys), len(xs)), "pending", dtype=object)
    mask = _select(table, fixed)
    _check_values(table, quantity, mask)
    for i in np.flatnonzero(mask):
        r, c = ys.index(table[y][i]), xs.index(table[x][i])
        z[r, c] = table[quantity][i]
        status[r, c] = table["status"][i]
    ax = ax or fig.add_subplot()
    mesh = ax.pcolormesh(np.ma.masked_invalid(z), cmap="viridis", shading="flat")
    ax.set_facecolor("0.85")
    fig.colorbar(mesh, ax=ax, label=_quantity_label(quantity))
    ax.set_xticks(np.arange(len(xs)) + 0.5, [format_value(v) for v in xs])
    ax.set_yticks(np.arange(len(ys)) + 0.5, [format_value(v) for v in ys])
    ax.set_xlabel(_key_label(x))
    ax.set_ylabel(_key_label(y))
    if len(xs) <= MAX_ANNOTATED and len(ys) <= MAX_ANNOTATED:
        finite = z[np.isfinite(z)]
        mid = (finite.min() + finite.max()) / 2 if finite.size else 0.0
        for r in range(len(ys)):
            for c in range(len(xs)):
                text = (f"{z[r, c]:.3g}" if np.isfinite(z[r, c]) else
                        "failed" if status[r, c] == "failed" else "-")
                color = "k" if not np.isfinite(z[r, c]) or z[r, c] > mid else "w"
                ax.text(c + 0.5, r + 0.5, text, ha="center", va="center", fontsize=7,
                        color=color)
    title = ", ".join(f"{_name(k)} = {format_value(v)}" for k, v in fixed.items())
    finite = z[np.isfinite(z)]
    same = ""
    if finite.size > 1 and finite.min() == finite.max():   # a colour scale of one value
        v = float(finite[0])
        half = 0.5 * abs(v) if v != 0 else 1.0
        mesh.set_clim(v - half, v + half)
        same = f" (every value {v:.4g})"
    _title(ax, _label(quantity) + same + (f"\nat {title}" if title else ""))


def sweep_figure(source, kind: str = "restitution", *, quantity=None, x=None, y=None,
                 at=None, panels=None, ax=None, figsize=None):
    """The matplotlib Figure of kind ``kind`` for a sweep file (path) or SweepTable; with
    ``ax``, drawn into that axes; ``panels`` (restitution): one panel per value of that
    key.  ``x``, ``y``, ``panels`` and the keys of ``at`` name swept keys as configuration
    keys (``rod.mu``) or as the dimension names of ``SweepTable.to_xarray`` (``mu``).
    NothingToDraw if every value shown would be NaN."""
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} is not allowed (one of {', '.join(KINDS)})")
    table = source if isinstance(source, SweepTable) else load_sweep(source)
    quantity = _check_quantity(quantity)
    at = {_check_key(table.grid, k, "at"): v for k, v in (at or {}).items()}
    fig = ax.figure if ax is not None else new_figure(figsize=figsize or (7.5, 4.8),
                                                      layout="constrained")
    if kind == "restitution":
        if y:
            raise BadPlotOption("heatmap_only", "y")
        _restitution(fig, table, quantity, x, at, ax, panels)
    else:
        if panels:
            raise BadPlotOption("restitution_only", "panels")
        _heatmap(fig, table, quantity, x, y, at, ax)
    if ax is None:
        fig.suptitle(f"sweep of {len(table)} points, N = {table.base.rod.N}", fontsize=10)
    return fig


def plot_sweep_file(path, output, kind: str = "restitution", *, dpi: int = 150,
                    figsize=None, **options) -> Path:
    """Draw figure ``kind`` of the sweep file ``path`` into the image file ``output`` (PNG,
    PDF or SVG by its suffix)."""
    return save(sweep_figure(path, kind, figsize=figsize, **options), output, dpi)
