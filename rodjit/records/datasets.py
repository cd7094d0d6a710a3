"""A run as an ``xarray.Dataset``: the one layout ``Result.to_xarray`` and
``rodjit.open_run`` (lazily, from a file) both give.

Dimensions: ``t`` and ``x`` (snapshots ``u``, ``v``), ``x_segment`` (the segment midpoints
x_{i+1/2}, where the strain ε_{i+1/2} = (u_{i+1} − u_i)/h − 1 lives, MODEL.md §2),
``t_diag`` (the diagnostics columns, sampled on their own interval), ``episode`` and
``bounce``.  Every variable carries ``long_name`` and ``units`` (``records.metadata``).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from .._extras import need
from .metadata import UNIT_SYSTEM, meaning

__all__ = ["run_dataset", "strain_of"]


def strain_of(u: np.ndarray, n: int) -> np.ndarray:
    """Segment strains ε_{i+1/2} = (u_{i+1} − u_i) N − 1 of heights ``u`` (last axis: nodes)."""
    return np.diff(u, axis=-1) * n - 1.0


def _attrs(table: str, column: str, **extra) -> dict:
    m = meaning(table, column)
    return {"long_name": m.long_name, "units": m.units, **extra}


def run_dataset(*, x, t, u, v, strain, diagnostics: dict, episodes: dict, bounces: dict,
                attrs: dict, what: str):
    """The Dataset of a run from its arrays (NumPy arrays or xarray lazily indexed arrays
    of the same shapes); ``what`` names the caller in a missing-extra message."""
    xr = need("xarray", "analysis", what)
    n = len(x) - 1
    x = np.asarray(x, float)
    data: dict[str, tuple[Any, Any, dict[str, Any]]] = {
        "u": (("t", "x"), u, _attrs("snapshots", "u")),
        "v": (("t", "x"), v, _attrs("snapshots", "v")),
        "strain": (("t", "x_segment"), strain,
                   {"long_name": "segment strain (u_{i+1} - u_i)/h - 1", "units": "1"}),
    }
    for name, values in diagnostics.items():
        if name != "t":
            data[name] = ("t_diag", values, _attrs("diagnostics", name))
    for name, values in episodes.items():
        data[f"episode_{name}"] = ("episode", values, _attrs("episodes", name))
    for name, values in bounces.items():
        data[f"bounce_{name}"] = ("bounce", values, _attrs("bounces", name))
    coords = {
        "t": ("t", np.asarray(t, float), _attrs("snapshots", "t")),
        "x": ("x", x, _attrs("grid", "x")),
        "x_segment": ("x_segment", (x[:-1] + x[1:]) / 2,
                      {"long_name": "natural position of the segment midpoint", "units": "m"}),
        "t_diag": ("t_diag", np.asarray(diagnostics["t"], float),
                   _attrs("diagnostics", "t", description="time of the diagnostics samples")),
        "episode": ("episode", np.arange(len(episodes["t_start"])),
                    {"long_name": "contact episode number (from 0)", "units": "1"}),
        "bounce": ("bounce", np.arange(1, len(bounces["t_impact"]) + 1),
                   {"long_name": "bounce number (from 1)", "units": "1"}),
    }
    return xr.Dataset(data, coords, {"units_system": UNIT_SYSTEM, "N": n, **attrs})
