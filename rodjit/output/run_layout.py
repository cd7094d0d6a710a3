"""The run file's layout (the public contract; README "HDF5 layout") and the builder that
creates it.

Format 3 (formats 1 and 2 are still read; continuing one rebuilds it in format 3): root attributes, the tables ``/snapshots``, ``/diagnostics``, ``/episodes``,
``/bounces`` (one dataset per column, growing along axis 0, with dimension scales so xarray
sees coordinates; ``/snapshots/x`` is the node coordinate) and ``/checkpoint`` (two slots written alternately; ``/checkpoint/current``
names the valid one; each slot's ``digest`` proves its content and the stored
configuration, ``run_reader.verify_checkpoint``).  Everything is created before SWMR writing starts, which cannot add
objects.  The file is netCDF-4 / CF where that fits (``cf``): every dataset has a
``long_name`` (and a ``units`` where one unit applies), every axis a dimension, booleans are
flagged ``int8``.  Format 1 also had ``/grid/x``, the same values as ``/snapshots/x``.
Formats 1 and 2 cut bounces at every apex of the centre of mass and had no
``energy_vibration_impact``, ``restitution_energy`` and ``ambiguous`` columns: read, their
rows have NaN and ``ambiguous`` true there (``OLD_BOUNCE_FILL``), and their checkpoints the
bounce bookkeeping entries of format 3 at their fresh values (``current_checkpoint``).
"""
from __future__ import annotations

import hashlib
from typing import NamedTuple

import h5py
import numpy as np
from h5py import h5a, h5d, h5p, h5s, h5t

from ..records.columns import BOOL_COLUMNS, BOUNCE_COLUMNS, INT_COLUMNS
from ..stepping import layout as L
from ..stepping.events import AMBIGUOUS_SPEED
from ..stepping.registry import SCHEME_STATS
from ..version import __version__
from . import cf
from .growing_table import Table
from .h5files import now, writer_attrs

__all__ = ["KIND", "FORMAT_VERSION", "READS", "x_path", "STATUSES", "TABLES", "CLOCK_NAMES", "COUNT_NAMES",
           "EV_NAMES", "SUMMARY_ATTRS", "CK_ARRAYS", "CK_SCALARS", "CK_DATASETS",
           "DIGEST_PARTS", "DIGESTS_SINCE", "REQUIRED_ATTRS", "RunLayout", "build_layout",
           "add_digests", "digest_rows", "overwrite", "CK_COUNTERS", "counter_names",
           "counters_by_name", "OLD_BOUNCE_FILL", "current_checkpoint", "OBSERVED",
           "ck_datasets", "digest_parts"]

KIND = "run"            # root attribute rodjit_kind: what this file holds
FORMAT_VERSION = 3
READS = (1, 2, 3)       # the formats this version reads (and continues: 1 and 2 rebuilt in 3)
STATUSES = ("running", "completed", "interrupted", "failed")

SNAPSHOT_CHUNK_BYTES = 256 * 1024   # one chunk of u (or v) holds this many bytes of snapshots
COLUMN_CHUNK_ROWS = 8192            # diagnostics: rows per chunk
EVENT_CHUNK_ROWS = 1024             # episodes, bounces: rows per chunk

# group -> columns (in file order); the first column is the group's dimension scale
TABLES = {
    "snapshots": ("t", "step", "u", "v"),
    "diagnostics": L.DIAG_COLUMNS,
    "episodes": L.EPISODE_COLUMNS,
    "bounces": BOUNCE_COLUMNS,
}

