"""Figures of a run (a ``Result`` or a run file): node heights (the paper's figures),
energies, restitution per bounce, the space-time map of strain (or height, velocity), and
the bottom's contact with the floor.

Units are those of ``records.metadata`` (SI for a rod of 1 m and 1 kg with the defaults).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..records.datasets import strain_of
from ..records.metadata import meaning
from .dense import contacts
from .dense import samples as sample
from .mpl import MissingMatplotlib, NothingToDraw, new_figure, save
from .source import MAX_POINTS, RunSource

__all__ = ["KINDS", "QUANTITIES", "figure", "plot_file", "impact_window", "check_t_range",
           "MissingMatplotlib"]

KINDS = ("heights", "energy", "bounces", "spacetime", "contact")
QUANTITIES = ("strain", "u", "v")      # what a space-time map colours
MAX_CURVES = 11        # node curves drawn at most (evenly spaced along the rod)
MAX_ROWS = 2_000       # snapshot rows a space-time map draws at most (strided)

_ENERGY = (("energy_kinetic", "kinetic"), ("energy_stretch", "stretch"),
           ("energy_bend", "bending"), ("energy_floor", "floor"),
           ("energy_gravity", "gravity"))


def _label(symbol: str, table: str, column: str) -> str:
    """``symbol [units]`` with the unit of ``records.metadata``."""
    units = meaning(table, column).units
    return f"{symbol} [{units}]" if units != "1" else symbol


def _title(config) -> str:
    return (f"N = {config.rod.N}, μ = {config.rod.mu:g}, κ = {config.rod.kappa:g}, "
            f"κ_b = {config.floor.kappa_b:g}, β = {config.floor.beta:g}")


def figure(source, kind: str = "heights", *, ax=None, quantity: str = "strain",
           t_range=None, figsize=None, dense: bool = True):
    """The matplotlib Figure of kind ``kind`` for a run.

    Parameters
    ----------
    source : Result or str or os.PathLike
        A run in memory, or a run file (read lazily, strided to ``MAX_POINTS`` rows).
    kind : str
        One of ``KINDS``: ``"heights"`` (node heights, the paper's figures),
        ``"energy"``, ``"bounces"`` (restitution per bounce), ``"spacetime"``,
        ``"contact"``.
    ax : matplotlib.axes.Axes, optional
        Draw into this axes (its figure is returned) instead of a new figure.
    quantity : str
        What ``spacetime`` colours, one of ``QUANTITIES`` (``"strain"``, ``"u"``, ``"v"``).
    t_range : tuple of float or "impact", optional
        ``(t0, t1)`` [s]: the part of the time axis drawn; ``"impact"``: the first
        impact, from half its duration before the floor is reached to half after the
        release (``impact_window``).  By default the whole run, and ``heights`` in a new
        figure adds a second panel with the first impact (an impact of 12 ms is a
        vertical line at the scale of a 5 s run).
    figsize : tuple of float, optional
        Size of a new figure in inches (default 7.5 × 4.5; 11 × 4.5 with the impact panel).
    dense : bool
        ``spacetime``: where the snapshots are too sparse for a contact or for the window
        (fewer than ``dense.MIN_SAMPLES``), draw the solution re-simulated there from the
        snapshot before at a finer interval (``plotting.dense``); False draws the
        snapshots only and warns.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        An unknown ``kind`` or ``quantity``, or a ``t_range`` that is not two finite
        times in increasing order or ``"impact"``.
    NothingToDraw
        The run has no data for ``kind`` (e.g. snapshots switched off), or
        ``t_range = "impact"`` and the rod never reached the floor.
    MissingMatplotlib
        matplotlib is not installed (the ``[plot]`` extra).

    Warns
    -----
    SparseSnapshots
        ``spacetime`` drew snapshots too sparse for a contact or the window (re-simulation
        off or impossible); the message names the ``output.snapshot_interval`` needed.
    """
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} is not allowed (one of {', '.join(KINDS)})")
    if kind == "spacetime" and quantity not in QUANTITIES:
        raise ValueError(f"quantity = {quantity!r} is not allowed (one of "
                         f"{', '.join(QUANTITIES)})")
    t_range = check_t_range(t_range)
    with RunSource(source) as src:
        if t_range == "impact":
            t_range = impact_window(src)
        # the default heights figure: the whole run and its first impact side by side
        zoom = (kind == "heights" and ax is None and t_range is None
                and src.n_snapshots() > 0 and first_impact_span(src) is not None)
        if ax is None:
            size = figsize or ((11.0, 4.5) if zoom else (7.5, 4.5))
            fig = new_figure(figsize=size, layout="constrained")
        else:
            fig = ax.figure
        if zoom:
            ax, ax_impact = fig.subplots(1, 2, width_ratios=(2, 1))
        draw = {"heights": _heights, "energy": _energy, "bounces": _bounces,
                "spacetime": _spacetime, "contact": _contact}[kind]
        axes = draw(src, fig, ax, quantity=quantity, t_range=t_range, dense=dense,
                    legend=not zoom)
        axes[0].set_title(_title(src.config), fontsize=10)
        if zoom:
            _impact_panel(src, fig, ax_impact, dense)
    return fig


def check_t_range(t_range):
    """``t_range`` as ``figure`` takes it: None, ``"impact"`` or ``(t0, t1)`` of finite
    floats with t0 < t1 (a ``ValueError`` naming ``t_range`` otherwise)."""
    if t_range is None or (isinstance(t_range, str) and t_range == "impact"):
        return t_range
    try:
        t0, t1 = (float(x) for x in t_range)
    except (TypeError, ValueError):
        raise ValueError(f"t_range = {t_range!r} is not allowed (two times (t0, t1) in "
                         f"seconds, or 'impact')") from None
    if not (np.isfinite(t0) and np.isfinite(t1) and t0 < t1):
        raise ValueError(f"t_range = {t_range!r} is out of range (finite times with "
                         f"t0 < t1, in seconds)")
    return (t0, t1)


def first_impact_span(src):
    """``(t_impact, t_release)`` of the run's first impact (one still in contact at the
    end: until the last snapshot), or None where the rod never reached the floor."""
    found = contacts(src, -np.inf, np.inf)
    return found[0] if found else None


def impact_window(src) -> tuple[float, float]:
    """The time window of the first impact: half its duration before the rod reaches the
    floor to half after it leaves (the approach and the release), inside the run."""
    hit = first_impact_span(src)
    if hit is None:
        raise NothingToDraw("the rod never reached the floor: no impact to draw "
                            "(t_range = 'impact'); give the times instead")
    a, b = hit
    t = src.snapshot_times()
    lo, hi = a - (b - a) / 2, b + (b - a) / 2
    if t.size:
        lo, hi = max(lo, float(t[0])), min(hi, float(t[-1]))
    return (lo, hi)


def _impact_panel(src, fig, ax, dense: bool) -> None:
    """The first impact's node heights beside the whole run (re-simulated where the
    snapshots are too sparse for it, ``plotting.dense``), with the nodes' legend."""
    lo, hi = impact_window(src)
    _heights(src, fig, ax, t_range=(lo, hi), dense=dense, legend=True)
    ax.set_title(f"first impact: t = {lo:.4g} to {hi:.4g} s", fontsize=10)


