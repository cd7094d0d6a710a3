"""Reading a run file: its configuration, valid checkpoint and tables, or all of it as a
``rodjit.Result`` (``load_file``).  A file still being written is read up to the rows
present in every column.  Formats 1 and 2 read alike: the nodes' positions from wherever
the format keeps them, boolean columns as bool."""
from __future__ import annotations

import os
import time

import h5py
import numpy as np

from ..config import Config
from ..records.columns import BOOL_COLUMNS
from ..records.result import Result
from ..records.stats import run_stats
from ..stepping import layout as L
from .cf import as_bool
from .h5files import NotARunFile, check_kind, damaged, open_file
from .run_layout import (CK_ARRAYS, CK_DATASETS, CK_SCALARS, DIGESTS_SINCE,
                         KIND, OLD_BOUNCE_FILL, READS, REQUIRED_ATTRS, STATUSES, TABLES,
                         OBSERVED, ck_datasets, counter_names, counters_by_name,
                         current_checkpoint, digest_parts, digest_rows, x_path)

__all__ = ["check_run_file", "check_not_lost", "read_config", "read_checkpoint", "read_table", "read_x",
           "load_file"]


def check_run_file(f: h5py.File, path=None) -> None:
    """Raise NotARunFile unless ``f`` is a complete rodjit run file of a format this
    version reads: its root attributes, every table's columns and both checkpoint slots
    present, with their digests in a format that has them (a file that claims such a
    format without them would otherwise be believed unchecked; its checkpoint's integrity
    is ``read_checkpoint``'s)."""
    name = str(path if path is not None else f.filename)
    with damaged(name):
        check_kind(f, KIND, READS, path)
        for attr in REQUIRED_ATTRS:
            if attr not in f.attrs:
                raise NotARunFile(f"{name!r} is not a complete rodjit file (its root "
                                  f"attribute {attr!r} is missing)")
        status = f.attrs["status"]
        if status not in STATUSES:
            raise NotARunFile(f"{name!r} is not a complete rodjit file (status {status!r} "
                              f"is not one of {', '.join(STATUSES)})")
        version = int(f.attrs.get("format_version", 1))
        old = version < 3    # without the newer columns
        needed = [f"{t}/{c}" for t, cols in TABLES.items() for c in cols
                  if not (old and t == "bounces" and c in OLD_BOUNCE_FILL)] + [x_path(f)]
        slot_datasets = CK_DATASETS + (("digest",) if version >= DIGESTS_SINCE else ())
        needed += ["checkpoint/current"] + [f"checkpoint/slot{i}/{d}" for i in (0, 1)
                                            for d in slot_datasets]
        for obj in needed:
            if obj not in f:
                raise NotARunFile(f"{name!r} is not a complete rodjit file ('/{obj}' is "
                                  f"missing)")


def read_config(f: h5py.File) -> Config:
    """The configuration the file's run runs (root attribute ``config_toml``; with the
    ``integrator_choice`` of a run whose integrator "auto" chose, ``Config.choice``)."""
    with damaged(f.filename):
        text = f.attrs["config_toml"]
        choice = f.attrs.get("integrator_choice", "")
    return Config.from_stored_toml(text).chosen(str(choice))


def read_checkpoint(f: h5py.File) -> dict:
    """The valid checkpoint: arrays for ``Run.from_checkpoint`` plus ``lengths`` (table
    rows it matches, ``{"snapshots": n, ...}``) and cumulative ``compile_time``."""
    with damaged(f.filename):
        tries = 3 if f.swmr_mode else 1      # a live writer may commit while it is read
        for _ in range(tries - 1):
            try:
                return _read_checkpoint(f)
            except NotARunFile:
                time.sleep(0.05)
        return _read_checkpoint(f)          # the last try: its refusal is the answer


def _read_checkpoint(f: h5py.File) -> dict:
    ck = f["checkpoint"]
    if f.swmr_mode:
        ck["current"].refresh()
    current = ck["current"][()]
    slot = int(current) if np.ndim(current) == 0 else -1
    if slot not in (0, 1):
        raise NotARunFile(f"{f.filename!r} holds no valid checkpoint yet")
    g = ck[f"slot{slot}"]
    datasets = ck_datasets(OBSERVED in g)
    if f.swmr_mode:
        for name in datasets + (("digest",) if "digest" in g else ()):
            g[name].refresh()
    values = {name: g[name][()] for name in datasets}
    verify_checkpoint(f, slot, values, g["digest"][()] if "digest" in g else None)
    out = {name: values[name] for name in CK_ARRAYS + datasets[len(CK_DATASETS):]}
    # the per-scheme counters by name, laid out as this version counts them
    out["sstats"] = counters_by_name(out["sstats"], counter_names(g["sstats"]))
    for name in CK_SCALARS:
        out[name] = float(values[name])
    out["lengths"] = dict(zip(TABLES, (int(n) for n in values["lengths"])))
    return current_checkpoint(out, read_config(f))


