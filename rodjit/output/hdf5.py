"""The run file: one self-describing HDF5 file per run, written while the run goes on.

Layout (the public contract; README "HDF5 layout"): root attributes, ``/grid/x``, the
tables ``/snapshots``, ``/diagnostics``, ``/episodes``, ``/bounces`` (one dataset per
column, growing along axis 0, with dimension scales so xarray sees coordinates) and
``/checkpoint`` (two slots written alternately; ``/checkpoint/current`` names the valid one).

The writer works in SWMR mode: other processes may read the file while it grows
(``h5py.File(path, "r", swmr=True)``), and a writer killed at any moment leaves a file
whose valid checkpoint matches the first ``lengths`` rows of every table.
"""
from __future__ import annotations

import datetime
import os
import socket
from pathlib import Path
from typing import NamedTuple

import h5py
import numpy as np
from h5py import h5a, h5d, h5p, h5s, h5t

from ..driver.run import Run, Sink
from ..stepping import layout as L
from ..stepping.schemes import SCHEME_STATS
from .extremes import Extremes
from .table import Table

__all__ = ["KIND", "FORMAT_VERSION", "STATUSES", "TABLES", "RunWriter", "NotARunFile",
           "FileBusy", "open_file", "check_kind", "check_run_file", "read_config",
           "read_checkpoint", "read_table", "load_file", "create_run_file", "reopen_run_file",
           "recover", "writer_alive", "CLOCK_NAMES", "COUNT_NAMES", "EV_NAMES"]

KIND = "run"            # root attribute rodjit_kind: what this file holds
FORMAT_VERSION = 1
STATUSES = ("running", "completed", "interrupted", "failed")

SNAPSHOT_CHUNK_BYTES = 256 * 1024   # one chunk of u (or v) holds this many bytes of snapshots
COLUMN_CHUNK_ROWS = 8192            # diagnostics: rows per chunk
EVENT_CHUNK_ROWS = 1024             # episodes, bounces: rows per chunk

# group -> columns (in file order); the first column is the group's dimension scale
TABLES = {
    "snapshots": ("t", "step", "u", "v"),
    "diagnostics": L.DIAG_COLUMNS,
    "episodes": L.EPISODE_COLUMNS,
    "bounces": ("t_impact",) + tuple(c for c in L.BOUNCE_COLUMNS if c != "t_impact") + ("open",),
}
_INT_COLUMNS = {"step", "n_episodes"}
_BOOL_COLUMNS = {"open"}

_DESCRIPTIONS = {
    "snapshots/t": "simulated time of each snapshot (t0 + k * output.snapshot_interval)",
    "snapshots/step": "accepted steps taken before the snapshot",
    "snapshots/u": "height u_i of every node (rows: times, columns: nodes at x)",
    "snapshots/v": "velocity v_i of every node",
    "snapshots/x": "natural position x_i = i/N of each node",
    "grid/x": "natural position x_i = i/N of each node",
    "episodes/t_start": "start of a contact episode (u_0 < 0)",
    "episodes/t_end": "end of the episode",
    "bounces/open": "true if the bounce's last episode had not ended when the run stopped",
}


def _names(size: int, mapping: dict[int, str]) -> tuple[str, ...]:
    """Names for the entries of a layout array, checked complete at import."""
    if sorted(mapping) != list(range(size)):
        raise RuntimeError(f"layout names out of date: indices {sorted(mapping)} vs size {size}")
    return tuple(mapping[i] for i in range(size))


CLOCK_NAMES = _names(L.CLOCK_SIZE, {
    L.T: "t", L.DT: "dt", L.T_END: "t_end", L.DISSIPATED: "dissipated", L.E0: "energy0",
    L.SNAP_DT: "snapshot_interval", L.DIAG_DT: "diagnostics_interval", L.T0: "t0",
    L.W: "cm_velocity", L.TOL: "time_tolerance", L.EMIN: "min_strain"})
