"""The sweep file: one HDF5 file per sweep, a summary row per grid point (public contract).

Layout (README "Sweeps"), format 3: root attributes (``rodjit_kind = "sweep"``, version,
base configuration as TOML, the grid as JSON, command, status, the CF ones);
``/summary/<column>``, 1-D along the dimension ``/summary/point`` (the point's index), one
row per point in grid order (the swept keys, which are the data's coordinates, then
``point.SUMMARY_COLUMNS``); and ``/bounces/<column>``, the bounce rows of every point in one
table along the dimension ``/bounces/bounce``.  The bounce table is a CF *indexed ragged
array*: ``/bounces/point_index`` (``instance_dimension = "point"``) gives each row's point.
Rows are appended as points are written, so they are grouped by point (each point's rows
are contiguous) but not in point order; ``/summary/bounce_start`` and
``/summary/bounce_count`` locate a point's rows without a search.  The number of HDF5
objects is fixed by the columns, whatever the number of points.

Formats 1 and 2 are still read (not continued).  They kept each point's bounce table in a
group ``/points/<index>/bounces/<column>`` of its own (ten datasets a point); format 1 had
no ``point`` dimension either and stored ``open`` as bool.  Both cut bounces at every
centre-of-mass apex, so their bounce rows read with the columns added since at
``run_layout.OLD_BOUNCE_FILL`` (``ambiguous`` true), and their summary columns of other
meanings read renamed (``OLD_SUMMARY``): format 2's ``restitution_impact`` and
``contact_time_impact`` are today's ``restitution_first`` and ``contact_time_first``, its
``restitution_first``, ``restitution_mean`` and ``contact_time_first`` (of the first apex
bounce, over every apex bounce) read as ``*_apex_bounces`` columns.

Every row exists from the start, ``status = "pending"`` until its point reports.  The parent
process is the only writer; it opens the file for each batch of results and closes it
again, so between batches the file is complete on disk and other processes can read it.

Whatever moment the writer dies at, the file keeps what it held before the write it was
in: a new file is written beside its name and renamed into place once whole
(``journal.creating``), and every later write (a batch, reopening, finishing) goes through
an undo journal (``journal.Journaled``), which a reader or the next writer plays back
(``journal.recover``) if the writer died in the middle.  The superblock's "open for
writing" flag that a killed HDF5 writer leaves set is part of what is undone, so no tool
is needed.  The same holds when the disk refuses a write (full, a file-size limit): the
write is rolled back, WriteFailed raised, and every point written before is kept.  The
only disk space a write needs beyond what the file grows by is its journal: a copy of the
pages it changes (the summary chunks of its points, a few HDF5 structures).
"""
from __future__ import annotations

import hashlib
import time
from contextlib import contextmanager

import h5py
import numpy as np

from ..config import Config, field_spec
from ..output import cf
from ..output.h5files import (FileBusy, NotARunFile, WriteFailed, abandon, check_kind,
                              damaged, disk_cause, history_with, now, open_file, stamp_writer,
                              writer_attrs)
from ..output.journal import Journaled, creating
from ..output.run_layout import OLD_BOUNCE_FILL
from ..records.bounces import empty_bounces
from ..records.columns import BOOL_COLUMNS, BOUNCE_COLUMNS
from ..version import __version__
from .grid import Grid
from .ensemble import as_batch
from .errors import FormatNotContinued
from .point import SUMMARY_COLUMNS, empty_columns, summary_columns

__all__ = ["KIND", "FORMAT_VERSION", "STATUSES", "create", "write_results", "finish",
           "read_header", "read_summary", "read_bounces", "read_all_bounces", "join_bounces",
           "check_sweep_file", "key_columns", "open_sweep", "reopen", "OLD_SUMMARY",
           "check_continuable", "key_kind", "row_digests", "header_digest", "ROW_DIGEST"]

KIND = "sweep"
FORMAT_VERSION = 4
DIGEST_SINCE = 3     # the first format whose files carry ``header_digest``
ROWS_SINCE = 4       # the first whose ``header_digest`` covers save_runs and rows carry
                     # ``row_digest`` (format 3: the same layout without them)
