"""Reading a run file: its configuration, valid checkpoint and tables, or all of it as a
``rodjit.Result`` (``load_file``).  A file still being written is read up to the rows
present in every column.  Formats 1 and 2 read alike: the nodes' positions from wherever
the format keeps them, boolean columns as bool."""
from __future__ import annotations

import h5py
import numpy as np

from ..config import Config
from ..records.columns import BOOL_COLUMNS
from ..records.result import Result
from ..records.stats import run_stats
from ..stepping import layout as L
from .h5files import NotARunFile, check_kind, open_file
from .cf import as_bool
from .run_layout import (CK_ARRAYS, CK_SCALARS, KIND, OLD_BOUNCE_FILL, READS, TABLES,
                         current_checkpoint, x_path)

__all__ = ["check_run_file", "read_config", "read_checkpoint", "read_table", "read_x",
           "load_file"]


def check_run_file(f: h5py.File, path=None) -> None:
    """Raise NotARunFile unless ``f`` is a rodjit run file of a format this version reads."""
    check_kind(f, KIND, READS, path)


def read_config(f: h5py.File) -> Config:
    """The configuration the file's run runs (root attribute ``config_toml``)."""
    return Config.from_stored_toml(f.attrs["config_toml"])


def read_checkpoint(f: h5py.File) -> dict:
    """The valid checkpoint: arrays for ``Run.from_checkpoint`` plus ``lengths`` (table
    rows it matches, ``{"snapshots": n, ...}``) and cumulative ``compile_time``."""
    ck = f["checkpoint"]
    slot = int(ck["current"][()])
    if slot not in (0, 1):
        raise NotARunFile(f"{f.filename!r} holds no valid checkpoint yet")
    g = ck[f"slot{slot}"]
    out = {name: g[name][()] for name in CK_ARRAYS}
    for name in CK_SCALARS:
        out[name] = float(g[name][()])
    out["lengths"] = dict(zip(TABLES, (int(n) for n in g["lengths"][()])))
    return current_checkpoint(out, read_config(f))


def read_table(f: h5py.File, group: str, rows: slice | None = None) -> dict[str, np.ndarray]:
    """Columns of one table (all rows, or ``rows``); a table still being written is cut to
    the rows present in every column."""
    g = f[group]
    present = [c for c in TABLES[group] if c in g]
    n = min(g[c].shape[0] for c in present)
    sel = slice(0, n) if rows is None else slice(*rows.indices(n))
    out = {}
    for c in TABLES[group]:
        if c in g:
            out[c] = as_bool(g[c][sel]) if c in BOOL_COLUMNS else g[c][sel]
        else:                  # a column formats 1 and 2 lack (run_layout.OLD_BOUNCE_FILL)
            value, dtype = OLD_BOUNCE_FILL[c]
            out[c] = np.full(len(range(*sel.indices(n))), value, dtype)
    return out


def read_x(f: h5py.File) -> np.ndarray:
    """The natural positions x_i = i/N of the nodes."""
    return f[x_path(f)][()]


def load_file(path):
    """Read a whole run file into a ``rodjit.Result`` (the same object ``simulate`` returns).

    Parameters
    ----------
    path : str or os.PathLike
        A run file written by ``rodjit run`` or ``run_to_file``, also one still being
        written or whose writer was killed.
    """
    with open_file(path) as f:
        check_run_file(f, path)
        config = read_config(f)
        ck = read_checkpoint(f)
        snaps = read_table(f, "snapshots")
        stats = run_stats(steps=int(ck["count"][L.STEP]), rejected=int(ck["count"][L.REJECTED]),
                          compile_time=ck["compile_time"], run_time=ck["run_time"],
                          nodes=config.rod.N + 1, scheme_counts=ck["sstats"])
        return Result(
            config=config, x=read_x(f), t=snaps["t"], u=snaps["u"], v=snaps["v"],
            diagnostics=read_table(f, "diagnostics"), episodes=read_table(f, "episodes"),
            bounces=read_table(f, "bounces"), stats=stats,
            status=str(f.attrs["status"]), message=str(f.attrs["message"]),
            t_final=float(ck["clock"][L.T]), u_final=ck["state"][0].copy(),
            v_final=ck["state"][1].copy(), energy0=float(ck["clock"][L.E0]),
            dissipated=float(ck["clock"][L.DISSIPATED]))