COUNT_NAMES = _names(L.COUNT_SIZE, {
    L.STEP: "step", L.REJECTED: "rejected", L.K_SNAP: "next_snapshot_index",
    L.K_DIAG: "next_diagnostics_index", L.N_SNAP: "buffered_snapshots",
    L.N_DIAG: "buffered_diagnostics", L.N_EP: "buffered_episodes",
    L.N_BOUNCE: "buffered_bounces", L.EPISODES_TOTAL: "episodes_total",
    L.BOUNCES_TOTAL: "bounces_total", L.STARTED: "started"})
EV_NAMES = _names(L.EV_SIZE, {
    L.IN_CONTACT: "in_contact", L.EP_START: "episode_start",
    L.B_NEP: "bounce_episodes", L.B_T_IMPACT: "bounce_t_impact",
    L.B_W_IMPACT: "bounce_w_impact", L.B_T_RELEASE: "bounce_t_release",
    L.B_W_RELEASE: "bounce_w_release", L.CUR_MIN_U0: "min_u0_since_impact",
    L.CUR_MAX_FF: "max_floor_force_since_impact", L.CUR_MIN_EPS: "min_strain_since_impact",
    L.REL_MIN_U0: "min_u0_at_release", L.REL_MAX_FF: "max_floor_force_at_release",
    L.REL_MIN_EPS: "min_strain_at_release"})
_EXTREME_COLUMNS = tuple(L.DIAG_COLUMNS.index(c) for c in Extremes.COLUMNS)
_SUMMARY_ATTRS = ("rodjit_version", "created", "command", "history")
_CK_ARRAYS = ("state", "clock", "count", "ev", "sstats")
_CK_SCALARS = ("run_time", "compile_time")
_CK_DATASETS = _CK_ARRAYS + _CK_SCALARS + ("lengths",)
_CK_NAMES = {"state": ("u", "v", "a"), "clock": CLOCK_NAMES, "count": COUNT_NAMES,
             "ev": EV_NAMES, "sstats": SCHEME_STATS or ("unused",),
             "lengths": tuple(TABLES)}


class NotARunFile(ValueError):
    """The path is not a rodjit run file (missing, not HDF5, or another kind of file)."""


class FileBusy(ValueError):
    """Another process holds the file (a live writer, or a reader blocking a write)."""


# ---- opening and inspecting --------------------------------------------------------------
def open_file(path) -> h5py.File:
    """Open a rodjit file read-only: plainly if it was closed, in SWMR-read mode if a writer
    has it open or was killed before closing it (both leave the SWMR flags set)."""
    path = Path(path)
    if not path.exists():
        raise NotARunFile(f"{str(path)!r} does not exist")
    if path.is_dir():
        raise NotARunFile(f"{str(path)!r} is a directory, not a rodjit file")
    if not os.access(path, os.R_OK):
        raise NotARunFile(f"{str(path)!r} is not readable")
    if not h5py.is_hdf5(path):
        raise NotARunFile(f"{str(path)!r} is not a rodjit file (not an HDF5 file)")
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        if "already open for write" not in str(exc):
            raise NotARunFile(f"cannot open {str(path)!r}: {exc}") from None
    return h5py.File(path, "r", swmr=True)


def check_kind(f: h5py.File, kind: str, version: int, path=None) -> None:
    """Raise NotARunFile unless ``f`` is a rodjit ``kind`` file ("run", "sweep") of format
    ``version``."""
    name = str(path if path is not None else f.filename)
    found = f.attrs.get("rodjit_kind")
    if found is None:
        raise NotARunFile(f"{name!r} is not a rodjit file (no 'rodjit_kind' attribute)")
    if found != kind:
        raise NotARunFile(f"{name!r} is a rodjit {found!r} file, not a {kind} file")
    got = int(f.attrs.get("format_version", 0))
    if got != version:
        raise NotARunFile(f"{name!r} has {kind}-file format {got}; this rodjit reads format "
                          f"{version}")