READS = (1, 2, 3, 4)    # the formats this version reads
CONTINUES = (3, 4)      # and those it continues (--resume; a format-3 file stays format 3)
# format 1 and 2 summary columns whose meaning has a new name: old name -> name read
OLD_SUMMARY = {"restitution_first": "restitution_first_apex_bounces",
               "restitution_mean": "restitution_mean_apex_bounces",
               "contact_time_first": "contact_time_first_apex_bounces",
               "restitution_impact": "restitution_first",
               "contact_time_impact": "contact_time_first"}
POINT = "point"         # the summary's dimension
BOUNCES = "bounces"     # format 3: the group of the one bounce table of every point
ROW = "bounce"          # its dimension (the row number)
POINT_INDEX = "point_index"     # each bounce row's point
ROW_DIGEST = "row_digest"       # the summary dataset that proves each written row
# the summary datasets that locate each point's bounce rows (format 3); not table columns
RAGGED = {"bounce_start": "first row of the point's bounces in /bounces (-1: none written)",
          "bounce_count": "number of the point's rows in /bounces (CF count of the ragged "
                          "bounce table)"}
BOUNCE_CHUNK = 4096     # rows per chunk of the bounce table
STATUSES = ("running", "completed", "interrupted", "failed")
LOCK_WAIT = 30.0        # seconds to wait for a reader to release the file before failing

# the root attributes without which a sweep file is not complete
REQUIRED_ATTRS = ("base_config_toml", "grid", "n_points", "status")

_STR = h5py.string_dtype("utf-8")
_DTYPES = {"str": _STR, "int": np.int64, "float": np.float64}
# the attribute that marks a summary column as the observer's (``output.observer``), naming it
OBSERVER = "observer"


def key_kind(values) -> str:
    """The dtype name ("str", "int", "float") of a swept key's column, from its values."""
    v = values[0]
    return "str" if isinstance(v, str) else "int" if isinstance(v, int) else "float"


def key_columns(grid: Grid) -> dict[str, np.ndarray]:
    """The swept keys' columns: the value of each key at every point, in grid order."""
    out = {}
    for axis, (key, values) in enumerate(zip(grid.keys, grid.values)):
        idx = np.indices(grid.shape)[axis].ravel() if len(grid) else np.zeros(0, int)
        kind = key_kind(values)
        arr = np.array(values, dtype=object if kind == "str" else _DTYPES[kind])
        out[key] = arr[idx]
    return out


def _journaled(path, wait: float) -> Journaled:
    """The file open for a journaled write, waiting up to ``wait`` seconds for a reader to
    let go (FileBusy after that)."""
    deadline = time.monotonic() + wait
    while True:
        try:
            return Journaled(path)
        except FileBusy:
            if time.monotonic() > deadline:
                raise FileBusy(f"{str(path)!r} is held open by another process; close it "
                               f"there and retry") from None
            time.sleep(0.05)
        except OSError as exc:
            cause = disk_cause(exc)
            if cause is not None:
                raise WriteFailed(cause, cause) from None
            raise ValueError(f"cannot open {str(path)!r} for writing: "
                             f"{exc.strerror or exc}") from None


@contextmanager
def _writing(path, wait: float = LOCK_WAIT, mode: str = "r+"):
    """``with _writing(path) as f:`` the sweep file open for writing (``mode="w"``: laid
    out anew), closed at the end: all of the write or, if anything fails (an exception, a
    write the disk refuses), none of it (``journal.Journaled``).  A refused write raises
    WriteFailed (its message: the cause)."""
    j = _journaled(path, wait)
    try:
        try:
            f = h5py.File(j, mode, libver=cf.LIBVER)
        except OSError as exc:
            raise ValueError(f"cannot open {str(path)!r} for writing: {exc}") from None
        try:
            yield f
        except BaseException:
            _close(f)                   # (a failure to close is the lesser news)
            raise
        failed = _close(f)
        if failed is not None:
            raise failed
    except BaseException:
        j.end(ok=False)
        if j.failure is None:
            raise
        _refused(j.failure)
    j.end(ok=True)
    if j.failure is not None:           # refused at the last moment: rolled back
        _refused(j.failure)


