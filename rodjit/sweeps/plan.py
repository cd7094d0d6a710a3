"""What a sweep will run and write, checked before anything starts: the grid's size, every
point's configuration and fixed step, the sweep file and (``save_runs``) the run files
against the size limit and the free space of their disks.

Everything here takes time that grows with the grid's values, not with its points: the
checks and estimates that depend on a few keys run once per combination of those keys
(``Grid.combinations``), so a grid of a million points is checked in seconds.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

from ..config import Config
from ..output.errors import TooManySteps
from ..output.estimate import (ESTIMATE_KEYS, MAX_OUTPUT, MAX_STEPS, Estimate, estimate_values,
                               format_size, free_space, size_refusal, step_refusal)
from ..output.h5files import check_output
from .errors import RunsDirUnusable, SweepFileTooLarge
from .grid import MAX_POINTS, Grid
from .point import summary_columns

__all__ = ["SweepPlan", "plan_sweep", "check_runs_dir", "check_memory", "memory_bytes",
           "SWEEP_OVERHEAD", "POINT_BYTES"]

# a sweep file's layout and attributes (its fixed set of datasets), and what each point
# adds to it besides its bounce rows (a summary row: ~640 bytes measured on files of 1 to
# 512 points, rounded up)
SWEEP_OVERHEAD = 52 * 2**10
POINT_BYTES = 2**10
# what a sweep holds in memory per point: its summary table (and the points' tasks) in the
# sweep's process, 3.2 kB kept in memory (``output=None``) and 0.73 kB with a sweep file,
# measured as the growth of the peak resident memory from 2,000 to 100,000 points of a
# tiny rod, inline (rounded up)
MEMORY_POINT_BYTES = 4 * 2**10
MEMORY_POINT_BYTES_FILE = 2**10


@dataclass
class SweepPlan:
    """What ``sweep`` would run and write, checked but not done (``plan_sweep``).

    Parameters
    ----------
    config : Config
        The base configuration.
    grid : Grid
        The checked grid.
    output : pathlib.Path or None
        The sweep file, None for a sweep kept in memory.
    replaces : bool
        The sweep file exists and would be replaced.
    sweep_bytes : float
        The estimated sweep file, without bounce rows.
    runs_dir : pathlib.Path or None
        The ``save_runs`` directory.
    runs_bytes : float
        The run files together (0 without ``save_runs``).
    worst_index : int
        The point whose run file is the largest.
    worst : Estimate
        That point's estimate (rows, file and memory bytes, fixed steps).
    max_output : float
        The size limit the files were checked against.
    memory : float
        The estimated memory of the sweep's process (``memory_bytes``).
    """

    config: Config
    grid: Grid
    output: Path | None
    replaces: bool
    sweep_bytes: float
    runs_dir: Path | None
    runs_bytes: float
    worst_index: int
    worst: Estimate
    max_output: float
    memory: float = 0.0

    def report(self) -> str:
        """The lines ``rodjit sweep --dry-run`` prints."""
        g = self.grid
        axes = " x ".join(f"{k} ({len(v)} values)" for k, v in zip(g.keys, g.values))
        lines = ["dry run: checked, nothing written"]
        if self.output is not None:
            what = "replaces the existing sweep file" if self.replaces else "a new file"
            lines.append(f"output       {self.output.absolute()} ({what})")
        lines.append(f"points       {len(g):,}: {axes}")
        if self.output is not None:
            free = free_space(self.output)
            lines.append(f"sweep file   about {format_size(self.sweep_bytes)} before bounce "
                         f"rows (limit {format_size(self.max_output)}"
                         + (f", {format_size(free)} free)" if free is not None else ")"))
        if self.runs_dir is not None:
            free = free_space(self.runs_dir)
            lines.append(f"run files    {len(g):,} in {self.runs_dir}, about "
                         f"{format_size(self.runs_bytes)} in total (limit "
                         f"{format_size(self.max_output)} per file"
                         + (f", {format_size(free)} free)" if free is not None else ")"))
        lines.append(f"worst point  {self.worst_index} ({g.describe(self.worst_index)}): "
                     f"{self.worst.describe()}")
        total = physical_memory()
        lines.append(f"memory       about {format_size(self.memory)} in the sweep's process"
                     + (f" ({format_size(total)} in this machine)" if total else ""))
        return "\n".join(lines)


def plan_sweep(config: Config | None = None, grid: Mapping[str, Any] | Grid | None = None, *,
               output: str | os.PathLike[str] | None = None,
               save_runs: str | os.PathLike[str] | None = None, overwrite: bool = False,
               max_output: float = MAX_OUTPUT, max_steps: float = MAX_STEPS,
               max_points: float = MAX_POINTS) -> SweepPlan:
    """Check everything ``sweep`` checks before it starts workers or writes, and say what
    it would write, without writing anything (no file, no lock, no directory).

    Parameters
    ----------
    config : Config or None
        The base configuration; ``None`` is ``Config()``.
    grid : mapping or Grid
        As in ``sweep``.
    output : str or os.PathLike, optional
        The sweep file: checked as ``sweep`` checks it (directory, an existing file only
        with ``overwrite`` and only a rodjit sweep file).
    save_runs : str or os.PathLike, optional
        The directory for one run file per point.
    overwrite : bool
        As in ``sweep``.
    max_output : float, optional
        The largest sweep file and the largest run file allowed, in bytes.
    max_steps : float, optional
        The most fixed steps a point may need.
    max_points : float, optional
        The most points the grid may have (counted before the grid is made).

    Returns
    -------
    SweepPlan
        The grid, the estimated sweep file and run files, the point with the largest run
        file; ``.report()`` is what ``rodjit sweep --dry-run`` prints.

    Raises
    ------
    ValueError
        What ``sweep`` would refuse, with the same message (a bad point is named).
    """
    if config is not None and not isinstance(config, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(config).__name__}")
    if grid is None:
        raise ValueError("a sweep needs a grid, e.g. {'rod.mu': [0, 1, 10]}")
    # "auto" chooses once for the study: every point runs the base's integrator
    base = (config if config is not None else Config()).resolve()
    grid = Grid.from_spec(grid, max_points=max_points)
    grid.validate(base)
    summary_columns(base)          # its observer's columns beside the built-in ones
    worst_index, worst, runs_bytes = _points(base, grid, max_steps)
    runs_dir = check_runs_dir(save_runs, grid, range(len(grid)), overwrite, False, output)
    replaces = False
    sweep_bytes = SWEEP_OVERHEAD + len(grid) * (POINT_BYTES + 8 * len(grid.keys))
    if output is not None:
        output = check_output(output, overwrite, "sweep")
        replaces = output.exists()
        if sweep_bytes > max_output:
            raise SweepFileTooLarge(len(grid), sweep_bytes, max_output)
    if runs_dir is not None:
        error = size_refusal(f"the run file of grid point {worst_index} "
                             f"({grid.describe(worst_index)})", worst, max_output)
        if error is not None:
            raise error
    _check_free(output, sweep_bytes if output is not None else 0.0, runs_dir,
                runs_bytes if runs_dir is not None else 0.0)
    memory = check_memory(len(grid), output is not None)
    return SweepPlan(base, grid, output, replaces, sweep_bytes, runs_dir,
                     runs_bytes if runs_dir is not None else 0.0, worst_index, worst,
                     max_output, memory)


def memory_bytes(points: int, to_file: bool) -> float:
    """The memory a sweep of ``points`` holds in its process (``MEMORY_POINT_BYTES``)."""
    return float(points) * (MEMORY_POINT_BYTES_FILE if to_file else MEMORY_POINT_BYTES)


def physical_memory() -> float | None:
    """Bytes of memory in this machine, or None where the system does not say."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return None