def check_run_file(f: h5py.File, path=None) -> None:
    """Raise NotARunFile unless ``f`` is a rodjit run file of a format this version reads."""
    check_kind(f, KIND, FORMAT_VERSION, path)


def read_config(f: h5py.File):
    from ..config import Config
    return Config.from_toml_string(f.attrs["config_toml"])


def read_checkpoint(f: h5py.File) -> dict:
    """The valid checkpoint: arrays for ``Run.from_checkpoint`` plus ``lengths`` (table
    rows it matches, ``{"snapshots": n, ...}``) and cumulative ``compile_time``."""
    ck = f["checkpoint"]
    slot = int(ck["current"][()])
    if slot not in (0, 1):
        raise NotARunFile(f"{f.filename!r} holds no valid checkpoint yet")
    g = ck[f"slot{slot}"]
    out = {name: g[name][()] for name in _CK_ARRAYS}
    for name in _CK_SCALARS:
        out[name] = float(g[name][()])
    out["lengths"] = dict(zip(TABLES, (int(n) for n in g["lengths"][()])))
    return out


def read_table(f: h5py.File, group: str, rows: slice | None = None) -> dict[str, np.ndarray]:
    """Columns of one table (all rows, or ``rows``); a table still being written is cut to
    the rows present in every column."""
    g = f[group]
    n = min(g[c].shape[0] for c in TABLES[group])
    sel = slice(0, n) if rows is None else slice(*rows.indices(n))
    return {c: g[c][sel] for c in TABLES[group]}


def _process_tag(pid: int) -> str:
    """Boot id and start time of process ``pid`` (Linux), so a reused pid is not mistaken
    for the writer; "" where /proc does not tell."""
    try:
        with open("/proc/sys/kernel/random/boot_id") as fh:
            boot = fh.read().strip()
        with open(f"/proc/{pid}/stat") as fh:
            start = fh.read().rsplit(")", 1)[1].split()[19]   # field 22: start time
        return f"{boot}:{start}"
    except (OSError, IndexError):
        return ""


def _writer_attrs() -> dict:
    pid = os.getpid()
    return {"writer_host": socket.gethostname(), "writer_pid": pid,
            "writer_tag": _process_tag(pid)}


def writer_alive(f: h5py.File) -> bool | None:
    """Is the process that last wrote ``f`` still running?  None if it ran on another host."""
    if f.attrs.get("writer_host") != socket.gethostname():
        return None
    pid = int(f.attrs.get("writer_pid", -1))
    if pid <= 0 or pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    tag = str(f.attrs.get("writer_tag", ""))
    return not tag or _process_tag(pid) in ("", tag)


def load_file(path):
    """Read a whole run file into a ``rodjit.Result`` (the same object ``simulate`` returns)."""
    from ..driver.result import Result

    with open_file(path) as f:
        check_run_file(f, path)
        config = read_config(f)
        ck = read_checkpoint(f)
        snaps = read_table(f, "snapshots")
        n1 = config.rod.N + 1
        steps = int(ck["count"][L.STEP])
        stats = {"steps": steps, "rejected_steps": int(ck["count"][L.REJECTED]),
                 "wall_time": ck["compile_time"] + ck["run_time"],
                 "compile_time": ck["compile_time"], "run_time": ck["run_time"],
                 "node_steps_per_second": steps * n1 / ck["run_time"] if ck["run_time"] > 0
                 else 0.0}
        stats.update({name: int(v) for name, v in zip(SCHEME_STATS, ck["sstats"])})
        return Result(
            config=config, x=f["grid/x"][()], t=snaps["t"], u=snaps["u"], v=snaps["v"],
            diagnostics=read_table(f, "diagnostics"), episodes=read_table(f, "episodes"),
            bounces=read_table(f, "bounces"), stats=stats,
            status=str(f.attrs["status"]), message=str(f.attrs["message"]),
            t_final=float(ck["clock"][L.T]), u_final=ck["state"][0].copy(),
            v_final=ck["state"][1].copy(), energy0=float(ck["clock"][L.E0]),
            dissipated=float(ck["clock"][L.DISSIPATED]))


