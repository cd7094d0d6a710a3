"""What a run will write and hold before it starts: rows of every time-sampled table, the
file size they make, the memory of the state, and the steps a fixed time step needs.  The
writers refuse up front what could never finish or never fit (``check_run``), instead of
writing until the disk is full or looping without progress.
"""
from __future__ import annotations

import math
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path

from ..stepping import layout as L
from ..stepping.control import LAND_FIXED
from .errors import FileTooLarge, TooManySteps

__all__ = ["Estimate", "estimate_run", "estimate_values", "check_run", "check_fixed_step",
           "fixed_step_error", "step_refusal", "free_space", "too_large", "size_refusal",
           "parse_size", "format_size", "check_count_limit",
           "ESTIMATE_KEYS", "MAX_OUTPUT", "MAX_STEPS"]

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


def check_count_limit(name: str, value, *, unlimited: bool = True) -> float:
    """``value`` as a limit on a count (``max_steps``, ``max_points``): a whole number >= 1,
    or (``unlimited``) ``math.inf`` for none; ValueError naming ``name`` otherwise.  NaN
    would make every comparison false and so turn the limit off without a word, and a
    fraction would be shown rounded ("2 points, more than the limit of 2").  The command
    line passes ``unlimited=False``: a limit there is raised, never turned off.

    Parameters
    ----------
    name : str
        The limit as the message names it (``"max_steps"``, ``"--max-points"``).
    value : float, int or str
        The limit (a text is read as a number).
    unlimited : bool, optional
        Accept ``math.inf`` (no limit).

    Returns
    -------
    float
        The limit.

    Raises
    ------
    ValueError
        Not a number, NaN, below 1, a fraction, or (unless ``unlimited``) infinite.
    """
    whole = "a whole number >= 1" + (", or math.inf for no limit" if unlimited else "")
    named = f"{name} " if name.startswith("--") else f"{name} = "   # an option, a keyword
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        shown = repr(value) if len(repr(value)) <= 26 else f"{repr(value)[:13]}...'"
        raise ValueError(f"{named}{shown} is not a number ({whole})") from None
    if isinstance(value, bool) or not (number >= 1) or (
            math.isfinite(number) and number != math.floor(number)) or (
            math.isinf(number) and not unlimited):
        shown = value if isinstance(value, str) else repr(value)
        shown = shown if len(shown) <= 24 else f"{shown[:12]}...({len(shown)} characters)"
        raise ValueError(f"{named}{shown} is out of range ({whole})")
    return number


def _rows(span: float, interval: float) -> float:
    return 0.0 if not interval else math.floor(span / interval) + 1


# the configuration keys an estimate and the fixed-step checks depend on (a sweep computes
# them once per combination of these keys, not once per point)
ESTIMATE_KEYS = ("rod.N", "time.t_end", "time.dt", "output.snapshot_interval",
                 "output.diagnostics_interval", "output.times")
_INTERVALS = ("output.snapshot_interval", "output.diagnostics_interval")


def _values(config) -> dict:
    return {key: config.get(key) for key in ESTIMATE_KEYS}


def estimate_run(config) -> Estimate:
    """The output and memory of ``config`` from t = 0 to time.t_end."""
    return estimate_values(_values(config))


