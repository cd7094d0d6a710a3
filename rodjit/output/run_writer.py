"""Writing a run file: ``RunWriter`` (the HDF5 sink and its checkpoint commit) and the
three ways a writer starts: a new file (``create_run_file``), a closed one continued
(``reopen_run_file``), a file whose writer died rebuilt from its checkpoint (``recover``).

The writer works in SWMR mode: other processes may read the file while it grows
(``h5py.File(path, "r", swmr=True)``), and a writer killed at any moment leaves a file
whose valid checkpoint matches the first ``lengths`` rows of every table.
"""
from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from ..records.bounces import bounce_table
from ..records.columns import BOOL_COLUMNS
from ..records.extremes import Extremes
from ..records.impact import ImpactStream
from ..records.sink import Sink
from ..stepping import layout as L
from .cf import LIBVER
from .h5files import (WriteFailed, abandon, disk_cause, history_with, now, open_for_writing,
                      stamp_writer)
from .run_layout import (CK_ARRAYS, CK_COUNTERS, FORMAT_VERSION, OLD_BOUNCE_FILL,
                         STATUSES, SUMMARY_ATTRS, TABLES, RunLayout, add_digests,
                         OBSERVED, build_layout, ck_datasets, counter_names,
                         counters_by_name, digest_rows, overwrite)
from .run_reader import check_run_file, read_checkpoint, read_config
from .writer_id import LEGACY_ATTRS, WRITER_ATTRS

__all__ = ["RunWriter", "create_run_file", "reopen_run_file", "recover"]


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
        layout = layout or RunLayout.of(f)
        self.tables = layout.tables
        self._current = layout.current
        self._slots = layout.slots
        self.current = int(self._current[()])
        self._config_toml = str(f.attrs["config_toml"])     # what each digest covers
        self._dtypes = {name: ds.dtype for name, ds in self._slots[0].items()}
        # the file's own counter names (an older file may name other counters than
        # this version's SCHEME_STATS): each checkpoint is written by name into them
        self._counters = counter_names(self._slots[0]["sstats"])
        self.checkpoint = checkpoint
        self.compile_time_before = float(checkpoint["compile_time"])
        self.extremes = Extremes()
        self.impact = ImpactStream(config)    # the first-impact observables
        b = self.tables["bounces"]       # every bounce row, kept for the summary
        self._bounces = [[np.zeros(0, _kept(name, buf.dtype)) if new else
                          d[:b.length].astype(_kept(name, d.dtype))]
                         for name, d, buf in zip(TABLES["bounces"], b.ds, b.buf)]
        if not new:
            self.extremes.read(f["diagnostics"], self.tables["diagnostics"].length)
            self._read_impact(f, checkpoint["ev"])
        self.pending = None              # the bounce pending at the end (``close``)
        # what closing leaves in the file (status, bounces, ...)
        self.final: dict[str, Any] | None = None

    def _read_impact(self, f, ev) -> None:
        """The first-impact state of the rows up to the checkpoint, the run in contact then
        (``ev``) if its first contact is open."""
        n_ep = self.tables["episodes"].length
        episodes = {c: f["episodes"][c][:n_ep] for c in ("t_start", "t_end")}
        start = math.nan
        if n_ep:
            start = float(episodes["t_start"][0])
        elif ev[L.IN_CONTACT] != 0.0:
            start = float(ev[L.EP_START])
        closed = {c: kept[0] for c, kept in zip(TABLES["bounces"], self._bounces)}
        self.impact.read(f["diagnostics"], self.tables["diagnostics"].length, episodes,
                         closed, len(closed["t_impact"]), start)

    # Sink interface: drained blocks of the compiled loop
    def snapshots(self, t, step, u, v):
        self.tables["snapshots"].append((t, step, u, v))

    def diagnostics(self, rows):
        self.tables["diagnostics"].append(list(rows.T))
        self.extremes.update_rows(rows)

    def episodes(self, rows):
        self.tables["episodes"].append(list(rows.T))

    def block(self, diagnostics, episodes, bounces, in_contact, contact_start):
        self.impact.block(diagnostics, episodes, bounces, in_contact, contact_start)

    def bounces(self, rows, pending=None):
        """Closed bounce rows, or (``rows`` None) the ``pending`` bounce of the run."""
        cols = list(bounce_table(() if rows is None else (rows,), pending).values())
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
        # what the slot stores: the counters by the file's own names
        arrays = CK_ARRAYS + ((OBSERVED,) if OBSERVED in g else ())
        stored = {name: ck[name] if name != "sstats" else
                  counters_by_name(ck[name], CK_COUNTERS, self._counters)
                  for name in arrays}
        for name in arrays:
            overwrite(g[name], stored[name])
        overwrite(g["run_time"], float(ck["run_time"]))
        overwrite(g["compile_time"], compile_time)
        lengths = [t.length for t in self.tables.values()]
        overwrite(g["lengths"], lengths)
        if "digest" in g:
            values = {"run_time": float(ck["run_time"]), "compile_time": compile_time,
                      "lengths": lengths, **stored}
            overwrite(g["digest"], digest_rows(
                {name: np.asarray(values[name], self._dtypes[name])
                 for name in ck_datasets(OBSERVED in g)},
                self._config_toml))
        self.file.flush()
        overwrite(self._current, slot)
        self.file.flush()
        self.current = slot
        self.checkpoint = {name: ck[name] for name in arrays}
        self.checkpoint.update(run_time=float(ck["run_time"]), compile_time=compile_time,
                               lengths=dict(zip(TABLES, lengths)))

    def close(self, run, status: str, message: str = "") -> None:
        """Final checkpoint, then the provisional row of the bounce still open (listed but
        beyond the checkpoint's lengths, so a resume drops it), then status, then close."""
        if status not in STATUSES:
            raise ValueError(f"status {status!r} is not one of {STATUSES}")
        if run is not None:
            self.save(run)
            pending = self.pending = run.pending_bounce()
            if pending is not None:
                self.bounces(None, pending)
                self.tables["bounces"].flush()
        attrs = self.file.attrs              # (each .attrs looks the root group up)
        attrs["status"] = status
        attrs["message"] = message
        self.final = {
            "status": status, "message": message,
            "counts": {name: t.written for name, t in self.tables.items()},
            "bounces": {c: np.concatenate(kept)[:self.tables["bounces"].written]
                        for c, kept in zip(TABLES["bounces"], self._bounces)},
            "attrs": {k: attrs[k] for k in SUMMARY_ATTRS if k in attrs}}
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


