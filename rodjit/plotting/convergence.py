"""Figure of a convergence study (``rodjit converge -o conv.h5``): the error of each
observable against the resolution on log-log axes, with the fitted order.

The error of level k is |f_k − f*| relative to |f*| (f* the extrapolated continuum value),
so observables of different units share one axes; the dashed line through the finest
level has the slope of the observed order.  Observables without an order (exact,
undefined or not converging ladders) are named in the title instead of drawn.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .mpl import new_figure, save

__all__ = ["KINDS", "convergence_figure", "plot_convergence_file"]

KINDS = ("convergence",)


def _text(v) -> str:
    return v.decode() if isinstance(v, bytes) else str(v)


def convergence_figure(path, kind: str = "convergence"):
    """The matplotlib Figure of the convergence file ``path``."""
    from ..analysis.converge import load_convergence

    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r} is not allowed (one of {', '.join(KINDS)})")
    study = load_convergence(path)
    key = _text(study["key"])
    levels = np.asarray(study["levels"], float)
    fig = new_figure(figsize=(6.4, 4.8), layout="constrained")
    ax = fig.add_subplot()
    skipped = []
    for name, obs in study["observables"].items():
        values = np.asarray(obs["values"], float)
        best = float(obs["value"])
        order = float(obs.get("order", math.nan))
        err = np.abs(values - best) / (abs(best) if best else 1.0)
        ok = np.isfinite(err) & (err > 0)
        if not (math.isfinite(best) and math.isfinite(order) and ok.sum() >= 2):
            skipped.append(f"{name} ({_text(obs['status'])})")
            continue
        line, = ax.loglog(levels[ok], err[ok], "o-",
                          label=f"{name}: {best:.6g} ± {float(obs['error']):.2g}, "
                                f"p = {order:.2f}")
        # the fitted order through the finest drawn level: err ∝ h^p, h = 1/N for rod.N
        k = np.flatnonzero(ok)[-1]
        h = 1.0 / levels if key == "rod.N" else levels
        ax.loglog(levels, err[k] * (h / h[k]) ** order, "--", color=line.get_color(),
                  alpha=0.6)
    if not ax.lines:
        raise ValueError(f"{str(path)!r}: no observable has an observed order to draw "
                         f"({', '.join(skipped) or 'none studied'})")
    ax.set_xlabel(key)
    ax.set_ylabel("|f − f*| / |f*|  (dashed: fitted order)")
    title = "convergence"
    if skipped:
        title += f"; not drawn: {', '.join(skipped)}"
    ax.set_title(title, fontsize="small")
    ax.legend(fontsize="x-small")
    ax.grid(True, which="both", alpha=0.3)
    return fig


def plot_convergence_file(path, output, kind: str = "convergence", *, dpi: int = 150) -> Path:
    """Draw the convergence figure of ``path`` into the image file ``output``."""
    return save(convergence_figure(path, kind), output, dpi=dpi)