def estimate_values(values) -> Estimate:
    """``estimate_run`` from the values of ``ESTIMATE_KEYS`` (a mapping)."""
    n1 = values["rod.N"] + 1
    span = float(values["time.t_end"])
    times = values.get("output.times") or ()
    snaps = len(times) if times else _rows(span, values["output.snapshot_interval"])
    diags = _rows(span, values["output.diagnostics_interval"])
    file_bytes = _OVERHEAD + snaps * (2 * n1 + 2) * 8 + diags * len(L.DIAG_COLUMNS) * 8
    snap_buffer = max(1, min(snaps, max(16, 2**22 // n1)))
    memory = 8 * n1 * (3 * 3 + 8) + snap_buffer * 2 * n1 * 8 * 2 + 4096 * 64 * 8
    dt = values["time.dt"]
    steps = None if dt is None else span / float(dt)
    return Estimate(int(min(snaps, 2**62)), int(min(diags, 2**62)), file_bytes, memory, steps)


def fixed_step_error(values, max_steps: float = MAX_STEPS) -> str | None:
    """The message of ``step_refusal``, or None."""
    error = step_refusal(values, max_steps)
    return None if error is None else str(error)


def step_refusal(values, max_steps: float = MAX_STEPS) -> ValueError | None:
    """The error (TooManySteps for more than ``max_steps``) saying why a fixed time.dt (in
    ``values``, a mapping of ``ESTIMATE_KEYS``) cannot run as asked, or None: a step below
    the resolution of t (the run would never advance), more than ``max_steps`` steps, or a
    step that does not divide an output interval (the loop would shorten a step before
    every output time to land on it: not the fixed step asked for).  The last step is the
    only one that may be shorter, to end on time.t_end.  A ``max_steps`` that is no limit
    (NaN, a fraction: ``check_count_limit``) is raised, whatever the step."""
    check_count_limit("max_steps", max_steps)
    dt, t_end = values["time.dt"], float(values["time.t_end"])
    if dt is None:
        return None
    dt = float(dt)
    if t_end + dt == t_end:
        return ValueError(f"time.dt = {dt!r} is below the resolution of t near time.t_end = "
                          f"{t_end!r} (t + dt == t): the run would never advance")
    steps = t_end / dt
    if steps > max_steps:
        return TooManySteps(dt, t_end, steps, max_steps)
    times = values.get("output.times") or ()
    for i, t in enumerate(times):
        if t > 0 and not _divides(dt, t):
            return ValueError(f"output.times[{i}] = {t!r} is not a whole number of steps of "
                              f"time.dt = {dt!r} ({t / dt:.6g}): with a fixed step every "
                              f"listed time must be a multiple of time.dt, so that every "
                              f"step is time.dt; or unset time.dt for adaptive steps")
    intervals = [float(values[key]) for key in _INTERVALS if float(values[key]) > 0]
    for key in _INTERVALS:
        if times and key == "output.snapshot_interval":
            continue                     # not used: the listed times replace its grid
        interval = float(values[key])
        if interval > 0 and not _divides(dt, interval):
            return ValueError(f"time.dt = {dt!r} does not divide {key} = {interval!r} ({key} "
                              f"/ time.dt = {interval / dt:.6g}): a fixed step must divide "
                              f"every output interval, so that every step is time.dt (e.g. "
                              f"time.dt = {_divisor(dt, interval, intervals)}); or unset "
                              f"time.dt for adaptive steps")
    return None


def _divides(dt: float, interval: float) -> bool:
    """Whether ``interval`` is a whole multiple of ``dt`` up to the rounding the loop's
    landing on output times absorbs (``LAND_FIXED``) and that of the division itself."""
    ratio = interval / dt
    n = round(ratio)
    return n >= 1 and abs(ratio - n) <= LAND_FIXED + 4 * sys.float_info.epsilon * ratio


def _divisor(dt: float, interval: float, intervals) -> str:
    """A short step below ``dt`` that divides every interval (for the message)."""
    first = max(math.ceil(interval / dt), 1)
    for k in range(first, 4 * first + 16):
        candidate = float(f"{interval / k:.3g}")
        if all(_divides(candidate, i) for i in intervals):
            return repr(candidate)
    return repr(interval / first)


def check_fixed_step(config, max_steps: float = MAX_STEPS) -> None:
    """ValueError (one line) if ``config``'s fixed time.dt cannot run as asked
    (``fixed_step_error``)."""
    if config.time.dt is None:
        check_count_limit("max_steps", max_steps)
        return   # adaptive steps: nothing more to check
    error = step_refusal(_values(config), max_steps)
    if error is not None:
        raise error


def free_space(path) -> float | None:
    """Bytes free on the disk that holds ``path`` (a file to be written, or a directory
    that may not exist yet: its nearest existing ancestor); None if unknown."""
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    if p.is_file():
        p = p.parent
    try:
        return shutil.disk_usage(p).free
    except OSError:
        return None


def too_large(what: str, e: Estimate, max_output: float) -> str | None:
    """The message of ``size_refusal``, or None."""
    error = size_refusal(what, e, max_output)
    return None if error is None else str(error)


def size_refusal(what: str, e: Estimate, max_output: float) -> FileTooLarge | None:
    """The refusal (FileTooLarge) of a file of estimate ``e`` above ``max_output`` bytes, or
    None."""
    if e.file_bytes <= max_output:
        return None
    return FileTooLarge(what, e.describe(), max_output, format_size(max_output))


def check_run(config, path=None, *, max_output: float = MAX_OUTPUT,
              max_steps: float = MAX_STEPS, what: str = "the run",
              written: float = 0) -> Estimate:
    """ValueError (one line, with the estimate) unless ``config`` can finish and fit: a
    fixed time.dt that time can resolve (t + dt > t at t_end), needing at most
    ``max_steps`` steps and dividing the output intervals; a file of at most
    ``max_output`` bytes and no more than the free space of the disk of ``path``.  Every
    path that starts or continues a run checks it here (a new run, a resume or extension,
    a sweep's points, ``converge``, ``fit``); ``written``: bytes of the file already on
    disk (a continued run), which need no new space."""
    values = _values(config)
    e = estimate_values(values)
    error = step_refusal(values, max_steps) or size_refusal(what, e, max_output)
    if error is not None:
        raise error
    if path is not None:
        free = free_space(path)
        if free is not None and e.file_bytes - written > free:
            parent = Path(path).parent if str(Path(path).parent) else Path(".")
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
