"""One sweep point, run where a worker is: the task, its result, and the summary row.

A point runs exactly the configuration ``rodjit run`` would run for it (snapshots are
taken, so the steps land on the same output times, and discarded); only its summary and
bounce table travel back.  With ``save_path`` the full run file is written instead, and the
row comes from the writer's summary of it: the row is the same either way.
"""
from __future__ import annotations

import importlib
import math
import os
import pickle
import socket
import sys
import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..config import ModelWarning
from ..driver.run import Run, SimulationError
from ..model.laws import get_law
from ..output.lock import lock_path
from ..records.bounces import bounce_table, empty_bounces
from ..records.columns import BOUNCE_COLUMNS
from ..records.extremes import Extremes
from ..records.impact import IMPACT_COLUMNS, ImpactStream
from ..records.sink import Sink
from ..stepping import layout as L
from ..stepping import registry
from ..stepping.observers import columns_of, get_observer
from .batch import BatchResult

__all__ = ["PointTask", "PointResult", "SUMMARY_COLUMNS", "run_point", "run_points", "died",
           "empty_columns", "empty_bounces", "user_modules", "BOUNCE_COLUMNS",
           "default_jobs", "worker_info", "reissue_warnings", "bounce_values", "pass_on",
           "summary_columns"]

# the summary columns a point fills, after the swept keys: name -> (dtype, description)
SUMMARY_COLUMNS: dict[str, tuple[str, str]] = {
    "status": ("str", "completed | failed (pending: not run yet)"),
    "message": ("str", "why the point failed ('' if it completed)"),
    "n_bounces": ("int", "bounces recorded, an unfinished last one included"),
    "n_complete_bounces": ("int", "bounces whose last contact episode ended"),
    **IMPACT_COLUMNS,
    "restitution_mean": ("float", "mean restitution over the bounces not marked ambiguous "
                                  "(NaN if none)"),
    "restitution_energy_mean": ("float", "mean restitution_energy over the bounces not "
                                         "marked ambiguous (NaN if none)"),
    "min_u0": ("float", "lowest bottom height u_0 (deepest penetration if < 0)"),
    "max_floor_force": ("float", "largest floor force sigma_b(u_0)"),
    "min_strain": ("float", "smallest segment strain"),
    "energy_error": ("float", "max |E + dissipated - E0| / max(|E0|, kinetic): drift at "
                              "mu = 0, balance error at mu > 0 (NaN without diagnostics)"),
    "steps": ("int", "accepted steps"),
    "rejected_steps": ("int", "rejected trial steps"),
    "wall_time": ("float", "seconds the point took in its worker, set-up included"),
    "compile_time": ("float", "of which compiling or loading kernels from the disk cache"),
    "run_time": ("float", "of which stepping in compiled code"),
    "t_final": ("float", "simulated time reached"),
    "run_file": ("str", "the point's run file if run files are saved, '' if not"),
}
_FILL = {"str": "", "int": 0, "float": math.nan}
_NP_DTYPES = {"str": object, "int": np.int64, "float": np.float64}


@dataclass(frozen=True)
class PointTask:
    """What a worker needs for one point (small and picklable)."""

    index: int
    config: Any                 # rodjit.Config of the point
    save_path: str | None       # full run file to write, or None
    laws: tuple[str, ...]       # modules to import first (user_modules: they register the
                                # laws and the integrator that are not rodjit's own)


@dataclass
class PointResult:
    """A point's summary row (``values``), bounce table and where it ran."""

    index: int
    values: dict
    bounces: dict = field(default_factory=dict)
    worker: dict = field(default_factory=dict)
    disk: str = ""      # the disk refused a write of the point's run file: what it said
    warnings: tuple = ()    # the ModelWarning texts the run issued, said by the parent

    @property
    def status(self) -> str:
        return self.values["status"]


def summary_columns(config) -> dict[str, tuple[str, str]]:
    """The summary columns of a sweep of ``config``: ``SUMMARY_COLUMNS``, then its
    observer's (``output.observer``), floats; a ValueError (one line) for an observer's
    column named as a built-in one."""
    extra = columns_of(config)
    if not extra:
        return SUMMARY_COLUMNS
    clash = [c for c in extra if c in SUMMARY_COLUMNS]
    if clash:
        raise ValueError(f"output.observer = {config.output.observer!r} names a column "
                         f"{clash[0]!r}, which is a built-in summary column; rename it")
    return {**SUMMARY_COLUMNS, **{c: ("float", text) for c, text in extra.items()}}


def empty_values(status: str = "pending", message: str = "",
                 columns: dict = SUMMARY_COLUMNS) -> dict:
    """A summary row of ``columns`` (``summary_columns``) with nothing measured (NaN, 0,
    '')."""
    values = {name: _FILL[kind] for name, (kind, _) in columns.items()}
    values.update(status=status, message=message)
    return values