def _close(f: h5py.File) -> Exception | None:
    """Close ``f``; what closing raised, its handles then kept alive (``abandon``: HDF5
    could not close it, and trying again at exit would print or crash)."""
    try:
        f.close()
    except Exception as exc:
        abandon(f, exc.__traceback__)
        return exc
    return None


def _refused(exc: OSError):
    """Raise WriteFailed for the write the disk refused (``exc``), its cause the message."""
    cause = disk_cause(exc) or exc.strerror or str(exc)
    raise WriteFailed(cause, cause) from None


def header_digest(base_toml: str, grid_json: str, n_points: int,
                  save_runs: str | None = None) -> str:
    """The root attribute ``header_digest``: BLAKE2b-128 (hex) of what the file claims to
    sweep (the base configuration, the grid, the number of points) and of the root
    attribute that steers a resume (``save_runs``, where the points' run files go), which
    also vouches for the summary column ``row_digest`` (``row_digests``): format 4.
    ``save_runs`` None: the digest of format 3, which covers neither (its files lack
    ``row_digest``); files of formats 1 and 2 lack ``header_digest``."""
    h = hashlib.blake2b(digest_size=16, person=b"rodjit-sweep")
    parts = [str(base_toml), str(grid_json), str(int(n_points))]
    if save_runs is not None:
        parts += [str(save_runs), ROW_DIGEST]
    for part in parts:
        data = part.encode("utf-8", "surrogatepass")
        h.update(len(data).to_bytes(8, "little") + data)
    return h.hexdigest()


def observer_columns(f: h5py.File, base) -> tuple[str, ...]:
    """The summary columns of the sweep's observer (``output.observer`` of its ``base``
    configuration), in file order: the datasets of ``/summary`` whose attribute
    ``observer`` names it (none in a sweep without one)."""
    name = base.output.observer
    if name == "none" or "summary" not in f:
        return ()
    return tuple(c for c, ds in f["summary"].items() if ds.attrs.get(OBSERVER) == name)


def row_digests(index, values: dict, starts, counts, table: dict,
                offset: int = 0, observed: tuple = ()) -> np.ndarray:
    """The summary column ``row_digest`` of the points ``index``: BLAKE2b-128 (hex) of each
    point's summary row (``values``: ``SUMMARY_COLUMNS``, then the ``observed`` columns of
    its observer, over those points, as they read
    back), where its bounce rows are (``starts``, ``counts``) and those rows (``table``:
    the bounce columns as stored, row ``starts[k] - offset`` the point's first).  It proves
    a written row: a byte changed anywhere in it, or in its bounce rows, no longer
    matches.  Pending rows carry none (``b""``)."""
    index = np.asarray(index, np.int64)
    starts, counts = np.asarray(starts, np.int64), np.asarray(counts, np.int64)
    numbers = [index, starts, counts]
    texts = []
    for name, (kind, _) in SUMMARY_COLUMNS.items():
        if kind == "str":
            texts.append(values[name])
        else:
            numbers.append(np.asarray(values[name], _DTYPES[kind]))
    numbers += [np.asarray(values[name], np.float64) for name in observed]
    fixed = np.ascontiguousarray(np.column_stack([a.view(np.uint64) for a in numbers]))
    # each bounce row's bytes, column after column: a point's rows are one slice
    rows = [np.ascontiguousarray(table[name]) for name in BOUNCE_COLUMNS]
    size = rows[0].shape[0]
    packed = np.ascontiguousarray(np.concatenate(
        [r.view(np.uint8).reshape(size, r.dtype.itemsize) for r in rows], axis=1))
    out = np.empty(index.size, dtype="S32")
    for k in range(index.size):
        text = "\0".join(str(t[k]) for t in texts).encode("utf-8", "surrogatepass")
        a, c = int(starts[k]) - offset, int(counts[k])
        data = b"".join((fixed[k].tobytes(), len(text).to_bytes(8, "little"), text,
                         packed[a:a + c].tobytes() if c > 0 else b""))
        out[k] = hashlib.blake2b(data, digest_size=16, person=b"rodjit-row").hexdigest()
    return out