def plot_file(path, output, kind: str = "heights", *, dpi: int = 150, figsize=None,
              **options) -> Path:
    """Draw figure ``kind`` of the run file ``path`` into the image file ``output``.

    Parameters
    ----------
    path : str or os.PathLike
        A run file.
    output : str or os.PathLike
        The image to write: PNG, PDF or SVG by its suffix.
    kind : str
        One of ``KINDS``, as for ``figure``.
    dpi : int
        Resolution of raster images, 10 to 2400.
    figsize : tuple of float, optional
        Figure size in inches.
    **options
        ``quantity``, ``t_range`` and ``dense``, as for ``figure``.

    Returns
    -------
    pathlib.Path
        ``output``.

    Raises
    ------
    ValueError
        An unknown suffix, ``kind`` or ``quantity``, or ``dpi`` out of range.
    """
    return save(figure(path, kind, figsize=figsize, **options), output, dpi)


def _one_axes(fig, ax):
    return ax if ax is not None else fig.add_subplot()


def _window(ax, t, t_range):
    ax.set_xlim(*(t_range if t_range is not None else (t[0], t[-1])))


def _heights(src, fig, ax, *, t_range, dense=True, legend=True, **_):
    n = src.n_snapshots()
    if n == 0:
        raise NothingToDraw("the run has no snapshots (output.snapshot_interval = 0); "
                            "nothing to draw for kind 'heights'")
    N = src.config.rod.N
    nodes = list(np.unique(np.round(np.linspace(0, N, min(MAX_CURVES, N + 1))).astype(int)))
    rows = src.strided_rows(MAX_POINTS, t_range)
    if t_range is None:
        t = src.snapshot_times()[rows]
        u = src.snapshots("u", rows, nodes)
    else:   # a window: its contacts drawn from enough samples (plotting.dense)
        s = sample(src, np.arange(n)[rows], t_range[0], t_range[1], dense=dense,
                   window=True, what="heights")
        t = s.t
        if t.size < 2:
            raise NothingToDraw(f"fewer than two snapshots in t_range = {t_range}; "
                                f"nothing to draw for kind 'heights'")
        u = s.states(src, "u")[:, nodes]
    import matplotlib

    ax = _one_axes(fig, ax)
    colors = matplotlib.colormaps["viridis"](np.linspace(0.0, 0.9, len(nodes)))
    for j, i in enumerate(nodes):
        ax.plot(t, u[:, j], color=colors[j], lw=1.0, label=f"x = {src.x[i]:.3g}")
    ax.axhline(0.0, color="0.3", lw=0.8, ls="--")
    ax.set_xlabel(_label("time t", "snapshots", "t"))
    ax.set_ylabel(_label("height u(t, x)", "snapshots", "u"))
    _window(ax, t, t_range)
    if legend:
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8,
                  title="node at", title_fontsize=8)
    return [ax]


