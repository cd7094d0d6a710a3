"""Samples of a run dense enough to draw an impact: its snapshots, and where they are too
sparse (fewer than ``MIN_SAMPLES`` across a contact or a zoomed window) the solution
re-simulated from the snapshot before, at a finer snapshot interval.

Why re-simulate rather than interpolate or only warn: an impact at μ = 100 lasts about
12 ms, and the default ``output.snapshot_interval`` (5 ms) puts two or three snapshots in
it; a space-time map of them is three blocky columns and a movie of them skips the
impact.  Nothing between two snapshots can be recovered from them (the compression wave
crosses the rod several times in between), but the run is deterministic and a snapshot
holds the whole state (u, v): ``simulate(config, u0=u, v0=v)`` continues from it and gives
the true solution of the same model at any interval, for the few milliseconds a figure
needs.  The continuation takes its own adaptive steps, so it agrees with the run's own
steps to the integrator's tolerance, not bit for bit (tests/test_plotting_dense.py
compares it with the run's snapshots).

Where re-simulation is not possible (the run's configuration no longer runs here, e.g. a
custom law that cannot be imported, or a fixed step that does not divide the finer
interval) or is switched off (``dense=False``), the figure draws the snapshots it has and
issues one ``SparseSnapshots`` warning naming the setting that resolves it:
``output.snapshot_interval`` and the value to give it.  The command line says it as one
``warning:`` line.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..config import ModelWarning

__all__ = ["MIN_SAMPLES", "DENSE_SAMPLES", "SparseSnapshots", "Samples", "contacts",
           "resimulate", "sparse_text"]

MIN_SAMPLES = 20      # samples across a contact or a zoomed window below which it is sparse
DENSE_SAMPLES = 40    # samples across a contact that re-simulation gives
WINDOW_SAMPLES = 200  # samples across a zoomed window that re-simulation gives
MAX_SPANS = 100       # re-simulated spans of one figure at most (else: the warning)


class SparseSnapshots(UserWarning):
    """A figure drew snapshots too sparse for an impact (or a zoomed window) it shows,
    and could not re-simulate them; the message names the ``output.snapshot_interval``
    that resolves it."""


@dataclass
class Samples:
    """The times a figure draws and where each state comes from: a snapshot row of the
    run (``row[k] >= 0``) or a re-simulated state (``row[k] == -1``, ``dense_u[j]``,
    ``dense_v[j]`` with ``j = index[k]``)."""

    t: np.ndarray
    row: np.ndarray
    index: np.ndarray
    dense_u: np.ndarray
    dense_v: np.ndarray
    spans: list = field(default_factory=list)   # the re-simulated (t0, t1, interval)

    def state(self, src, quantity: str, k: int) -> np.ndarray:
        """``u`` or ``v`` at sample ``k`` (one snapshot read, or a re-simulated row)."""
        if self.row[k] >= 0:
            return src.snapshot_row(quantity, int(self.row[k]))
        return (self.dense_u if quantity == "u" else self.dense_v)[self.index[k]]

    def states(self, src, quantity: str) -> np.ndarray:
        """``u`` or ``v`` at every sample, shape ``(samples, N + 1)``."""
        out = np.empty((self.t.size, src.x.size))
        snap = self.row >= 0
        if snap.any():
            # one strided read (the rows are a strided slice less the re-simulated spans),
            # not a point selection of each row
            r = self.row[snap]
            step = max(1, int(np.gcd.reduce(np.diff(r)))) if r.size > 1 else 1
            block = src.snapshots(quantity, slice(int(r[0]), int(r[-1]) + 1, step))
            out[snap] = block[(r - r[0]) // step]
        if (~snap).any():
            out[~snap] = (self.dense_u if quantity == "u" else self.dense_v)[self.index[~snap]]
        return out


def contacts(src, lo: float, hi: float) -> list[tuple[float, float]]:
    """The impacts ``(t_impact, t_release)`` that overlap ``[lo, hi]`` (one still in
    contact at the end runs to the last snapshot).

    Bounces rather than contact episodes: at μ = 0 one impact chatters through several
    episodes of a millisecond, and it is the impact a picture must resolve."""
    b = src.table("bounces")
    t = src.snapshot_times()
    last = float(t[-1]) if t.size else hi
    out = []
    for a, r in zip(b["t_impact"], b["t_release"]):
        a, r = float(a), float(r) if math.isfinite(r) else last
        if r > a and r >= lo and a <= hi:
            out.append((a, r))
    return out


def resimulate(src, t0: float, t1: float, interval: float):
    """``(t, u, v)`` every ``interval`` over ``[t0, t1]``: the run continued from its last
    snapshot at or before ``t0`` with ``output.snapshot_interval = interval``.

    A fixed ``time.dt`` must divide the output interval: ``interval`` is then a whole
    number of steps (at least one).  Raises whatever the continuation raises (an
    exception means: no dense data here)."""
    from ..driver.simulate import simulate

    dt = src.config.time.dt
    if dt is not None:
        interval = max(1, round(interval / dt)) * dt

    times = src.snapshot_times()
    row = max(0, int(np.searchsorted(times, t0, "right")) - 1)
    ts = float(times[row])
    config = src.config.override({"time.t_end": max(t1 - ts, interval),
                                  "output.snapshot_interval": interval, "output.times": (),
                                  "output.diagnostics_interval": 0.0})
    with warnings.catch_warnings():   # the run's own warnings were said when it ran
        warnings.simplefilter("ignore", ModelWarning)
        res = simulate(config, u0=src.snapshot_row("u", row), v0=src.snapshot_row("v", row))
    t = res.t + ts
    keep = (t >= t0 - 1e-12 * max(1.0, abs(t0))) & (t <= t1 + 1e-12 * max(1.0, abs(t1)))
    return t[keep], res.u[keep], res.v[keep]


def sparse_text(what: str, count: int, span: tuple[float, float], interval: float,
                needed: float, why: str) -> str:
    """The warning for a ``what`` (``"the contact"``, ``"the window"``) of ``span`` drawn
    from ``count`` snapshots."""
    a, b = span
    return (f"{count} snapshots across {what} from t = {a:.6g} s to {b:.6g} s "
            f"(output.snapshot_interval = {interval:.3g} s), too few to draw it; a run with "
            f"output.snapshot_interval = {_round_down(needed):.3g} s or less resolves it "
            f"({why})")


def _round_down(x: float) -> float:
    """``x`` rounded down to 1, 2 or 5 times a power of ten (a value to type)."""
    p = 10.0 ** math.floor(math.log10(x))
    return max(m * p for m in (1, 2, 5) if m * p <= x * (1 + 1e-12))


def _count(times: np.ndarray, a: float, b: float) -> int:
    return int(np.searchsorted(times, b, "right") - np.searchsorted(times, a, "left"))


def _merge(spans):
    out = []
    for a, b, dt in sorted(spans):
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b), min(out[-1][2], dt))
        else:
            out.append((a, b, dt))
    return out


def sparse_spans(src, lo: float, hi: float, *, per_contact: int = MIN_SAMPLES,
                 window: bool = True, impacts=None):
    """What is sparse in ``[lo, hi]``: a list of ``(what, (a, b), count, needed, span)``,
    ``span = (s0, s1, interval)`` the part to re-simulate at ``interval``.

    A contact with fewer than ``per_contact`` snapshots is re-simulated from half its
    duration before to half after (the approach and the release), at its duration over
    ``DENSE_SAMPLES``; with ``window``, a window of fewer than ``MIN_SAMPLES`` snapshots
    is re-simulated whole, at its width over ``WINDOW_SAMPLES``.  ``impacts``: the
    contacts to look at (default: every one in the window).  Nothing beyond the run's
    last snapshot is re-simulated (a run that failed there does not go on in a figure)."""
    times = src.snapshot_times()
    interval = src.config.output.snapshot_interval
    found: list[tuple] = []
    if times.size == 0:
        return found
    lo, hi = max(lo, float(times[0])), min(hi, float(times[-1]))
    if hi <= lo:
        return found
    n_window = _count(times, lo, hi)
    if window and n_window < MIN_SAMPLES:
        w = hi - lo
        found.append(("the window", (lo, hi), n_window, w / MIN_SAMPLES,
                      (lo, hi, w / WINDOW_SAMPLES)))
    for a, b in (contacts(src, lo, hi) if impacts is None else impacts):
        d = b - a
        n = _count(times, a, b)
        if n < per_contact and interval > d / per_contact:
            s0, s1 = max(lo, a - d / 2), min(hi, b + d / 2)
            found.append(("the contact", (a, b), n, d / per_contact,
                          (s0, s1, d / DENSE_SAMPLES)))
    return found


def samples(src, rows, lo: float, hi: float, *, dense: bool, what: str,
            per_contact: int = MIN_SAMPLES, window: bool = True, impacts=None,
            max_dense: int = 20_000) -> Samples:
    """The snapshot ``rows`` (indices) of ``[lo, hi]``, with every sparse contact (and a
    sparse window) replaced by re-simulated states when ``dense`` and possible; else one
    ``SparseSnapshots`` warning for ``what`` (the figure).  ``impacts``: the contacts to
    resolve (default: every one in the window)."""
    times = src.snapshot_times()
    rows = np.asarray(rows, dtype=np.int64)
    found = sparse_spans(src, lo, hi, per_contact=per_contact, window=window,
                         impacts=impacts)
    spans = _merge([f[4] for f in found])
    total = sum((s1 - s0) / dt for s0, s1, dt in spans)
    if total > max_dense:        # coarser everywhere, still at most max_dense states
        spans = [(s0, s1, dt * total / max_dense) for s0, s1, dt in spans]
    why = None
    if not found:
        pass
    elif not dense:
        why = "re-simulation switched off: dense=False"
    elif len(spans) > MAX_SPANS:
        why = f"{len(spans)} spans to re-simulate, more than {MAX_SPANS}: draw a shorter t_range"
    else:
        pieces = []
        try:
            for s0, s1, dt in spans:
                pieces.append(resimulate(src, s0, s1, dt))
        except Exception as exc:   # noqa: BLE001 - any failure: draw the snapshots, warn
            why = f"re-simulating from a snapshot failed: {type(exc).__name__}: {exc}"
        else:
            return _with_dense(times, rows, spans, pieces)
    if why is not None:
        # the worst case names the interval that resolves every case
        worst = min(found, key=lambda f: f[3])
        warnings.warn(f"{what}: " + sparse_text(worst[0], worst[2], worst[1],
                                                src.config.output.snapshot_interval,
                                                worst[3], why), SparseSnapshots, stacklevel=4)
    n1 = src.x.size
    return Samples(times[rows], rows, np.zeros(rows.size, np.int64), np.empty((0, n1)),
                   np.empty((0, n1)))


def _with_dense(times, rows, spans, pieces) -> Samples:
    """The snapshot rows outside the spans and the re-simulated states inside, in time
    order."""
    t_rows = times[rows]
    inside = np.zeros(rows.size, bool)
    for s0, s1, _ in spans:
        inside |= (t_rows >= s0) & (t_rows <= s1)
    dt = np.concatenate([p[0] for p in pieces])
    du = np.concatenate([p[1] for p in pieces])
    dv = np.concatenate([p[2] for p in pieces])
    t = np.concatenate([t_rows[~inside], dt])
    row = np.concatenate([rows[~inside], np.full(dt.size, -1, np.int64)])
    index = np.concatenate([np.zeros((~inside).sum(), np.int64), np.arange(dt.size)])
    order = np.argsort(t, kind="stable")
    return Samples(t[order], row[order], index[order], du, dv, list(spans))