def create(path, base, grid: Grid, *, command: str, attrs: dict) -> None:
    """A new sweep file: attributes, every summary column with all rows pending.  It takes
    its name only once whole (``journal.creating``); WriteFailed if the disk refuses, and
    nothing is left."""
    n = len(grid)
    attrs = {"save_runs": "", **attrs}
    digest = header_digest(base.to_toml(), grid.to_json(), n, str(attrs["save_runs"]))
    with creating(path) as tmp, _writing(tmp, mode="w") as f:
        for key, value in {"rodjit_kind": KIND, "format_version": FORMAT_VERSION,
                           "rodjit_version": __version__, "created": now(),
                           "command": command, "base_config_toml": base.to_toml(),
                           "base_integrator_choice": base.choice,
                           "grid": grid.to_json(), "grid_keys": list(grid.keys),
                           "n_points": n,
                           "header_digest": digest,
                           "status": "running", "message": "",
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
            kind = key_kind(grid.values[grid.keys.index(key)])
            ds = s.create_dataset(key, data=col, dtype=_DTYPES[kind], chunks=chunk)
            spec = field_spec(key)
            ds.attrs["description"] = f"swept configuration key {key}"
            ds.attrs.update(long_name=spec.meaning, config_key=key)
            if spec.unit:
                ds.attrs["units"] = spec.unit
            ds.dims[0].attach_scale(point)
        coordinates = " ".join(grid.keys)      # CF auxiliary coordinates of every column
        columns = summary_columns(base)
        for name, col in empty_columns(n, columns).items():
            kind, text = columns[name]
            ds = s.create_dataset(name, data=col, dtype=_DTYPES[kind], chunks=chunk)
            ds.attrs["description"] = text
            if name in SUMMARY_COLUMNS:
                ds.attrs.update(cf.column_attrs("summary", name))
            else:       # a column of the sweep's observer
                ds.attrs.update(long_name=text, units="1")
                ds.attrs[OBSERVER] = base.output.observer
            if coordinates:
                ds.attrs["coordinates"] = coordinates
            ds.dims[0].attach_scale(point)
        for name, text in RAGGED.items():
            ds = s.create_dataset(name, data=np.full(n, -1 if name == "bounce_start" else 0,
                                                     np.int64), chunks=chunk)
            ds.attrs.update(description=text, long_name=text, units="1")
            ds.dims[0].attach_scale(point)
        ds = s.create_dataset(ROW_DIGEST, data=np.full(n, b"", "S32"), chunks=chunk)
        text = ("BLAKE2b-128 (hex) of the point's summary row and bounce rows, written with "
                "them ('' while pending): proves the row as rodjit wrote it")
        ds.attrs.update(description=text, long_name=text)
        ds.dims[0].attach_scale(point)
        _create_bounces(f)


def _create_bounces(f: h5py.File) -> None:
    """The empty bounce table of a new format-3 file: the run file's ``/bounces`` columns
    and each row's point, growing along ``bounce``."""
    g = f.create_group(BOUNCES, track_order=True)
    g.attrs["description"] = ("the bounce rows of every point (the run file's /bounces "
                              "columns); point_index gives each row's point; a point's rows "
                              "are contiguous, the points in the order they were written")
    g.attrs["rows"] = 0           # rows written; later ones are the remains of a cut write
    opts = dict(shape=(0,), maxshape=(None,), chunks=(BOUNCE_CHUNK,))
    row = g.create_dataset(ROW, dtype=np.int64, **opts)
    row.make_scale(ROW)
    row.attrs.update(long_name="row of the bounce table", units="1")
    ds = g.create_dataset(POINT_INDEX, dtype=np.int64, **opts)
    ds.attrs.update(long_name="index of the grid point of the bounce row", units="1",
                    instance_dimension=POINT)
    ds.dims[0].attach_scale(row)
    empty = empty_bounces()
    for name in BOUNCE_COLUMNS:
        dtype = np.asarray(empty[name]).dtype
        ds = g.create_dataset(name, dtype=cf.BOOL_DTYPE if dtype == bool else dtype, **opts)
        ds.attrs.update(cf.column_attrs("bounces", name))
        ds.dims[0].attach_scale(row)


def check_continuable(f: h5py.File, path=None) -> None:
    """ValueError unless this version continues the sweep file's format (``CONTINUES``)."""
    version = _format(f)
    if version not in CONTINUES:
        raise FormatNotContinued(path or f.filename, version, CONTINUES)


def reopen(path, *, history: str) -> None:
    """Mark a sweep file running again (resume), recording who continues it."""
    with _writing(path) as f:
        f.attrs["status"] = "running"
        f.attrs["message"] = ""
        f.attrs["history"] = history_with(f, history)
        stamp_writer(f.attrs)


def write_results(path, results, wait: float = LOCK_WAIT) -> None:
    """Write PointResults and BatchResults: their summary rows and bounce tables, as one
    BatchResult (``write_batch``).  FileBusy if another process holds the file open for
    longer than ``wait`` seconds."""
    if results:
        write_batch(path, as_batch(results), wait)


def write_batch(path, result, wait: float = LOCK_WAIT) -> None:
    """Write a BatchResult whose points are in increasing order (``ensemble.as_batch``):
    column by column, its bounce rows appended to the one table."""
    idx = np.asarray(result.index, dtype=np.int64)
    if idx.size == 0:
        return
    v = {name: np.asarray(result.values[name], dtype=object if kind == "str" else
                          _DTYPES[kind]) for name, (kind, _) in SUMMARY_COLUMNS.items()}
    counts = np.asarray(result.bounce_count, np.int64)
    with _writing(path, wait) as f:
        s = f["summary"]
        observed = tuple(c for c, ds in s.items() if OBSERVER in ds.attrs)
        v.update({name: np.asarray(result.values[name], np.float64) for name in observed})
        for name in v:
            if name == "status":
                continue      # last: a row counts as done only once all of it is there
            s[name][idx] = v[name]
        n0, table = _append_rows(f, idx, result.bounces, counts)
        if ROW_DIGEST in s:       # (a format-3 file written before rows had digests: none)
            s[ROW_DIGEST][idx] = row_digests(idx, v, s["bounce_start"][idx], counts, table,
                                             n0, observed)
        s["status"][idx] = v["status"]


def _append_rows(f: h5py.File, idx: np.ndarray, bounces: dict,
                 counts: np.ndarray) -> tuple[int, dict]:
    """Append the bounce rows of the points ``idx`` (increasing; ``counts`` rows each, in
    that order in the columns ``bounces``) to the one table, and record where each point's
    rows are; the table's first new row and the new rows as stored."""
    g, s = f[BOUNCES], f["summary"]
    n0 = int(g.attrs["rows"])
    starts = n0 + np.cumsum(counts) - counts
    n1 = n0 + int(counts.sum())
    stored = {}
    for name in BOUNCE_COLUMNS:
        data = np.asarray(bounces[name])
        stored[name] = data.astype(cf.BOOL_DTYPE) if data.dtype == bool else data
    if n1 > n0:
        names = (ROW, POINT_INDEX) + tuple(BOUNCE_COLUMNS)
        for name in names:
            g[name].resize((n1,))
        g[ROW][n0:n1] = np.arange(n0, n1, dtype=np.int64)
        g[POINT_INDEX][n0:n1] = np.repeat(idx, counts)
        for name in BOUNCE_COLUMNS:
            g[name][n0:n1] = stored[name]
    s["bounce_count"][idx] = counts
    s["bounce_start"][idx] = np.where(counts > 0, starts, -1)
    g.attrs["rows"] = n1
    return n0, stored


def finish(path, status: str, message: str = "", attrs: dict | None = None,
           wait: float = LOCK_WAIT) -> None:
    """Record the sweep's ``status`` and ``message`` (and ``attrs``).  FileBusy if another
    process holds the file open for longer than ``wait`` seconds."""
    if status not in STATUSES:
        raise ValueError(f"status {status!r} is not one of {STATUSES}")
    with _writing(path, wait) as f:
        f.attrs["status"] = status
        f.attrs["message"] = message
        for key, value in (attrs or {}).items():
            f.attrs[key] = value


# ---- reading ------------------------------------------------------------------------------
def check_sweep_file(f: h5py.File, path=None) -> None:
    """Raise NotARunFile unless ``f`` is a sweep file of a format this version reads."""
    check_kind(f, KIND, READS, path)


def read_header(f: h5py.File) -> dict:
    """Base configuration, grid and the root attributes of an open sweep file, which must
    prove itself: NotARunFile (one line, naming what does not match) if a required
    attribute is missing (``header_digest`` in a format that has it) or ``header_digest``
    does not match them."""
    name = f.filename
    with damaged(name):
        required = REQUIRED_ATTRS + (("header_digest",) if _format(f) >= DIGEST_SINCE
                                     else ())
        for attr in required:
            if attr not in f.attrs:
                raise NotARunFile(f"{name!r} is not a complete rodjit file (its root "
                                  f"attribute {attr!r} is missing)")
        if f.attrs["status"] not in STATUSES:
            raise NotARunFile(f"{name!r} is not a complete rodjit file (status "
                              f"{f.attrs['status']!r} is not one of {', '.join(STATUSES)})")
        attrs = {k: (v.tolist() if isinstance(v, np.ndarray) else v)
                 for k, v in f.attrs.items()}
        base_toml, grid_json = str(f.attrs["base_config_toml"]), str(f.attrs["grid"])
        n = f.attrs["n_points"]
        digest = str(f.attrs.get("header_digest", ""))
        # the digest of a format-4 file covers save_runs and vouches for row_digest; that
        # of a format-3 file covers neither
        rows = _format(f) >= ROWS_SINCE
        expected = (header_digest(base_toml, grid_json, int(n),
                                  str(f.attrs.get("save_runs", ""))) if rows
                    else header_digest(base_toml, grid_json, int(n)))
        if "header_digest" in f.attrs and digest != expected:
            raise NotARunFile(f"{name!r} fails its integrity check: its header_digest does "
                              f"not match its base_config_toml, grid, n_points and save_runs "
                              f"(the file was altered or damaged)")
    grid = Grid.from_json(grid_json)
    if int(n) != len(grid):
        raise NotARunFile(f"{name!r} fails its integrity check: it claims {int(n)} points, "
                          f"its grid has {len(grid)}")
    base = Config.from_stored_toml(base_toml).chosen(
        str(attrs.get("base_integrator_choice", "")))
    return {"base": base, "grid": grid, "attrs": attrs,
            "row_digests": rows, "observed": observer_columns(f, base)}


def _format(f: h5py.File) -> int:
    return int(f.attrs.get("format_version", FORMAT_VERSION))


def read_summary(f: h5py.File) -> dict[str, np.ndarray]:
    """The summary columns, in the layout's order (a format 1 or 2 file's: in file order);
    text columns as arrays of str.  NotARunFile if
    a column is missing or its rows are not the points the file claims.  A format 1 or 2
    file's columns of another meaning read under their ``OLD_SUMMARY`` names, and the
    columns it lacks as NaN."""
    name = f.filename
    out = {}
    old = _format(f) < 3
    with damaged(name):
        n = int(f.attrs["n_points"])
        for col, ds in f["summary"].items():
            if col == POINT and ds.is_scale:
                continue                      # the dimension, not a column
            if ds.shape != (n,):
                raise NotARunFile(f"{name!r} fails its integrity check: its summary column "
                                  f"{col!r} has {ds.shape[0] if ds.shape else 0} rows, not "
                                  f"the {n} points it claims")
            if col in RAGGED or col == ROW_DIGEST:
                continue                      # where the bounce rows are, not a column
            out[OLD_SUMMARY.get(col, col) if old else col] = (
                ds.asstr()[()].astype(object) if h5py.check_string_dtype(ds.dtype)
                else ds[()])
    for col in ("status",):     # (format 1 lacks columns added since)
        if col not in out:
            raise NotARunFile(f"{name!r} is not a complete rodjit file (its summary column "
                              f"{col!r} is missing)")
    if old:
        for col, (kind, _) in SUMMARY_COLUMNS.items():
            if col not in out and kind == "float":
                out[col] = np.full(n, np.nan)
    if not old:                 # the swept keys, then SUMMARY_COLUMNS, as written
        first = [str(k) for k in np.ravel(Grid.from_json(str(f.attrs["grid"])).keys)]
        first += [c for c in SUMMARY_COLUMNS if c not in first]
        out = {c: out[c] for c in first if c in out} | {c: v for c, v in out.items()
                                                       if c not in first}
    return out


def read_bounces(f: h5py.File, index: int) -> dict[str, np.ndarray]:
    """Point ``index``'s bounce table (empty columns if the point has not run)."""
    if _format(f) >= 3:
        start = int(f["summary/bounce_start"][index])
        count = int(f["summary/bounce_count"][index])
        if start < 0 or count == 0:
            return empty_bounces()
        g = f[BOUNCES]
        if count < 0 or start + count > int(g.attrs["rows"]) or start + count > g[ROW].shape[0] \
                or np.any(g[POINT_INDEX][start:start + count] != index):
            raise NotARunFile(f"{f.filename!r} fails its integrity check: point {index}'s "
                              f"bounce rows {start}..{start + count - 1} are not its rows "
                              f"in its bounce table ({g[ROW].shape[0]} rows)")
        return _as_read({name: g[name][start:start + count] for name in BOUNCE_COLUMNS})
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
    return _as_read(out)


def _as_read(table: dict) -> dict[str, np.ndarray]:
    """A bounce table as rodjit hands it out: its flag columns as bool."""
    for name in BOOL_COLUMNS:
        table[name] = cf.as_bool(table[name])
    return table


def read_all_bounces(f: h5py.File, done=None) -> dict[str, np.ndarray]:
    """Every point's bounce rows in one table, ordered by point (then by time), with the
    column ``point``: each row's grid point.  Any format.  ``done``: the points to read
    (a mask; by default those the file has written), of which those the file has not
    written are left out."""
    if _format(f) < 3:
        n = int(f.attrs["n_points"])
        return join_bounces((i, read_bounces(f, i)) for i in range(n)
                            if done is None or done[i])
    s, g = f["summary"], f[BOUNCES]
    written = s["status"].asstr()[()] != "pending"
    done = written if done is None else written & np.asarray(done, bool)
    start, count = s["bounce_start"][()], s["bounce_count"][()]
    points = np.flatnonzero(done & (count > 0))
    c = count[points]
    offset = np.cumsum(c) - c               # where each point's rows go in the result
    take = np.arange(int(c.sum()), dtype=np.int64) + np.repeat(start[points] - offset, c)
    out = {"point": np.repeat(points, c)}
    for name in BOUNCE_COLUMNS:
        out[name] = g[name][()][take]
    return _as_read(out)


def join_bounces(tables) -> dict[str, np.ndarray]:
    """One table of ``(point, bounce table)`` pairs, with the column ``point``."""
    tables = list(tables)
    empty = empty_bounces()
    out = {"point": np.concatenate([np.full(len(t["t_impact"]), i, np.int64)
                                    for i, t in tables] or [np.zeros(0, np.int64)])}
    for name in BOUNCE_COLUMNS:
        out[name] = np.concatenate([np.asarray(t[name]) for _, t in tables]
                                   or [np.asarray(empty[name])])
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
