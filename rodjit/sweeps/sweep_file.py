"""The sweep file: one HDF5 file per sweep, a summary row per grid point (public contract).

Layout (README "Sweeps"), format 3: root attributes (``rodjit_kind = "sweep"``, version,
base configuration as TOML, the grid as JSON, command, status, the CF ones);
``/summary/<column>``, 1-D along the dimension ``/summary/point`` (the point's index), one
row per point in grid order (the swept keys, which are the data's coordinates, then
``point.SUMMARY_COLUMNS``); and ``/points/<index>/bounces/<column>``, the bounce table of
each point that ran, along its ``t_impact``.  Formats 1 and 2 are still read (not
continued): format 1 had no ``point`` dimension and stored ``open`` as bool; both cut
bounces at every centre-of-mass apex, so their bounce rows read with the columns added
since at ``run_layout.OLD_BOUNCE_FILL`` (``ambiguous`` true), and their summary columns of
other meanings read renamed (``OLD_SUMMARY``): format 2's ``restitution_impact`` and
``contact_time_impact`` are today's ``restitution_first`` and ``contact_time_first``, its
``restitution_first``, ``restitution_mean`` and ``contact_time_first`` (of the first apex
bounce, over every apex bounce) read as ``*_apex_bounces`` columns.

Every row exists from the start, ``status = "pending"`` until its point reports.  The parent
process is the only writer; it opens the file for each batch of results and closes it
again, so between batches the file is complete on disk and other processes can read it.

The disk refusing a write (full, a file-size limit) must not cut a batch half-way: HDF5
would leave the file's structures inconsistent.  Each write therefore first reserves more
disk space at the end of the file than it can use (``h5files.reserve_space``); if the disk
refuses that, WriteFailed is raised with the file exactly as it was, every point written
before kept.  A write that fails anyway (an I/O error) leaves its handles open
(``h5files.abandon``): closing a file HDF5 cannot write only makes matters worse.
"""
from __future__ import annotations

import os
import time
from contextlib import contextmanager

import h5py
import numpy as np

from ..config import Config, field_spec
from ..output import cf
from ..output.h5files import (FileBusy, NotARunFile, WriteFailed, abandon, check_kind,
                              disk_cause, history_with, now, open_file, reserve_space,
                              stamp_writer, writer_attrs)
from ..output.run_layout import OLD_BOUNCE_FILL
from ..records.bounces import empty_bounces
from ..records.columns import BOUNCE_COLUMNS
from ..version import __version__
from .grid import Grid
from .point import SUMMARY_COLUMNS, empty_columns

__all__ = ["KIND", "FORMAT_VERSION", "STATUSES", "create", "write_results", "finish",
           "read_header", "read_summary", "read_bounces", "check_sweep_file", "key_columns",
           "open_sweep", "reopen", "OLD_SUMMARY", "check_continuable"]

KIND = "sweep"
FORMAT_VERSION = 3
READS = (1, 2, 3)       # the formats this version reads
CONTINUES = (3,)        # and those it continues (--resume)
# format 1 and 2 summary columns whose meaning has a new name: old name -> name read
OLD_SUMMARY = {"restitution_first": "restitution_first_apex_bounces",
               "restitution_mean": "restitution_mean_apex_bounces",
               "contact_time_first": "contact_time_first_apex_bounces",
               "restitution_impact": "restitution_first",
               "contact_time_impact": "contact_time_first"}
POINT = "point"         # the summary's dimension
STATUSES = ("running", "completed", "interrupted", "failed")
LOCK_WAIT = 30.0        # seconds to wait for a reader to release the file before failing
# disk space reserved before a write (bytes): the file grows by less, measured at ~11 KiB a
# point with a short bounce table (its arrays are counted twice on top)
RESERVE_BASE = 64 * 1024
RESERVE_POINT = 32 * 1024

_STR = h5py.string_dtype("utf-8")
_DTYPES = {"str": _STR, "int": np.int64, "float": np.float64}


def _key_kind(values) -> str:
    v = values[0]
    return "str" if isinstance(v, str) else "int" if isinstance(v, int) else "float"


def key_columns(grid: Grid) -> dict[str, np.ndarray]:
    """The swept keys' columns: the value of each key at every point, in grid order."""
    out = {}
    for axis, (key, values) in enumerate(zip(grid.keys, grid.values)):
        idx = np.indices(grid.shape)[axis].ravel() if len(grid) else np.zeros(0, int)
        kind = _key_kind(values)
        arr = np.array(values, dtype=object if kind == "str" else _DTYPES[kind])
        out[key] = arr[idx]
    return out


