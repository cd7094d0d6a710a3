"""What a run will write and hold before it starts: rows of every time-sampled table, the
file size they make, the memory of the state, and the steps a fixed time step needs.  The
writers refuse up front what could never finish or never fit (``check_run``), instead of
writing until the disk is full or looping without progress.
"""
from __future__ import annotations

import math
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

from .run_layout import TABLES

__all__ = ["Estimate", "estimate_run", "check_run", "parse_size", "format_size",
           "MAX_OUTPUT", "MAX_STEPS"]

MAX_OUTPUT = 10 * 2**30     # bytes a run file may reach unless the caller raises the limit
MAX_STEPS = 10**10          # fixed steps a run may need unless the caller raises the limit
_OVERHEAD = 3 * 2**19       # layout, checkpoints, the first chunk of every table (~1.6 MB)


@dataclass
class Estimate:
    snapshots: int          # rows of /snapshots
    diagnostics: int        # rows of /diagnostics
    file_bytes: float       # the file, without the event tables (contacts, bounces)
    memory_bytes: float     # the state, work arrays and output buffers
    steps: float | None     # steps of a fixed time.dt (None: adaptive)

    def describe(self) -> str:
        steps = "" if self.steps is None else f", {self.steps:.3g} fixed steps"
        return (f"{self.snapshots:.6g} snapshot rows, {self.diagnostics:.6g} diagnostics rows, "
                f"about {format_size(self.file_bytes)} of file, "
                f"{format_size(self.memory_bytes)} of memory{steps}")


def _rows(span: float, interval: float) -> float:
    return 0.0 if not interval else math.floor(span / interval) + 1


def estimate_run(config) -> Estimate:
    """The output and memory of ``config`` from t = 0 to time.t_end."""
    n1 = config.rod.N + 1
    span = float(config.time.t_end)
    snaps = _rows(span, config.output.snapshot_interval)
    diags = _rows(span, config.output.diagnostics_interval)
    file_bytes = _OVERHEAD + snaps * (2 * n1 + 2) * 8 + diags * len(TABLES["diagnostics"]) * 8
    snap_buffer = max(1, min(snaps, max(16, 2**22 // n1)))
    memory = 8 * n1 * (3 * 3 + 8) + snap_buffer * 2 * n1 * 8 * 2 + 4096 * 64 * 8
    dt = config.time.dt
    steps = None if dt is None else span / float(dt)
    return Estimate(int(min(snaps, 2**62)), int(min(diags, 2**62)), file_bytes, memory, steps)


def check_run(config, path=None, *, max_output: float = MAX_OUTPUT,
              max_steps: float = MAX_STEPS, what: str = "the run") -> Estimate:
    """ValueError (one line, with the estimate) unless ``config`` can finish and fit: a
    fixed time.dt that time can resolve (t + dt > t at t_end) and needing at most
    ``max_steps`` steps; a file of at most ``max_output`` bytes and no more than the free
    space of the disk of ``path``."""
    e = estimate_run(config)
    t_end, dt = float(config.time.t_end), config.time.dt
    if dt is not None:
        if t_end + float(dt) == t_end:
            raise ValueError(f"time.dt = {dt!r} is below the resolution of t near time.t_end "
                             f"= {t_end!r} (t + dt == t): the run would never advance")
        if e.steps > max_steps:
            raise ValueError(f"time.dt = {dt!r} needs {e.steps:.3g} steps to reach time.t_end "
                             f"= {t_end!r}, more than the limit of {max_steps:.3g} (raise it "
                             f"with --max-steps / max_steps=)")
    if e.file_bytes > max_output:
        raise ValueError(f"{what} would write {e.describe()}: more than the limit of "
                         f"{format_size(max_output)} (raise it with --max-output / "
                         f"max_output=, or write less: output.snapshot_interval, "
                         f"output.diagnostics_interval, time.t_end)")
    if path is not None:
        parent = Path(path).parent if str(Path(path).parent) else Path(".")
        try:
            free = shutil.disk_usage(parent).free
        except OSError:
            free = None
        if free is not None and e.file_bytes > free:
            raise ValueError(f"{what} would write {e.describe()}, more than the "
                             f"{format_size(free)} free on the disk of {str(parent)!r}")
    return e


_UNITS = {"": 1, "B": 1, "K": 2**10, "KB": 10**3, "KIB": 2**10, "M": 2**20, "MB": 10**6,
          "MIB": 2**20, "G": 2**30, "GB": 10**9, "GIB": 2**30, "T": 2**40, "TB": 10**12,
          "TIB": 2**40}


def parse_size(text) -> float:
    """Bytes of a size such as ``500M``, ``10GiB``, ``2e9`` or ``inf`` (no limit)."""
    s = str(text).strip().upper().replace(" ", "")
    if s in ("INF", "NONE", "UNLIMITED"):
        return math.inf
    num = s.rstrip("KMGTIB")
    unit = s[len(num):]
    try:
        value = float(num) * _UNITS[unit]
    except (ValueError, KeyError):
        raise ValueError(f"size {text!r} is not understood (e.g. 500M, 10GiB, 2e9, inf)") from None
    if not value > 0:
        raise ValueError(f"size {text!r} is out of range (> 0)")
    return value


def format_size(n: float) -> str:
    if not math.isfinite(n):
        return "unlimited" if n > 0 else str(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{n:.0f} B"
        n /= 1024
    return f"{n:.3g} EiB"