def empty_columns(n: int, columns: dict = SUMMARY_COLUMNS) -> dict[str, np.ndarray]:
    """The summary ``columns`` (``summary_columns``) of ``n`` points that have not run
    (status "pending")."""
    row = empty_values(columns=columns)
    return {name: np.full(n, row[name], dtype=_NP_DTYPES[kind])
            for name, (kind, _) in columns.items()}


def died(index: int, message: str) -> PointResult:
    """The result of a point whose worker process died while running it."""
    return PointResult(index, empty_values("failed", message), empty_bounces())


def user_modules(config) -> tuple[str, ...]:
    """Modules defining the point's stress laws, its integrator and its observer, unless
    rodjit's own: a worker in a fresh process imports them to find them by name
    (the module of ``from_config`` is the one that registers a law, the kernels may come
    from others; an integrator's is its ``Scheme.module``, which registers it on import)."""
    mods = []

    def add(mod: str) -> None:
        if mod and mod != "__main__" and not mod.startswith("rodjit.") and mod not in mods:
            mods.append(mod)

    for kind, name in (("rod", config.rod.law), ("floor", config.floor.law)):
        law = get_law(kind, name)
        for part in (law.from_config, law.value, law.deriv, law.primitive, law.lower):
            add(getattr(getattr(part, "py_func", part), "__module__", None) or "")
    if config.time.integrator in registry.NAMES:
        add(registry.get(config.time.integrator).module)
    ob = get_observer(config.output.observer)
    for piece in (ob.from_config, ob.start, ob.step, ob.stop, ob.values):
        add(getattr(getattr(piece, "py_func", piece), "__module__", None) or "")
    return tuple(mods)


class _PointSink(Sink):
    """Keeps what a summary row needs: running extremes, the first-impact state
    (``ImpactStream``) and the bounce rows."""

    def __init__(self, config):
        self.extremes = Extremes()
        self.impact = ImpactStream(config)
        self.rows: list[np.ndarray] = []

    def diagnostics(self, rows):
        self.extremes.update_rows(rows)

    def bounces(self, rows):
        self.rows.append(rows.copy())

    def block(self, diagnostics, episodes, bounces, in_contact, contact_start):
        self.impact.block(diagnostics, episodes, bounces, in_contact, contact_start)


def bounce_values(values: dict, bounces: dict) -> dict:
    """The summary columns of a bounce table: counts, and means over the rows not marked
    ambiguous (an open or unfinished bounce is always ambiguous); and, where the first
    impact could not be read from diagnostics (``values["impact_status"]`` undefined), its
    restitution and contact time from the table's first row, the same bounce (its status
    and apex values stay undefined)."""
    done = ~bounces["open"]
    sure = ~np.asarray(bounces["ambiguous"], bool)
    e = bounces["restitution"][sure]
    e_energy = bounces["restitution_energy"][sure]
    out = {
        "n_bounces": int(bounces["t_impact"].size),
        "n_complete_bounces": int(done.sum()),
        "restitution_mean": float(np.mean(e)) if e.size else math.nan,
        "restitution_energy_mean": float(np.mean(e_energy)) if e_energy.size else math.nan,
    }
    if values["impact_status"] == "undefined" and bounces["t_impact"].size \
            and not bounces["open"][0]:
        out["restitution_first"] = float(bounces["restitution"][0])
        out["contact_time_first"] = float(bounces["t_release"][0] - bounces["t_impact"][0])
    return out


def _run_in_memory(config) -> tuple[dict, dict]:
    run = Run(config)
    sink = _PointSink(config)
    status, message = "completed", ""
    try:
        run.start(None)   # the outputs at t0 wait in the buffers for the first drain
        while run.advance(sink) != L.DONE:
            pass
    except SimulationError as exc:
        status, message = "failed", str(exc)
    pending = run.pending_bounce()
    bounces = bounce_table(sink.rows, pending)
    ext = sink.extremes.with_bounces(bounces)
    values = {"status": status, "message": message, "min_u0": _finite(ext.u0_min),
              "max_floor_force": _finite(ext.force_max), "min_strain": _finite(ext.strain_min),
              "energy_error": ext.energy_error(run.energy0), "steps": run.steps,
              "rejected_steps": run.rejected, "compile_time": run.compile_time,
              "run_time": run.run_time, "t_final": run.t, "run_file": "", **run.observed}
    values.update(sink.impact.values(run.t, run.u, pending))
    return values, bounces


def _finite(x: float) -> float:
    return x if math.isfinite(x) else math.nan