_PART_NAMES = {"config_toml": "stored configuration (config_toml)"}


def verify_checkpoint(f: h5py.File, slot: int, values: dict, digest) -> None:
    """NotARunFile (one line, naming what does not match) unless the checkpoint of
    ``slot`` (``values``: its datasets) proves itself: its ``digest`` (absent in files
    written before digests existed) matches its content and the stored configuration, its
    state has a row of every node, and the table rows it claims are in the file."""
    name = f.filename
    where = f"the checkpoint (slot {slot})"
    if digest is not None:
        expected = digest_rows(values, str(f.attrs["config_toml"]))
        if np.shape(digest) != expected.shape:
            raise NotARunFile(f"{name!r} fails its integrity check: the digest of {where} "
                              f"has shape {np.shape(digest)}, not {expected.shape}")
        bad = [_PART_NAMES.get(part, f"'{part}'") for part, a, b in
               zip(digest_parts(OBSERVED in values), digest, expected)
               if not np.array_equal(a, b)]
        if bad:
            raise NotARunFile(f"{name!r} fails its integrity check: the digest of {where} "
                              f"does not match its {', '.join(bad)} (the file was altered or "
                              f"damaged)")
    n1 = f[x_path(f)].shape[0]
    state = values["state"]
    if np.ndim(state) != 2 or state.shape[1] != n1:
        raise NotARunFile(f"{name!r} fails its integrity check: the state of {where} has "
                          f"shape {np.shape(state)}, not (3, {n1}) for its {n1} nodes")
    lengths = np.ravel(values["lengths"])
    if lengths.shape != (len(TABLES),):
        raise NotARunFile(f"{name!r} fails its integrity check: {where} claims "
                          f"{lengths.size} table lengths, not {len(TABLES)}")
    for table, n in zip(TABLES, lengths):
        rows = min(f[table][c].shape[0] for c in TABLES[table] if c in f[table])
        if not 0 <= int(n) <= rows:
            raise NotARunFile(f"{name!r} fails its integrity check: {where} claims {int(n)} "
                              f"rows of /{table}, which holds {rows}")


def check_not_lost(f: h5py.File, ck: dict, on_disk: int, path=None) -> None:
    """NotARunFile unless every byte the checkpoint ``ck`` relies on lies in the first
    ``on_disk`` bytes of the file: a file cut short (``h5files.repair_truncated``) by a
    full disk loses only what was written after its last checkpoint; one cut anywhere
    else lost rows its checkpoint claims, which zeros must not stand in for."""
    name = str(path if path is not None else f.filename)
    with damaged(name):
        for table, cols in TABLES.items():
            n = ck["lengths"][table]
            for col in cols:
                ds = f[table][col]
                if n == 0 or ds.chunks is None:
                    continue
                for i in range(ds.id.get_num_chunks()):
                    info = ds.id.get_chunk_info(i)
                    if info.chunk_offset[0] < n and info.byte_offset + info.size > on_disk:
                        raise NotARunFile(
                            f"{name!r} is cut short ({on_disk} bytes) inside rows its "
                            f"checkpoint claims (/{table}/{col} from row "
                            f"{info.chunk_offset[0]}): they are lost, and the file cannot "
                            f"be continued")
        ckg = f["checkpoint"]
        g = ckg[f"slot{int(ckg['current'][()])}"]
        for ds in [ckg["current"], *(g[d] for d in g)]:
            offset = ds.id.get_offset()
            if offset is not None and offset + ds.id.get_storage_size() > on_disk:
                raise NotARunFile(f"{name!r} is cut short ({on_disk} bytes) inside its "
                                  f"checkpoint ({ds.name}): it cannot be continued")


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


def load_file(path: str | os.PathLike[str]) -> Result:
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
            dissipated=float(ck["clock"][L.DISSIPATED]), observed=read_observed(f, ck))


def read_observed(f: h5py.File, ck: dict) -> dict:
    """The observer's values in the checkpoint ``ck`` of ``f`` (``Result.observed``): the
    entries of its ``observed`` array that its ``names`` do not mark as the observer's
    state; empty for a run without an observer."""
    if OBSERVED not in ck:
        return {}
    names = counter_names(f["checkpoint/slot0"][OBSERVED])
    return {n: float(x) for n, x in zip(names, np.asarray(ck[OBSERVED]))
            if ".state" not in n and n != "unused"}