_DESCRIPTIONS = {
    "snapshots/t": "simulated time of each snapshot (t0 + k * output.snapshot_interval, or "
                   "the listed output.times)",
    "snapshots/step": ("accepted steps taken up to the snapshot (for a row interpolated by a "
                       "dense output: up to the end of the step it lies in)"),
    "snapshots/u": "height u_i of every node (rows: times, columns: nodes at x)",
    "snapshots/v": "velocity v_i of every node",
    "snapshots/x": "natural position x_i = i/N of each node",
    "episodes/t_start": "start of a contact episode (u_0 < 0)",
    "episodes/t_end": "end of the episode",
    "bounces/open": "true if the bounce's last episode had not ended when the run stopped",
    "bounces/ambiguous": ("true if the bounce's restitution is not an impact's: open or not "
                          "over when the run stopped, not falling at impact (w_impact >= 0), "
                          f"or an approach speed below {AMBIGUOUS_SPEED:g} of the "
                          "vibrational velocity scale sqrt(2 energy_vibration_impact)"),
    "bounces/restitution_energy": ("w_release / sqrt(w_impact^2 + 2 energy_vibration_impact):"
                                   " the rebound over the energy brought into the impact"),
}

# the bounce columns formats 1 and 2 lack, as they read: (value, dtype)
OLD_BOUNCE_FILL = {"energy_vibration_impact": (np.nan, np.float64),
                   "restitution_energy": (np.nan, np.float64), "ambiguous": (True, bool)}
_EV_SIZE_FORMAT2 = 13       # ev entries of a checkpoint of formats 1 and 2


def current_checkpoint(ck: dict, config) -> dict:
    """``ck`` (``read_checkpoint``) with its ``ev`` in the current layout: a format 1 or 2
    checkpoint gains the entries added since at their fresh values (the flight time of
    ``config``, no turn-over seen, no vibration energy of a pending bounce)."""
    ev = np.asarray(ck["ev"])
    if ev.shape != (_EV_SIZE_FORMAT2,):
        return ck
    from ..records.physics import flight_time

    new = np.zeros(L.EV_SIZE)
    new[:_EV_SIZE_FORMAT2] = ev
    new[L.B_EV_IMPACT] = np.nan
    new[L.FLIGHT_TIME] = flight_time(config)
    return dict(ck, ev=new)


def x_path(f: h5py.File) -> str:
    """Where a run file keeps the nodes' positions: ``/snapshots/x`` (format 2) or
    ``/grid/x`` (format 1)."""
    return "grid/x" if "grid" in f else "snapshots/x"


# the checkpoint's dimensions (netCDF dimensions without values): name -> entries named
_CK_DIMS = {"state": ("state_row", "node"), "clock": ("clock_entry",),
            "count": ("count_entry",), "ev": ("ev_entry",), "sstats": ("sstats_entry",),
            "lengths": ("table",), "observed": ("observed_entry",)}
_CK_LONG_NAMES = {
    "state": "heights u, velocities v and accelerations a of every node",
    "clock": "the run's real-valued state (entries named in 'names')",
    "count": "the run's counters (entries named in 'names')",
    "ev": "contact and bounce bookkeeping (entries named in 'names')",
    "sstats": "per-scheme step counts (entries named in 'names')",
    "run_time": "wall time spent stepping in compiled code", "compile_time":
    "wall time spent compiling or loading kernels", "lengths":
    "rows of each table (in 'names' order) this checkpoint matches",
    "current": "the valid checkpoint slot (0 or 1)",
    "observed": "the observer's state, then its values (entries named in 'names')"}
_CK_UNITS = {"run_time": "s", "compile_time": "s", "lengths": "1", "current": "1"}


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
    L.REL_MIN_EPS: "min_strain_at_release", L.B_EV_IMPACT: "bounce_energy_vibration_impact",
    L.FLIGHT: "bounce_turned_over", L.FLIGHT_TIME: "flight_time"})
SUMMARY_ATTRS = ("rodjit_version", "format_version", "created", "command",
                 "history")                                 # shown by ``info``
CK_ARRAYS = ("state", "clock", "count", "ev", "sstats")      # a checkpoint's arrays
CK_SCALARS = ("run_time", "compile_time")                     # and its numbers
_CK_DATASETS = CK_DATASETS = CK_ARRAYS + CK_SCALARS + ("lengths",)
# what a slot's ``digest`` covers, one row each: its datasets and the stored configuration
DIGEST_PARTS = _CK_DATASETS + ("config_toml",)
# The observer's array (``output.observer``: its state, then its values, named in its
# ``names``), in the slots of a run with an observer only: the files of runs without one
# are laid out as before, and every reader of format 3 reads them.
OBSERVED = "observed"