# ---- layout -------------------------------------------------------------------------------
def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def _filters(compression: str) -> dict:
    if compression == "gzip":
        return {"compression": "gzip", "compression_opts": 4, "shuffle": True}
    if compression == "lzf":
        return {"compression": "lzf", "shuffle": True}
    return {}


class _Layout(NamedTuple):
    """What a writer writes: each table, the checkpoint slots' datasets, current."""

    tables: dict
    slots: list
    current: h5py.Dataset

    @classmethod
    def of(cls, f: h5py.File) -> "_Layout":
        """Looked up in an existing run file."""
        ckg = f["checkpoint"]
        return cls({name: Table.of(f[name][c] for c in cols) for name, cols in TABLES.items()},
                   [{name: ckg[f"slot{i}"][name] for name in _CK_DATASETS} for i in (0, 1)],
                   ckg["current"])


def _build_layout(f: h5py.File, config, ck: dict, attrs: dict) -> _Layout:
    """Create every group, dataset, dimension scale and attribute of a run file with empty
    tables and the checkpoint ``ck`` in slot 0 (``ck["lengths"]``: the rows it matches, none
    if absent); everything must exist before SWMR writing starts.  Return the datasets
    written."""
    from .. import __version__

    n1 = config.rod.N + 1
    x = np.arange(n1, dtype=np.float64) / config.rod.N
    base = {"rodjit_kind": KIND, "format_version": FORMAT_VERSION,
            "rodjit_version": __version__, "created": _now(), "command": "",
            "config_toml": config.to_toml(), "status": "running", "message": "",
            **_writer_attrs()}
    base.update(attrs)
    for key, value in base.items():
        _attr(f, key, value)
    filters = _filters(config.output.compression)

    grid = f.create_group("grid")
    gx = grid.create_dataset("x", data=x)
    gx.make_scale("x")

    def column(group, name, row_shape, chunk_rows, dtype=np.float64, like=None):
        """A growing column; ``like``: a column of the same group, shape and dtype whose
        creation properties it shares."""
        if like is not None:
            ds = _like(like, group, name)
        else:
            ds = group.create_dataset(name, shape=(0,) + row_shape,
                                      maxshape=(None,) + row_shape,
                                      chunks=(chunk_rows,) + row_shape, dtype=dtype, **filters)
        text = _DESCRIPTIONS.get(f"{group.name[1:]}/{name}")
        if text:
            _attr(ds, "description", text)
        return ds

    snap = f.create_group("snapshots")
    rows = max(1, SNAPSHOT_CHUNK_BYTES // (8 * n1))
    t = column(snap, "t", (), rows)
    t.make_scale("t")
    sx = snap.create_dataset("x", data=x)
    sx.make_scale("x")
    _attr(sx, "description", _DESCRIPTIONS["snapshots/x"])
    step = column(snap, "step", (), rows, np.int64)
    step.dims[0].attach_scale(t)
    columns = {"snapshots": [t, step]}
    for name in ("u", "v"):
        ds = column(snap, name, (n1,), rows, like=columns["snapshots"][-1] if name == "v" else None)
        ds.dims[0].attach_scale(t)
        ds.dims[1].attach_scale(sx)
        columns["snapshots"].append(ds)
    shapes = {"snapshots": ((rows, [(), (), (n1,), (n1,)],
                             [np.float64, np.int64, np.float64, np.float64]))}

    for group, chunk in (("diagnostics", COLUMN_CHUNK_ROWS), ("episodes", EVENT_CHUNK_ROWS),
                         ("bounces", EVENT_CHUNK_ROWS)):
        g = f.create_group(group)
        names = TABLES[group]
        scale = column(g, names[0], (), chunk)
        scale.make_scale(names[0])
        columns[group] = [scale]
        dtypes = [np.int64 if name in _INT_COLUMNS else bool if name in _BOOL_COLUMNS
                  else np.float64 for name in names]
        for name, dtype in zip(names[1:], dtypes[1:]):
            ds = column(g, name, (), chunk, dtype, like=scale if dtype is np.float64 else None)
            ds.dims[0].attach_scale(scale)
            columns[group].append(ds)
        shapes[group] = (chunk, [()] * len(names), dtypes)
    tables = {name: Table(columns[name], cap=shapes[name][0], rows=shapes[name][1],
                          dtypes=shapes[name][2], direct=not filters) for name in TABLES}

    ckg = f.create_group("checkpoint")
    _attr(ckg, "description", "two slots written alternately; 'current' names the valid "
                              "one; its 'lengths' are the table rows it matches")
    current = ckg.create_dataset("current", data=np.int64(0))
    lengths = ck.get("lengths", {})
    first = {name: np.asarray(ck[name], np.float64) for name in _CK_SCALARS}
    first.update({name: ck[name] for name in _CK_ARRAYS},
                 lengths=np.array([lengths.get(name, 0) for name in TABLES], np.int64))
    slots = []
    for slot in (0, 1):                       # slot 1: zeros (its fill value), unwritten
        g = ckg.create_group(f"slot{slot}")
        slots.append({})
        for name in _CK_DATASETS:
            value = np.asarray(first[name])
            ds = slots[-1][name] = (g.create_dataset(name, data=value) if slot == 0 else
                                    g.create_dataset(name, value.shape, value.dtype))
            if name in _CK_NAMES:
                _attr(ds, "names", _CK_NAMES[name])
    return _Layout(tables, slots, current)


# Creating ~50 datasets and ~35 attributes through h5py's high-level calls costs ~8 ms, more
# than streaming thousands of snapshots; these two make the same objects at a third of the
# price (h5py's checks for an existing attribute or dataset are moot in a new file).
_STR = h5py.string_dtype()
_LINKS = h5p.create(h5p.LINK_CREATE)       # as h5py creates links with ASCII names
_LINKS.set_create_intermediate_group(True)


def _attr(obj, name: str, value) -> None:
    """A new attribute, stored as ``obj.attrs[name] = value`` stores it: str and sequences
    of str as variable-length UTF-8 strings, numbers as their NumPy type."""
    arr = np.asarray(value)
    if arr.dtype.kind in "OU":
        arr = np.asarray(value, dtype=_STR)
    space = h5s.create_simple(arr.shape) if arr.ndim else h5s.create(h5s.SCALAR)
    h5a.create(obj.id, name.encode(), h5t.py_create(arr.dtype, logical=True), space).write(arr)


def _like(proto: h5py.Dataset, group: h5py.Group, name: str) -> h5py.Dataset:
    """A new dataset in ``group`` with the dtype, shape, maxshape and creation properties
    (chunks, filters) of ``proto``."""
    return h5py.Dataset(h5d.create(group.id, name.encode(), proto.id.get_type(),
                                   proto.id.get_space(), dcpl=proto.id.get_create_plist(),
                                   lcpl=_LINKS))


def _put(ds: h5py.Dataset, value) -> None:
    """Overwrite a whole small dataset (low-level: a tenth of ``ds[...] = value``'s cost;
    HDF5 converts the value's type to the dataset's)."""
    ds.id.write(h5s.ALL, h5s.ALL, np.ascontiguousarray(value))


class RunWriter(Sink):
    """The HDF5 sink: tables fed by ``Run.advance``, checkpoints by ``save``.

    ``save`` writes the buffered rows and a checkpoint that records the table lengths, with
    an HDF5 flush before and after flipping ``/checkpoint/current``: whatever moment the
    process dies, the current slot is complete and matches rows present on disk.  The
    writer also keeps what the end-of-run summary needs (``summary.closed_summary``), so
    the file is not read back.
    """

    def __init__(self, f: h5py.File, path, config, checkpoint: dict, layout=None):
        """``checkpoint``: the file's valid one, as ``read_checkpoint`` gives it; ``layout``:
        that of a file just laid out (empty tables), else it is looked up."""
        self.file = f
        self.path = str(path)
        self.config = config
        new = layout is not None
        layout = layout or _Layout.of(f)
        self.tables = layout.tables
        self._current = layout.current
        self._slots = layout.slots
        self.current = int(self._current[()])
        self.checkpoint = checkpoint
        self.compile_time_before = float(checkpoint["compile_time"])
        self.extremes = Extremes()
        b = self.tables["bounces"]       # every bounce row, kept for the summary
        self._bounces = [[np.zeros(0, buf.dtype) if new else d[:b.length]]
                         for d, buf in zip(b.ds, b.buf)]
        if not new:
            self.extremes.read(f["diagnostics"], self.tables["diagnostics"].length)
        self.final = None        # what closing leaves in the file (status, bounces, ...)

    # Sink interface: drained blocks of the compiled loop
    def snapshots(self, t, step, u, v):
        self.tables["snapshots"].append((t, step, u, v))

    def diagnostics(self, rows):
        self.tables["diagnostics"].append(list(rows.T))
        self.extremes.update(*(rows[:, j] for j in _EXTREME_COLUMNS))

    def episodes(self, rows):
        self.tables["episodes"].append(list(rows.T))

    def bounces(self, rows, is_open=None):
        cols = dict(zip(L.BOUNCE_COLUMNS, rows.T))
        cols["n_episodes"] = cols["n_episodes"].astype(np.int64)
        cols["open"] = (np.zeros(rows.shape[0], bool) if is_open is None
                        else np.asarray(is_open, bool))
        cols = [cols[c] for c in TABLES["bounces"]]
        self.tables["bounces"].append(cols)
        for kept, c in zip(self._bounces, cols):
            kept.append(np.array(c, dtype=kept[0].dtype))

    def save(self, run) -> None:
        """Write buffered rows and a checkpoint of ``run`` matching them.  A run that is not
        ``drained`` (an error while draining) gets no new checkpoint: the last one stays
        valid, and a resume cuts the tables back to it."""
        for table in self.tables.values():
            table.flush()
        if not run.drained:
            self.file.flush()
            return
        self._commit(run.checkpoint(), self.compile_time_before + run.compile_time)

    def _commit(self, ck: dict, compile_time: float) -> None:
        """Checkpoint ``ck`` into the idle slot with the current table lengths (rows already
        written), flush, flip ``current``, flush."""
        slot = 1 if self.current == 0 else 0
        g = self._slots[slot]
        for name in _CK_ARRAYS:
            _put(g[name], ck[name])
        _put(g["run_time"], float(ck["run_time"]))
        _put(g["compile_time"], compile_time)
        lengths = [t.length for t in self.tables.values()]
        _put(g["lengths"], lengths)
        self.file.flush()
        _put(self._current, slot)
        self.file.flush()
        self.current = slot
        self.checkpoint = {name: ck[name] for name in _CK_ARRAYS}
        self.checkpoint.update(run_time=float(ck["run_time"]), compile_time=compile_time,
                               lengths=dict(zip(TABLES, lengths)))

    def close(self, run, status: str, message: str = "") -> None:
        """Final checkpoint, then the provisional row of the bounce still open (listed but
        beyond the checkpoint's lengths, so a resume drops it), then status, then close."""
        if status not in STATUSES:
            raise ValueError(f"status {status!r} is not one of {STATUSES}")
        if run is not None:
            self.save(run)
            pending = run.pending_bounce()
            if pending is not None:
                self.bounces(pending[0][None, :], [pending[1]])
                self.tables["bounces"].flush()
        attrs = self.file.attrs              # (each .attrs looks the root group up)
        attrs["status"] = status
        attrs["message"] = message
        self.final = {
            "status": status, "message": message,
            "counts": {name: t.written for name, t in self.tables.items()},
            "bounces": {c: np.concatenate(kept)[:self.tables["bounces"].written]
                        for c, kept in zip(TABLES["bounces"], self._bounces)},
            "attrs": {k: attrs[k] for k in _SUMMARY_ATTRS if k in attrs}}
        self.file.close()

    def abandon(self, status: str, message: str) -> None:
        """Mark and close after an unexpected error, keeping the last saved checkpoint."""
        try:
            if self.file.id.valid:
                self.file.attrs["status"] = status
                self.file.attrs["message"] = message
                self.file.close()
        except Exception:  # the file may be the cause (disk full); nothing more to save
            pass


def _open_for_writing(path, mode: str) -> h5py.File:
    try:
        return h5py.File(path, mode, libver="latest")
    except OSError as exc:
        if "lock" in str(exc):
            raise FileBusy(f"{str(path)!r} is open in another process; close it there and "
                           f"retry") from None
        raise ValueError(f"cannot open {str(path)!r} for writing: {exc}") from None


def _history(f: h5py.File, entry: str) -> list[str]:
    return [str(s) for s in f.attrs.get("history", [])] + [f"{_now()} {entry}"]


def create_run_file(path, config, start, *, command: str) -> RunWriter:
    """A new run file in SWMR mode whose first checkpoint is ``start``: a Run not started
    yet, or the ``checkpoint()`` of one (taken before it started, so the run may already
    be computing)."""
    ck = start.checkpoint() if isinstance(start, Run) else start
    f = _open_for_writing(path, "w")
    try:
        layout = _build_layout(f, config, ck, {"command": command,
                                               "history": [f"{_now()} created by: {command}"]})
        f.swmr_mode = True             # flushes the file: the first checkpoint is on disk
        writer = RunWriter(f, path, config, dict(ck, lengths=dict.fromkeys(TABLES, 0)),
                           layout)
    except BaseException:
        f.close()
        raise
    return writer


def reopen_run_file(path, *, config_toml: str | None, history: str) -> RunWriter:
    """Open a closed run file to continue it: cut every table to the checkpoint's lengths
    (dropping the provisional open bounce and rows written after the last checkpoint),
    mark it running, then switch to SWMR writing."""
    f = _open_for_writing(path, "r+")
    try:
        ck = read_checkpoint(f)
        lengths = ck["lengths"]
        for name, cols in TABLES.items():
            for col in cols:
                ds = f[name][col]
                if ds.shape[0] != lengths[name]:
                    ds.resize(lengths[name], axis=0)
        if config_toml is not None:
            f.attrs["config_toml"] = config_toml
        f.attrs["history"] = _history(f, history)
        f.attrs["status"] = "running"
        f.attrs["message"] = ""
        for key, value in _writer_attrs().items():
            f.attrs[key] = value
        f.swmr_mode = True
        return RunWriter(f, path, read_config(f), ck)
    except BaseException:
        f.close()
        raise


def recover(path) -> None:
    """Rebuild a file whose writer died without closing it (SWMR flags still set): copy the
    rows matched by its checkpoint into a fresh file, which then replaces it."""
    path = Path(path)
    tmp = path.with_name(path.name + ".recovering")
    with h5py.File(path, "r", swmr=True) as src:
        check_run_file(src, path)
        config = read_config(src)
        ck = read_checkpoint(src)
        attrs = {k: v for k, v in src.attrs.items()}
        t = float(ck["clock"][L.T])
        attrs["history"] = _history(src, f"recovered at the checkpoint t = {t!r} after the "
                                         f"writer stopped without closing the file")
        attrs["status"] = "interrupted"
        attrs["message"] = (f"the writing process stopped without closing the file (killed?); "
                            f"recovered at the checkpoint t = {t!r}")
        with h5py.File(tmp, "w", libver="latest") as dst:
            _build_layout(dst, config, ck, attrs)       # its checkpoint in slot 0
            for group, cols in TABLES.items():
                n = ck["lengths"][group]
                for col in cols:
                    s, d = src[group][col], dst[group][col]
                    d.resize(n, axis=0)
                    step = d.chunks[0] * 16
                    for i in range(0, n, step):
                        d[i:min(n, i + step)] = s[i:min(n, i + step)]
    os.replace(tmp, path)