def check_memory(points: int, to_file: bool) -> float:
    """``memory_bytes``, refused (ValueError, one line) where it exceeds the machine's
    memory: the sweep would be killed at its end, its work lost with it."""
    need = memory_bytes(points, to_file)
    total = physical_memory()
    if total is not None and need > total:
        where = ("with a sweep file" if to_file else
                 "kept in memory; a sweep file (output=, -o) needs a quarter of it")
        raise ValueError(f"a sweep of {points:,} points would hold about "
                         f"{format_size(need)} in memory ({where}), more than the "
                         f"{format_size(total)} of this machine: sweep fewer points at once")
    return need


def _points(base: Config, grid: Grid, max_steps: float) -> tuple[int, Estimate, float]:
    """Check every point's fixed step; (the point with the largest run file, its
    estimate, the run files' total)."""
    flat = base.flat()
    share = grid.multiplicity(ESTIMATE_KEYS)
    worst_index, worst, total = 0, None, 0.0
    for index, over in grid.combinations(ESTIMATE_KEYS):
        values = {k: over.get(k, flat[k]) for k in ESTIMATE_KEYS}
        error = step_refusal(values, max_steps)
        if isinstance(error, TooManySteps):
            raise error.at(f"grid point {index} ({grid.describe(index)})")
        if error is not None:
            raise ValueError(f"grid point {index} ({grid.describe(index)}): {error}")
        e = estimate_values(values)
        total += e.file_bytes * share
        if worst is None or e.file_bytes > worst.file_bytes:
            worst_index, worst = index, e
    assert worst is not None, "Grid.combinations yields at least one combination"
    return worst_index, worst, total


def _device(path: Path):
    p = path.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        return os.stat(p).st_dev
    except OSError:
        return None


def _check_free(output, sweep_bytes: float, runs_dir, runs_bytes: float) -> None:
    """ValueError if the sweep file and the run files would not fit their disks' free
    space (together, when they share a disk)."""
    same = (output is not None and runs_dir is not None
            and _device(Path(output)) == _device(runs_dir))
    needs = []
    if output is not None:
        needs.append((Path(output), sweep_bytes + (runs_bytes if same else 0.0),
                      "the sweep file" + (" and the run files" if same else "")))
    if runs_dir is not None and not same:
        needs.append((runs_dir, runs_bytes, "the run files"))
    for path, need, what in needs:
        free = free_space(path)
        if free is not None and need > free and math.isfinite(need):
            where = path.parent if path != runs_dir else path
            raise ValueError(f"{what} would take about {format_size(need)}, more than the "
                             f"{format_size(free)} free on the disk of {str(where)!r}")


def check_runs_dir(save_runs, grid: Grid, todo, overwrite: bool, resume: bool,
                   output=None) -> Path | None:
    """Check the directory of the points' run files (``save_runs``; created later, once
    everything else is valid); RunsDirUnusable if it cannot take them, or if the sweep
    file ``output`` would be inside it."""
    if save_runs is None:
        return None
    d = Path(save_runs).resolve()
    if d.exists() and not d.is_dir():
        raise RunsDirUnusable(save_runs, "not_a_directory")
    if output is not None and d in Path(output).resolve().parents:
        raise RunsDirUnusable(save_runs, "holds_output", str(output))
    existing = d.parent
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir() or not os.access(existing, os.W_OK | os.X_OK):
        raise RunsDirUnusable(save_runs, "not_creatable")
    if d.is_dir() and not (overwrite or resume) and next(d.iterdir(), None) is not None:
        clash = next((grid.run_name(i) for i in todo if (d / grid.run_name(i)).exists()), None)
        if clash:
            raise RunsDirUnusable(save_runs, "holds", clash)
    return d