def _energy(src, fig, ax, *, t_range, **_):
    cols = ("t", "energy_total", "dissipated") + tuple(c for c, _ in _ENERGY)
    d = src.diagnostics(cols)
    t = d["t"]
    if t.size == 0:
        raise NothingToDraw("the run has no diagnostics (output.diagnostics_interval = 0); "
                            "nothing to draw for kind 'energy'")
    c = src.config
    if ax is None:
        top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    else:
        top, bottom = ax, None
    for key, label in _ENERGY:
        if key == "energy_bend" and c.rod.gamma == 0:
            continue
        top.plot(t, d[key], lw=1.0, label=label)
    top.plot(t, d["energy_total"], color="k", lw=1.4, label="total E")
    if c.rod.mu > 0:
        top.plot(t, d["dissipated"], color="0.5", lw=1.2, ls="--", label="dissipated")
        top.plot(t, d["energy_total"] + d["dissipated"], color="r", lw=1.0, ls=":",
                 label="E + dissipated")
    top.set_ylabel(_label("energy", "diagnostics", "energy_total"))
    top.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
    _window(top, t, t_range)
    if bottom is None:
        top.set_xlabel(_label("time t", "diagnostics", "t"))
        return [top]
    e0 = d["energy_total"][0]
    scale = max(abs(e0), float(np.max(d["energy_kinetic"])), 1e-300)
    error = np.abs(d["energy_total"] + d["dissipated"] - e0) / scale
    what = "relative energy drift" if c.rod.mu == 0 else "energy balance error"
    positive = error > 0
    bottom.semilogy(t[positive], error[positive], color="C3", lw=1.0,
                    label=f"max {error.max():.2g}")
    bottom.set_ylabel(what, fontsize=8)
    bottom.set_xlabel(_label("time t", "diagnostics", "t"))
    bottom.legend(loc="lower right", fontsize=8)
    return [top, bottom]