def ck_datasets(observed: bool) -> tuple[str, ...]:
    """A checkpoint slot's datasets (``observed``: with the observer's array)."""
    return _CK_DATASETS + ((OBSERVED,) if observed else ())


def digest_parts(observed: bool) -> tuple[str, ...]:
    """What the ``digest`` of such a slot covers, one row each, in order."""
    return ck_datasets(observed) + ("config_toml",)
DIGEST_SIZE = 16
# the first format whose files carry a ``digest`` in both checkpoint slots: a file that
# claims this format or a later one and lacks them is not complete (older files never had
# them and are read as before)
DIGESTS_SINCE = 3
# the root attributes without which a run file is not complete (the kind and format are
# checked on their own, ``h5files.check_kind``)
REQUIRED_ATTRS = ("config_toml", "status")
_CK_NAMES = {"state": ("u", "v", "a"), "clock": CLOCK_NAMES, "count": COUNT_NAMES,
             "ev": EV_NAMES, "sstats": SCHEME_STATS or ("unused",),
             "lengths": tuple(TABLES)}


CK_COUNTERS = _CK_NAMES["sstats"]       # the names of a new checkpoint's 'sstats' entries


def counter_names(ds) -> tuple[str, ...]:
    """The names of a checkpoint's ``sstats`` entries as its file stores them (attribute
    ``names``; a file without it has the current ``SCHEME_STATS`` layout)."""
    names = ds.attrs.get("names")
    if names is None:
        return CK_COUNTERS[:ds.shape[0]]
    return tuple(n.decode() if isinstance(n, bytes) else str(n) for n in np.atleast_1d(names))


def counters_by_name(values, names, to=None) -> np.ndarray:
    """Counter ``values`` named ``names`` laid out as ``to`` (default: this version's
    ``sstats``, ``SCHEME_STATS``): matched by name, a counter ``to`` has and ``names``
    lacks is 0, one ``to`` lacks is dropped.  A checkpoint stores the per-scheme counters
    by name, so adding or removing a counter never breaks resuming an older file."""
    to = CK_COUNTERS if to is None else to
    stored = dict(zip(names, np.asarray(values, np.int64).tolist()))
    return np.array([stored.get(n, 0) for n in to], np.int64)


def _filters(compression: str) -> dict:
    if compression == "gzip":
        return {"compression": "gzip", "compression_opts": 4, "shuffle": True}
    if compression == "lzf":
        return {"compression": "lzf", "shuffle": True}
    return {}


class RunLayout(NamedTuple):
    """What a writer writes: each table, the checkpoint slots' datasets, current."""

    tables: dict
    slots: list
    current: h5py.Dataset

    @classmethod
    def of(cls, f: h5py.File) -> "RunLayout":
        """Looked up in an existing run file."""
        ckg = f["checkpoint"]
        names = (ck_datasets(OBSERVED in ckg["slot0"])
                 + (("digest",) if "digest" in ckg["slot0"] else ()))
        return cls({name: Table.of(f[name][c] for c in cols) for name, cols in TABLES.items()},
                   [{name: ckg[f"slot{i}"][name] for name in names} for i in (0, 1)],
                   ckg["current"])