def _run_to_file(config, path: str) -> tuple[dict, dict]:
    # the run file's writer and h5py load only where a point writes a run file: a worker
    # of the ensemble engine never does, and starts faster without them
    from ..driver.files import run_to_file
    from ..output.h5files import truncation

    if os.path.exists(path) and truncation(path):
        os.unlink(path)     # this point's file, cut short by a full disk: nothing to keep
    try:
        s = run_to_file(config, path, overwrite=True, handle_signals=False,
                        command=f"rodjit sweep point -> {path}")
        status, message = "completed", ""
    except SimulationError as exc:
        s = exc.summary
        status, message = "failed", str(exc)
    values = {"status": status, "message": message, "min_u0": _finite(s.min_u0),
              "max_floor_force": s.max_floor_force, "min_strain": s.min_strain,
              "energy_error": s.energy_error,
              "steps": s.steps, "rejected_steps": s.rejected_steps,
              "compile_time": s.compile_time, "run_time": s.run_time, "t_final": s.t,
              "run_file": os.path.basename(path), **s.impact, **s.observed}
    return values, {name: np.asarray(s.bounces[name]) for name in BOUNCE_COLUMNS}


def run_point(task: PointTask) -> PointResult:
    """Run one point; every failure of the point itself becomes ``status = failed``."""
    t0 = time.perf_counter()
    values = empty_values(columns=summary_columns(task.config))
    bounces = empty_bounces()
    disk = ""
    said: tuple = ()
    try:
        for mod in task.laws:
            importlib.import_module(mod)
        caught: list = []
        try:
            # (process-wide, like every warnings filter: a Dask worker running tasks in
            # several threads may misplace a warning between its points, never a result)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", ModelWarning)
                if task.save_path is None:
                    got, bounces = _run_in_memory(task.config)
                else:
                    got, bounces = _run_to_file(task.config, task.save_path)
        finally:
            said = pass_on(caught)
        values.update(got)
        values.update(bounce_values(values, bounces))
    except Exception as exc:   # a bug or a resource error: the sweep goes on without it
        save_path = task.save_path
        disk = ""
        if save_path is not None:
            from ..output.h5files import disk_cause    # loaded with its run file's writer

            disk = disk_cause(exc) or ""
        if disk and save_path is not None:   # the run file: removed (the point runs again
            _remove_run_file(save_path)      # on --resume)
            values.update(status="failed", message=f"writing the run file failed: {disk}",
                          run_file=os.path.basename(save_path))
        else:
            values.update(status="failed", message=f"{type(exc).__name__}: {exc}")
    values["wall_time"] = time.perf_counter() - t0
    return PointResult(task.index, values, bounces, worker_info(), disk, said)


def pass_on(caught) -> tuple:
    """The texts of the ModelWarnings among ``caught`` (the parent says them: a worker's
    own stderr would repeat them once per worker, with its file and line); other warnings
    are issued again here as they came."""
    texts = []
    for w in caught:
        if issubclass(w.category, ModelWarning):
            texts.append(str(w.message))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return tuple(dict.fromkeys(texts))


def reissue_warnings(result: PointResult | BatchResult, seen: set[str]) -> None:
    """Issue in this process, as ModelWarning, each warning text of ``result`` not in
    ``seen`` (which gets it): every distinct warning of a sweep once."""
    for text in getattr(result, "warnings", ()):
        if text not in seen:
            seen.add(text)
            warnings.warn(text, ModelWarning, stacklevel=3)


def _remove_run_file(path: str) -> None:
    """Remove a run file the disk refused, and the lock file noting why."""
    for p in (path, lock_path(path)):
        try:
            os.unlink(p)
        except OSError:
            pass


def run_points(points: tuple[PointTask, ...]) -> bytes:
    """Run several points in turn (one Dask task); their PointResults pickled into one
    blob, which Dask moves as a single frame (a list of dicts of arrays would cost it a
    size estimate and a frame per array)."""
    return pickle.dumps([run_point(task) for task in points], protocol=pickle.HIGHEST_PROTOCOL)


def default_jobs() -> int:
    """The cores this process may use (also Numba's default thread count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:   # not Linux
        return os.cpu_count() or 1


def worker_info() -> dict:
    """Who this worker is: its process, host and the threads Numba runs there (read from
    the environment where Numba is not loaded, as it would read it: a worker on the
    ahead-of-time kernels never imports Numba, whose import alone takes a tenth of a
    second)."""
    numba = sys.modules.get("numba")
    if numba is not None:
        # numba.config sets its options at import: not in its (absent) stubs' view
        threads = int(getattr(numba.config, "NUMBA_NUM_THREADS"))
    else:
        try:
            threads = int(os.environ.get("NUMBA_NUM_THREADS", ""))
        except ValueError:
            threads = default_jobs()
    return {"pid": os.getpid(), "host": socket.gethostname(), "numba_threads": threads}