def _kept(column: str, dtype):
    """The dtype a kept bounce column has in memory (a flagged int8 column as bool)."""
    return bool if column in BOOL_COLUMNS else dtype


def create_run_file(path, config, start, *, command: str) -> RunWriter:
    """A new run file in SWMR mode whose first checkpoint is ``start``: a Run not started
    yet, or the ``checkpoint()`` of one (taken before it started, so the run may already
    be computing)."""
    ck = start if isinstance(start, dict) else start.checkpoint()
    try:
        f = open_for_writing(path, "w")
    except BaseException as exc:
        cause = disk_cause(exc)
        if cause is None:
            raise
        Path(path).unlink(missing_ok=True)   # the start of a file the disk cut short
        raise WriteFailed(f"cannot create {str(path)!r}: {cause}; nothing was "
                          f"written", cause) from None
    try:
        layout = build_layout(f, config, ck, {"command": command,
                                               "history": [f"{now()} created by: {command}"]})
        f.swmr_mode = True             # flushes the file: the first checkpoint is on disk
        writer = RunWriter(f, path, config, dict(ck, lengths=dict.fromkeys(TABLES, 0)),
                           layout)
    except BaseException as exc:
        cause = disk_cause(exc)
        if cause is None:
            f.close()
            raise
        # the layout is incomplete and HDF5 cannot close a file it cannot extend: leave
        # the handle alone and remove the file, which holds no checkpoint yet
        abandon(f, exc.__traceback__)
        Path(path).unlink(missing_ok=True)
        raise WriteFailed(f"cannot create {str(path)!r}: {cause}; nothing was "
                          f"written", cause) from None
    return writer


def reopen_run_file(path, *, config_toml: str | None, history: str) -> RunWriter:
    """Open a closed run file to continue it: cut every table to the checkpoint's lengths
    (dropping the provisional open bounce and rows written after the last checkpoint),
    mark it running, then switch to SWMR writing."""
    with h5py.File(path, "r") as f:
        old = int(f.attrs.get("format_version", FORMAT_VERSION)) < FORMAT_VERSION
    if old:      # an older layout lacks columns this version writes: rebuild it first
        _rebuild(path, swmr=False, status=None, message=None,
                 note=f"rebuilt in format {FORMAT_VERSION} to be continued")
    f = open_for_writing(path, "r+")
    try:
        ck = read_checkpoint(f)
        # whatever reading can refuse, before the first write: a refusal leaves the file
        entries = history_with(f, history)
        lengths = ck["lengths"]
        for name, cols in TABLES.items():
            for col in cols:
                ds = f[name][col]
                if ds.shape[0] != lengths[name]:
                    ds.resize(lengths[name], axis=0)
        if config_toml is not None:
            f.attrs["config_toml"] = config_toml
        _sign_current(f)
        f.attrs["history"] = entries
        f.attrs["status"] = "running"
        f.attrs["message"] = ""
        stamp_writer(f.attrs)
        f.swmr_mode = True
        return RunWriter(f, path, read_config(f), ck)
    except BaseException:
        f.close()
        raise


