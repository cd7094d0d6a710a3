"""Figures of a run file: node heights (the paper's figures), energies, restitution."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..output import hdf5
from .mpl import MissingMatplotlib, new_figure

__all__ = ["KINDS", "figure", "plot_file", "MissingMatplotlib"]

KINDS = ("heights", "energy", "bounces")
MAX_CURVES = 11        # node curves drawn at most (evenly spaced along the rod)
MAX_POINTS = 20_000    # time samples drawn at most per curve (strided read)


def figure(path, kind: str = "heights"):
    """The matplotlib Figure of kind ``kind`` for the run file ``path``."""
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} is not allowed (one of {', '.join(KINDS)})")
    fig = new_figure(figsize=(7.5, 4.5), layout="constrained")
    with hdf5.open_file(path) as f:
        hdf5.check_run_file(f, path)
        config = hdf5.read_config(f)
        ax = fig.add_subplot()
        {"heights": _heights, "energy": _energy, "bounces": _bounces}[kind](f, config, ax)
    ax.set_title(f"{Path(path).name}: N = {config.rod.N}, μ = {config.rod.mu:g}, "
                 f"κ = {config.rod.kappa:g}, κ_b = {config.floor.kappa_b:g}, "
                 f"β = {config.floor.beta:g}", fontsize=10)
    return fig


def plot_file(path, output, kind: str = "heights", *, dpi: int = 150) -> Path:
    """Draw figure ``kind`` of the run file ``path`` into the image file ``output``."""
    fig = figure(path, kind)
    output = Path(output)
    fig.savefig(output, dpi=dpi)
    return output


def _stride(n: int) -> int:
    return max(1, math.ceil(n / MAX_POINTS))


def _heights(f, config, ax) -> None:
    g = f["snapshots"]
    n = min(g["t"].shape[0], g["u"].shape[0])
    if n == 0:
        raise ValueError("the file has no snapshots (output.snapshot_interval = 0); nothing to "
                         "draw for kind 'heights'")
    nodes = np.unique(np.round(np.linspace(0, config.rod.N, min(MAX_CURVES, config.rod.N + 1)))
                      .astype(int))
    s = _stride(n)
    t = g["t"][0:n:s]
    u = g["u"][0:n:s, list(nodes)]
    x = hdf5.read_x(f)
    import matplotlib

    colors = matplotlib.colormaps["viridis"](np.linspace(0.0, 0.9, nodes.size))
    for j, i in enumerate(nodes):
        ax.plot(t, u[:, j], color=colors[j], lw=1.0, label=f"x = {x[i]:.3g}")
    ax.axhline(0.0, color="0.3", lw=0.8, ls="--")
    ax.set_xlabel("time t")
    ax.set_ylabel("height u(t, x)")
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8, title="node",
              title_fontsize=8)


def _energy(f, config, ax) -> None:
    g = f["diagnostics"]
    n = min(g[c].shape[0] for c in hdf5.TABLES["diagnostics"])
    if n == 0:
        raise ValueError("the file has no diagnostics (output.diagnostics_interval = 0); "
                         "nothing to draw for kind 'energy'")
    s = _stride(n)
    d = {c: g[c][0:n:s] for c in ("t", "energy_kinetic", "energy_stretch", "energy_bend",
                                  "energy_floor", "energy_gravity", "energy_total",
                                  "dissipated")}
    t = d["t"]
    for key, label in (("energy_kinetic", "kinetic"), ("energy_stretch", "stretch"),
                       ("energy_bend", "bending"), ("energy_floor", "floor"),
                       ("energy_gravity", "gravity")):
        if key == "energy_bend" and config.rod.gamma == 0:
            continue
        ax.plot(t, d[key], lw=1.0, label=label)
    ax.plot(t, d["energy_total"], color="k", lw=1.4, label="total E")
    if config.rod.mu > 0:
        ax.plot(t, d["dissipated"], color="0.5", lw=1.2, ls="--", label="dissipated")
        ax.plot(t, d["energy_total"] + d["dissipated"], color="r", lw=1.0, ls=":",
                label="E + dissipated")
    ax.set_xlabel("time t")
    ax.set_ylabel("energy")
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)


def _bounces(f, config, ax) -> None:
    b = hdf5.read_table(f, "bounces")
    k = np.arange(1, b["t_impact"].size + 1)
    closed = ~b["open"]
    ax.axhline(1.0, color="0.6", lw=0.8, ls="--")
    if k.size == 0:
        ax.text(0.5, 0.5, "no bounces", transform=ax.transAxes, ha="center")
    else:
        ax.plot(k[closed], b["restitution"][closed], "o-", ms=4, lw=1.0, label="restitution")
        for j, kk in enumerate(k[~closed]):   # no release yet, so no restitution
            ax.axvline(kk, color="r", lw=0.8, ls=":",
                       label="open bounce (in contact at the end)" if j == 0 else None)
        ax.set_xticks(k if k.size <= 20 else np.unique(np.linspace(1, k.size, 20).astype(int)))
        ax.legend(loc="best", fontsize=8)
    ax.set_xlabel("bounce")
    ax.set_ylabel("restitution e = -w_release / w_impact")