def _open(path, mode: str, wait: float = LOCK_WAIT) -> h5py.File:
    """Open for writing, waiting up to ``wait`` seconds for a reader to let go."""
    deadline = time.monotonic() + wait
    while True:
        try:
            return h5py.File(path, mode, libver=cf.LIBVER)
        except OSError as exc:
            if disk_cause(exc) is not None:
                raise WriteFailed(disk_cause(exc), disk_cause(exc)) from None
            if "lock" not in str(exc) or time.monotonic() > deadline:
                if "lock" in str(exc):
                    raise FileBusy(f"{str(path)!r} is held open by another process; "
                                   f"close it there and retry") from None
                raise ValueError(f"cannot open {str(path)!r} for writing: {exc}") from None
            time.sleep(0.05)


@contextmanager
def _writing(path, mode: str, wait: float = LOCK_WAIT, reserve: int = 0):
    """``with _writing(path, mode) as f:`` the file open for writing, closed at the end;
    ``reserve`` bytes of disk space are reserved first (not for a new file).  A write the
    disk refuses raises WriteFailed (its message: the cause), and the file's handles are
    abandoned rather than closed."""
    size = reserve_space(path, reserve) if reserve else None
    try:
        f = _open(path, mode, wait)
    except BaseException:
        if size is not None:          # give the reservation back
            try:
                os.truncate(path, size)
            except OSError:
                pass
        raise
    try:
        yield f
        f.close()
    except BaseException as exc:
        cause = disk_cause(exc)
        if cause is None:
            if f.id.valid:
                f.close()
            raise
        abandon(f, exc.__traceback__)      # every frame's h5py objects with it
        raise WriteFailed(cause, cause) from None


def create(path, base, grid: Grid, *, command: str, attrs: dict) -> None:
    """A new sweep file: attributes, every summary column with all rows pending.
    WriteFailed if the disk refuses (the caller removes the partial file)."""
    n = len(grid)
    with _writing(path, "w") as f:
        for key, value in {"rodjit_kind": KIND, "format_version": FORMAT_VERSION,
                           "rodjit_version": __version__, "created": now(),
                           "command": command, "base_config_toml": base.to_toml(),
                           "grid": grid.to_json(), "grid_keys": list(grid.keys),
                           "n_points": n, "status": "running", "message": "",
                           "history": [f"{now()} created by: {command}"],
                           **writer_attrs(), **attrs,
                           **cf.root_attrs(f"rodjit sweep over {', '.join(grid.keys)} "
                                           f"({n} points)")}.items():
            f.attrs[key] = value
        s = f.create_group("summary", track_order=True)
        s.attrs["description"] = ("one row per grid point, in grid order (the last swept key "
                                  "varies fastest); status 'pending' until the point has run")
        chunk = (min(max(n, 1), 65536),)
        point = s.create_dataset(POINT, data=np.arange(n, dtype=np.int64))
        point.make_scale(POINT)
        point.attrs.update(long_name="index of the grid point (grid order)", units="1")
        for key, col in key_columns(grid).items():
            kind = _key_kind(grid.values[grid.keys.index(key)])
            ds = s.create_dataset(key, data=col, dtype=_DTYPES[kind], chunks=chunk)
            spec = field_spec(key)
            ds.attrs["description"] = f"swept configuration key {key}"
            ds.attrs.update(long_name=spec.meaning, config_key=key)
            if spec.unit:
                ds.attrs["units"] = spec.unit
            ds.dims[0].attach_scale(point)
        coordinates = " ".join(grid.keys)      # CF auxiliary coordinates of every column
        for name, col in empty_columns(n).items():
            kind, text = SUMMARY_COLUMNS[name]
            ds = s.create_dataset(name, data=col, dtype=_DTYPES[kind], chunks=chunk)
            ds.attrs["description"] = text
            ds.attrs.update(cf.column_attrs("summary", name))
            if coordinates:
                ds.attrs["coordinates"] = coordinates
            ds.dims[0].attach_scale(point)
        p = f.create_group("points")
        p.attrs["description"] = "per point: its bounce table (the run file's /bounces columns)"


def check_continuable(f: h5py.File, path=None) -> None:
    """ValueError unless this version continues the sweep file's format (``CONTINUES``)."""
    version = _format(f)
    if version not in CONTINUES:
        raise ValueError(f"{str(path or f.filename)!r} is a sweep file of format {version}, "
                         f"whose bounces and summary columns have older meanings; --resume "
                         f"continues format {FORMAT_VERSION} only: start a new sweep")


def reopen(path, *, history: str) -> None:
    """Mark a sweep file running again (resume), recording who continues it."""
    with _writing(path, "r+", reserve=RESERVE_BASE) as f:
        f.attrs["status"] = "running"
        f.attrs["message"] = ""
        f.attrs["history"] = history_with(f, history)
        stamp_writer(f.attrs)