def _sign_current(f: h5py.File) -> None:
    """Give the current slot the digest of its (verified) content and of the file's
    configuration as it now stands: after ``config_toml`` changed (a new t_end), and in a
    file written before digests existed, whose slots get them here (before SWMR writing
    starts, which cannot add datasets)."""
    ckg = f["checkpoint"]
    if "digest" not in ckg["slot0"]:
        add_digests(ckg, [{}, {}])
    g = ckg[f"slot{int(ckg['current'][()])}"]
    values = {name: g[name][()] for name in ck_datasets(OBSERVED in g)}
    overwrite(g["digest"], digest_rows(values, str(f.attrs["config_toml"])))


def recover(path) -> None:
    """Rebuild a file whose writer died without closing it (SWMR flags still set): copy the
    rows matched by its checkpoint into a fresh file, which then replaces it (the file a
    symbolic link names, keeping the link).  A file with several hard links is refused
    (``check_single_link``)."""
    with h5py.File(path, "r", swmr=True) as src:
        t = float(read_checkpoint(src)["clock"][L.T])
    _rebuild(path, swmr=True, status="interrupted",
             message=(f"the writing process stopped without closing the file (killed?); "
                      f"recovered at the checkpoint t = {t!r}"),
             note=(f"recovered at the checkpoint t = {t!r} after the writer stopped without "
                   f"closing the file"))


def check_single_link(path) -> None:
    """ValueError (one line) if ``path`` has more than one hard link.  A rebuild (crash
    recovery, an older format made continuable) writes a fresh file and renames it over
    the old one: the only way that a kill at any moment leaves either the old file or the
    whole new one.  A rename replaces one name only; the other hard links would keep the
    killed run, and two copies would diverge.  Writing the rebuilt bytes back into the
    shared file instead would leave, if killed during that copy, no valid file under any
    name.  So such a file is refused before anything is written, saying what to do."""
    links = os.stat(path).st_nlink
    if links > 1:
        raise ValueError(f"{str(path)!r} has {links} hard links: continuing it needs a "
                         f"rebuild into a new file, which would part this name from the "
                         f"other {links - 1} (they would keep the old run); remove the other "
                         f"links (find -samefile {str(path)!r}) or continue a copy; nothing "
                         f"was written")


def _rebuild(path, *, swmr: bool, status, message, note: str) -> None:
    """Copy the rows of ``path`` matched by its checkpoint into a fresh file in the current
    layout, which then replaces it (the file a symbolic link names, keeping the link);
    ``status`` and ``message`` (None: kept) are its new ones, ``note`` goes into its
    history.  A column an older format lacks gets its ``OLD_BOUNCE_FILL`` value.
    ValueError (one line, nothing written) for a file with several hard links
    (``check_single_link``)."""
    path = Path(os.path.realpath(path))
    check_single_link(path)
    tmp = path.with_name(path.name + ".recovering")
    with h5py.File(path, "r", swmr=swmr) as src:
        check_run_file(src, path)
        config = read_config(src)
        ck = read_checkpoint(src)
        attrs = {k: v for k, v in src.attrs.items()}
        attrs.pop("format_version")       # the rebuilt file has the current layout
        for name in LEGACY_ATTRS + WRITER_ATTRS:   # this process's record, not the old one
            attrs.pop(name, None)
        attrs["history"] = history_with(src, note)
        if status is not None:
            attrs["status"] = status
            attrs["message"] = message
        with h5py.File(tmp, "w", libver=LIBVER) as dst:
            build_layout(dst, config, ck, attrs)       # its checkpoint in slot 0
            for group, cols in TABLES.items():
                n = ck["lengths"][group]
                for col in cols:
                    d = dst[group][col]
                    d.resize(n, axis=0)
                    if col not in src[group]:
                        d[...] = OLD_BOUNCE_FILL[col][0]
                        continue
                    s = src[group][col]
                    step = d.chunks[0] * 16
                    for i in range(0, n, step):
                        d[i:min(n, i + step)] = s[i:min(n, i + step)]
    os.replace(tmp, path)