def _bounces(src, fig, ax, **_):
    b = src.table("bounces")
    ax = _one_axes(fig, ax)
    k = np.arange(1, b["t_impact"].size + 1)
    closed = ~b["open"]
    ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
    if k.size == 0:
        ax.text(0.5, 0.5, "no bounces", transform=ax.transAxes, ha="center")
    else:
        amb = np.asarray(b["ambiguous"], bool)
        sure = closed & ~amb
        ax.plot(k[sure], b["restitution"][sure], "o-", ms=4, lw=1.0, label="restitution")
        ax.plot(k[closed], b["restitution_energy"][closed], "s", ms=3, mfc="none",
                color="C2", label="restitution_energy")
        if (closed & amb).any():   # shown apart: not an impact's restitution
            ax.plot(k[closed & amb], b["restitution"][closed & amb], "x", color="0.5",
                    label="ambiguous (not over, or approach below the vibration speed)")
        for j, kk in enumerate(k[~closed]):   # no release yet, so no restitution
            ax.axvline(kk, color="r", lw=0.8, ls=":",
                       label="open bounce (in contact at the end)" if j == 0 else None)
        ax.set_xticks(k if k.size <= 20 else np.unique(np.linspace(1, k.size, 20).astype(int)))
        ax.legend(loc="best", fontsize=8)
    ax.set_xlabel("bounce")
    ax.set_ylabel("restitution e = -w_release / w_impact")
    return [ax]


def _mark_episodes(ax, src, t_range, t):
    """Shade the contact episodes along the time axis (one legend entry)."""
    ep = src.table("episodes")
    lo, hi = t_range if t_range is not None else (t[0], t[-1])
    first = True
    for a, b in zip(ep["t_start"], ep["t_end"]):
        if b < lo or a > hi:
            continue
        ax.axvspan(a, b, ymin=0.0, ymax=0.03, color="k", lw=0,
                   label="contact (u₀ < 0)" if first else None)
        first = False
    return not first