def build_layout(f: h5py.File, config, ck: dict, attrs: dict) -> RunLayout:
    """Create every group, dataset, dimension scale and attribute of a run file with empty
    tables and the checkpoint ``ck`` in slot 0 (``ck["lengths"]``: the rows it matches, none
    if absent); everything must exist before SWMR writing starts.  Return the datasets
    written."""
    n1 = config.rod.N + 1
    x = np.arange(n1, dtype=np.float64) / config.rod.N
    base = {"rodjit_kind": KIND, "format_version": FORMAT_VERSION,
            "rodjit_version": __version__, "created": now(), "command": "",
            "config_toml": config.to_toml(), "status": "running", "message": "",
            **writer_attrs(),
            **cf.root_attrs(f"rodjit run: rod of {config.rod.N} segments dropped on a floor")}
    if config.choice:         # how "auto" chose the integrator (``Config.resolve``)
        base["integrator_choice"] = config.choice
    base.update(attrs)
    for key, value in base.items():
        _attr(f, key, value)
    filters = _filters(config.output.compression)

    def column(group, name, row_shape, chunk_rows, dtype=np.float64, like=None):
        """A growing column; ``like``: a column of the same group, shape and dtype whose
        creation properties it shares."""
        if like is not None:
            ds = _like(like, group, name)
        else:
            ds = group.create_dataset(name, shape=(0,) + row_shape,
                                      maxshape=(None,) + row_shape,
                                      chunks=(chunk_rows,) + row_shape, dtype=dtype, **filters)
        table = group.name[1:]
        text = _DESCRIPTIONS.get(f"{table}/{name}")
        if text:
            _attr(ds, "description", text)
        for key, value in cf.column_attrs(table, name).items():
            _attr(ds, key, value)
        return ds

    snap = f.create_group("snapshots")
    rows = max(1, SNAPSHOT_CHUNK_BYTES // (8 * n1))
    t = column(snap, "t", (), rows)
    t.make_scale("t")
    sx = snap.create_dataset("x", data=x)
    sx.make_scale("x")
    _attr(sx, "description", _DESCRIPTIONS["snapshots/x"])
    for key, value in cf.column_attrs("grid", "x").items():
        _attr(sx, key, value)
    step = column(snap, "step", (), rows, np.int64)
    step.dims[0].attach_scale(t)
    columns = {"snapshots": [t, step]}
    for name in ("u", "v"):
        ds = column(snap, name, (n1,), rows, like=columns["snapshots"][-1] if name == "v" else None)
        ds.dims[0].attach_scale(t)
        ds.dims[1].attach_scale(sx)
        columns["snapshots"].append(ds)
    # each table's chunk rows, row shapes and dtypes
    shapes: dict[str, tuple[int, list[tuple[int, ...]], list[type[np.generic]]]] = {
        "snapshots": (rows, [(), (), (n1,), (n1,)],
                      [np.float64, np.int64, np.float64, np.float64])}

    for group, chunk in (("diagnostics", COLUMN_CHUNK_ROWS), ("episodes", EVENT_CHUNK_ROWS),
                         ("bounces", EVENT_CHUNK_ROWS)):
        g = f.create_group(group)
        names = TABLES[group]
        scale = column(g, names[0], (), chunk)
        scale.make_scale(names[0])
        columns[group] = [scale]
        dtypes: list[type[np.generic]] = [
            np.int64 if name in INT_COLUMNS else cf.BOOL_DTYPE if name in BOOL_COLUMNS
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
    _ck_attrs(current, "current")
    lengths = ck.get("lengths", {})
    first = {name: np.asarray(ck[name], np.float64) for name in CK_SCALARS}
    first.update({name: ck[name] for name in CK_ARRAYS},
                 lengths=np.array([lengths.get(name, 0) for name in TABLES], np.int64))
    entry_names = dict(_CK_NAMES)
    if config.output.observer != "none":
        from ..stepping.observers import get_observer
        ob = get_observer(config.output.observer)
        first[OBSERVED] = np.zeros(ob.size + len(ob.columns))
        if OBSERVED in ck:
            first[OBSERVED][:] = np.asarray(ck[OBSERVED])[:first[OBSERVED].size]
        entry_names[OBSERVED] = (tuple(f"{ob.name}.state{i}" for i in range(ob.size))
                                 + tuple(ob.columns)) or ("unused",)
    datasets = ck_datasets(OBSERVED in first)
    dims = {}
    for name in datasets:
        for dim, size in zip(_CK_DIMS.get(name, ()), np.shape(first[name])):
            dims[dim] = cf.pure_dimension(ckg, dim, size)
    slots: list[dict[str, h5py.Dataset]] = []
    for slot in (0, 1):                       # slot 1: zeros (its fill value), unwritten
        g = ckg.create_group(f"slot{slot}")
        slots.append({})
        for name in datasets:
            value = np.asarray(first[name])
            ds = slots[-1][name] = (g.create_dataset(name, data=value) if slot == 0 else
                                    g.create_dataset(name, value.shape, value.dtype))
            if name in entry_names:
                _attr(ds, "names", entry_names[name])
            _ck_attrs(ds, name)
            for axis, dim in enumerate(_CK_DIMS.get(name, ())):
                ds.dims[axis].attach_scale(dims[dim])
    first_values = {name: np.asarray(first[name]) for name in datasets}
    add_digests(ckg, slots, digest_rows(first_values, base["config_toml"]))
    return RunLayout(tables, slots, current)


def digest_rows(values: dict, config_toml: str) -> np.ndarray:
    """The ``digest`` of a checkpoint slot: one BLAKE2b row per ``DIGEST_PARTS`` entry,
    over the dtype, shape and bytes of each of its datasets (``values``: name -> the array
    as stored) and over the stored configuration."""
    parts = digest_parts(OBSERVED in values)
    rows = np.zeros((len(parts), DIGEST_SIZE), np.uint8)
    for i, name in enumerate(parts):
        h = hashlib.blake2b(name.encode(), digest_size=DIGEST_SIZE, person=b"rodjit-ck")
        if name == "config_toml":
            h.update(str(config_toml).encode("utf-8", "surrogatepass"))
        else:
            arr = np.ascontiguousarray(values[name])
            h.update(f"|{arr.dtype.str}|{arr.shape}|".encode())
            h.update(arr.tobytes())
        rows[i] = np.frombuffer(h.digest(), np.uint8)
    return rows


def add_digests(ckg: h5py.Group, slots: list, first=None) -> None:
    """Create the ``digest`` dataset of both slots (``first``: slot 0's rows; slot 1 and a
    missing ``first`` stay zeros, which match no content), adding them to ``slots``.  Run
    files written before digests existed lack them and get them when continued."""
    parts = digest_parts(OBSERVED in ckg["slot0"])
    shape = (len(parts), DIGEST_SIZE)
    # its axes are netCDF dimensions without values, as the other checkpoint datasets'
    dims = [ckg[d] if d in ckg else cf.pure_dimension(ckg, d, n)
            for d, n in zip(("digest_part", "digest_byte"), shape)]
    for slot, datasets in enumerate(slots):
        g = ckg[f"slot{slot}"]
        ds = (g.create_dataset("digest", data=first) if slot == 0 and first is not None
              else g.create_dataset("digest", shape, np.uint8))
        _attr(ds, "names", parts)
        _attr(ds, "long_name", "checkpoint: BLAKE2b-128 of each of the slot's datasets and "
                               "of the root attribute config_toml (in 'names' order)")
        for axis, dim in enumerate(dims):
            ds.dims[axis].attach_scale(dim)
        datasets["digest"] = ds


def _ck_attrs(ds, name: str) -> None:
    _attr(ds, "long_name", "checkpoint: " + _CK_LONG_NAMES[name])
    if name in _CK_UNITS:              # the other arrays mix units (see their 'names')
        _attr(ds, "units", _CK_UNITS[name])


# A new run file has dozens of datasets and attributes, whose creation through h5py's
# high-level calls costs more than streaming many snapshots; _attr and _like make the same
# objects through the low-level API, skipping h5py's checks for an existing attribute or
# dataset, which are moot in a new file (benchmarks/streaming_overhead.py measures it).
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


def overwrite(ds: h5py.Dataset, value) -> None:
    """Overwrite a whole small dataset through the low-level API, far cheaper than
    ``ds[...] = value`` for the checkpoint's small writes (HDF5 converts the value's type
    to the dataset's)."""
    ds.id.write(h5s.ALL, h5s.ALL, np.ascontiguousarray(value))