def write_results(path, results, wait: float = LOCK_WAIT) -> None:
    """Write a batch of PointResults: their summary rows and bounce tables.  FileBusy if
    another process holds the file open for longer than ``wait`` seconds."""
    if not results:
        return
    results = sorted(results, key=lambda r: r.index)
    idx = np.array([r.index for r in results])
    with _writing(path, "r+", wait, reserve=_batch_bytes(results)) as f:
        s = f["summary"]
        for name, (kind, _) in SUMMARY_COLUMNS.items():
            if name == "status":
                continue      # last: a row counts as done only once all of it is there
            vals = [r.values[name] for r in results]
            s[name][idx] = np.array(vals, dtype=object if kind == "str" else _DTYPES[kind])
        p = f["points"]
        for r in results:
            key = str(r.index)
            if key in p:
                del p[key]
            b = p.create_group(key).create_group("bounces", track_order=True)
            _bounce_table(b, r.bounces)
        s["status"][idx] = np.array([r.status for r in results], dtype=object)


def _batch_bytes(results) -> int:
    """Disk space to reserve for writing ``results``: more than they can take."""
    total = RESERVE_BASE
    for r in results:
        total += RESERVE_POINT + 4 * sum(len(str(v)) for v in r.values.values()
                                         if isinstance(v, str))
        total += 2 * sum(np.asarray(col).nbytes for col in r.bounces.values())
    return total


def _bounce_table(g: h5py.Group, bounces: dict) -> None:
    """A point's bounce table as the run file's ``/bounces`` (format 3): columns along the
    dimension ``t_impact``, ``open`` and ``ambiguous`` as flagged int8, long names and
    units."""
    scale = None
    for name in BOUNCE_COLUMNS:
        data = np.asarray(bounces[name])
        if data.dtype == bool:
            data = data.astype(cf.BOOL_DTYPE)
        ds = g.create_dataset(name, data=data)
        ds.attrs.update(cf.column_attrs("bounces", name))
        if scale is None:
            ds.make_scale(name)
            scale = ds
        else:
            ds.dims[0].attach_scale(scale)


def finish(path, status: str, message: str = "", attrs: dict | None = None) -> None:
    if status not in STATUSES:
        raise ValueError(f"status {status!r} is not one of {STATUSES}")
    with _writing(path, "r+", reserve=RESERVE_BASE + 4 * len(message)) as f:
        f.attrs["status"] = status
        f.attrs["message"] = message
        for key, value in (attrs or {}).items():
            f.attrs[key] = value


# ---- reading ------------------------------------------------------------------------------
def check_sweep_file(f: h5py.File, path=None) -> None:
    """Raise NotARunFile unless ``f`` is a sweep file of a format this version reads."""
    check_kind(f, KIND, READS, path)


def read_header(f: h5py.File) -> dict:
    """Base configuration, grid and the root attributes of an open sweep file."""
    attrs = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in f.attrs.items()}
    return {"base": Config.from_stored_toml(f.attrs["base_config_toml"]),
            "grid": Grid.from_json(f.attrs["grid"]), "attrs": attrs}


def _format(f: h5py.File) -> int:
    return int(f.attrs.get("format_version", FORMAT_VERSION))


def read_summary(f: h5py.File) -> dict[str, np.ndarray]:
    """The summary columns, in file order; text columns as arrays of str.  A format 1 or 2
    file's columns of another meaning read under their ``OLD_SUMMARY`` names, and the
    columns it lacks as NaN."""
    out = {}
    old = _format(f) < 3
    for name, ds in f["summary"].items():
        if name == POINT and ds.is_scale:
            continue                      # the dimension, not a column
        out[OLD_SUMMARY.get(name, name) if old else name] = (
            ds.asstr()[()].astype(object) if h5py.check_string_dtype(ds.dtype) else ds[()])
    if old:
        n = len(next(iter(out.values()))) if out else 0
        for name, (kind, _) in SUMMARY_COLUMNS.items():
            if name not in out and kind == "float":
                out[name] = np.full(n, np.nan)
    return out


def read_bounces(f: h5py.File, index: int) -> dict[str, np.ndarray]:
    """Point ``index``'s bounce table (empty columns if the point has not run)."""
    g = f["points"].get(str(index))
    if g is None:
        return empty_bounces()
    b = g["bounces"]
    n = b["t_impact"].shape[0]
    out = {}
    for name in BOUNCE_COLUMNS:
        if name in b:
            out[name] = b[name][()]
        else:                       # a column formats 1 and 2 lack
            value, dtype = OLD_BOUNCE_FILL[name]
            out[name] = np.full(n, value, dtype)
    out["open"] = cf.as_bool(out["open"])
    out["ambiguous"] = cf.as_bool(out["ambiguous"])
    return out


def open_sweep(path) -> h5py.File:
    """Open a sweep file read-only (one-line errors for a missing or foreign file); waits
    briefly while the sweep's writer has it open for a batch of results."""
    deadline = time.monotonic() + 5.0
    while True:
        try:
            f = open_file(path)
            break
        except NotARunFile as exc:
            if "lock" not in str(exc) or time.monotonic() > deadline:
                raise
            time.sleep(0.05)
    try:
        check_sweep_file(f, path)
    except BaseException:
        f.close()
        raise
    return f