def _spacetime(src, fig, ax, *, quantity, t_range, dense=True, **_):
    n = src.n_snapshots()
    if n == 0:
        raise NothingToDraw("the run has no snapshots (output.snapshot_interval = 0); "
                            "nothing to draw for kind 'spacetime'")
    times = src.snapshot_times()
    rows = np.arange(n)[src.strided_rows(MAX_ROWS, t_range)]
    lo, hi = t_range if t_range is not None else (float(times[0]), float(times[-1]))
    # every contact and a zoomed window drawn from enough columns (re-simulated where the
    # snapshots are too sparse, else a warning naming output.snapshot_interval)
    s = sample(src, rows, lo, hi, dense=dense, window=t_range is not None,
               what="spacetime", max_dense=MAX_ROWS)
    t = s.t
    if t.size < 2:
        raise NothingToDraw(f"fewer than two snapshots in t_range = {t_range}; nothing to "
                            f"draw for kind 'spacetime'")
    x = src.x
    if quantity == "strain":
        z = strain_of(s.states(src, "u"), x.size - 1)
        y_edges = x                                  # a segment spans its two nodes
        label = "strain ε = u_x − 1"
    else:
        z = s.states(src, quantity)
        mid = (x[:-1] + x[1:]) / 2
        y_edges = np.concatenate([[x[0]], mid, [x[-1]]])
        label = _label("height u" if quantity == "u" else "velocity v", "snapshots", quantity)
    t_mid = (t[:-1] + t[1:]) / 2
    t_edges = np.concatenate([[t[0] - (t[1] - t[0]) / 2], t_mid, [t[-1] + (t[-1] - t[-2]) / 2]])
    ax = _one_axes(fig, ax)
    if quantity == "u":
        mesh = ax.pcolormesh(t_edges, y_edges, z.T, cmap="viridis", shading="flat")
    else:    # the colour scale fitted to the data drawn, symmetric about 0
        lim = float(np.nanmax(np.abs(z))) or 1.0
        mesh = ax.pcolormesh(t_edges, y_edges, z.T, cmap="RdBu_r", vmin=-lim, vmax=lim,
                             shading="flat")
    fig.colorbar(mesh, ax=ax, label=label)
    marked = _mark_episodes(ax, src, t_range, t)
    for j, (s0, s1, dt) in enumerate(s.spans):   # say where the columns are re-simulated
        ax.axvspan(s0, s1, ymin=0.97, ymax=1.0, color="0.35", lw=0,
                   label=(f"re-simulated every {dt:.2g} s (the run's snapshots: every "
                          f"{src.config.output.snapshot_interval:g} s)") if j == 0 else None)
    if s.spans:     # below the axes, covering nothing
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), fontsize=8, ncols=1,
                  frameon=False)
    elif marked:
        ax.legend(loc="upper right", fontsize=8)
    ax.set_xlabel(_label("time t", "snapshots", "t"))
    ax.set_ylabel(_label("natural coordinate x (0: bottom)", "grid", "x"))
    ax.set_xlim(t_edges[0], t_edges[-1])
    return [ax]


def _contact(src, fig, ax, *, t_range, **_):
    d = src.diagnostics(("t", "u_bottom", "floor_force"))
    t = d["t"]
    if t.size == 0:
        raise NothingToDraw("the run has no diagnostics (output.diagnostics_interval = 0); "
                            "nothing to draw for kind 'contact'")
    beta = src.config.floor.beta
    if ax is None:
        top, bottom = fig.subplots(2, 1, sharex=True)
    else:
        top, bottom = ax, ax.twinx()
    top.plot(t, d["u_bottom"], color="C0", lw=1.0, label="bottom height u₀")
    top.axhline(0.0, color="0.3", lw=0.8, ls="--", label="floor surface")
    top.axhline(-beta, color="C3", lw=1.0, ls="-.", label=f"bending limit −β = {-beta:g}")
    top.set_ylabel(_label("u₀", "diagnostics", "u_bottom"))
    top.legend(loc="upper right", fontsize=8)
    bottom.plot(t, d["floor_force"], color="C1", lw=1.0, label="floor force σ_b(u₀)")
    bottom.set_ylabel(_label("σ_b", "diagnostics", "floor_force"))
    if ax is None:
        bottom.set_xlabel(_label("time t", "diagnostics", "t"))
        bottom.legend(loc="upper right", fontsize=8)
    else:
        top.set_xlabel(_label("time t", "diagnostics", "t"))
    _window(top, t, t_range)
    if t_range is not None:     # the heights and forces of the window, not of the whole run
        shown = (t >= t_range[0]) & (t <= t_range[1])
        _fit_y(top, d["u_bottom"][shown], (0.0, -beta))
        _fit_y(bottom, d["floor_force"][shown], (0.0,))
    return [top, bottom]


def _fit_y(ax, values, include=()) -> None:
    """The y range of ``ax``: the finite ``values`` shown and the levels ``include``, with a
    margin of 5 %."""
    v = np.asarray(values, float)
    v = np.concatenate([v[np.isfinite(v)], np.asarray(include, float)])
    if v.size == 0:
        return
    lo, hi = float(v.min()), float(v.max())
    pad = 0.05 * (hi - lo) if hi > lo else max(abs(hi), 1.0) * 0.05
    ax.set_ylim(lo - pad, hi + pad)
