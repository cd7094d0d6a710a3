"""The arrays of one run of the compiled loop, as one named structure: ``RunArrays``.

The loop's kernels (``loop.start``, ``loop.advance``), the per-point driver
(``trajectory.run_one``) and the batch kernel (``ensemble.run_batch``) take them as one
argument and read its fields by name (``arrays.state``).  Numba types a NamedTuple of
arrays as a tuple of the arrays themselves: the fields are not copied, a field read is a
compile-time index, and a call unboxes the same arrays it would as separate arguments.

Its fields are listed here once, with their dtypes and shapes (``SPEC``); everything else
is made from that list: ``allocate`` (a ``driver.run.Run``'s arrays, a CPU batch's
scratch), the exported functions' array arguments of the ahead-of-time extension
(``aot_type``, ``stepping.aot``: its ABI stays arrays, and the wrappers build the
NamedTuple inside), and the GPU kernel's arrays (``gpu.kernel``: the fields sized by the
rod in ``cuda.local.array``, the output buffers as the point's rows of device arrays).

A dimension of a shape is a number or the name of a size (``sizes``): ``"n1"`` nodes
N + 1, ``"work"`` the scheme's work rows (``schemes.work_rows``), the buffers' row
counts ``"snapshots"``, ``"diagnostics"`` and ``"events"``, ``"times"`` the listed
snapshot times, and ``"observed"`` the observer's state and values
(``observers.state_size``).  The fields sized by the buffers' counts are the output buffers
(``BUFFERS``); ``times`` is the one input (``INPUTS``).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import layout as L
from .schemes import SCHEME_STATS, work_rows

__all__ = ["RunArrays", "SPEC", "BUFFERS", "INPUTS", "sizes", "shape", "allocate", "aot_type"]


class RunArrays(NamedTuple):
    """The arrays of one run of the compiled loop (module docstring; ``SPEC``)."""

    state: np.ndarray       # u, v, a rows of the current state
    trial: np.ndarray       # the trial step's u, v, a rows
    work: np.ndarray        # the scheme's scratch rows
    interp: np.ndarray      # a dense output's interpolated (u, v)
    sstats: np.ndarray      # the scheme's counters (``registry.SCHEME_STATS``)
    clock: np.ndarray       # ``layout``: clock, count, ev, fail rows
    count: np.ndarray
    ev: np.ndarray
    snap_t: np.ndarray      # the output buffers: snapshots, diagnostics, events
    snap_step: np.ndarray
    snap_u: np.ndarray
    snap_v: np.ndarray
    diag: np.ndarray
    episodes: np.ndarray
    bounces: np.ndarray
    fail: np.ndarray
    observed: np.ndarray    # the observer's state, then its values (``observers``)
    times: np.ndarray       # the listed snapshot times (``output.times``; read only)


_F8, _I8 = np.dtype(np.float64), np.dtype(np.int64)
_STATS = max(1, len(SCHEME_STATS))

# each field's dtype and shape (a dimension: a number or a name of ``sizes``)
SPEC: dict[str, tuple[np.dtype, tuple]] = {
    "state": (_F8, (3, "n1")),
    "trial": (_F8, (3, "n1")),
    "work": (_F8, ("work", "n1")),
    "interp": (_F8, (2, "n1")),
    "sstats": (_I8, (_STATS,)),
    "clock": (_F8, (L.CLOCK_SIZE,)),
    "count": (_I8, (L.COUNT_SIZE,)),
    "ev": (_F8, (L.EV_SIZE,)),
    "snap_t": (_F8, ("snapshots",)),
    "snap_step": (_I8, ("snapshots",)),
    "snap_u": (_F8, ("snapshots", "n1")),
    "snap_v": (_F8, ("snapshots", "n1")),
    "diag": (_F8, ("diagnostics", len(L.DIAG_COLUMNS))),
    "episodes": (_F8, ("events", len(L.EPISODE_COLUMNS))),
    "bounces": (_F8, ("events", len(L.BOUNCE_ROW_COLUMNS))),
    "fail": (_F8, (L.FAIL_SIZE,)),
    "observed": (_F8, ("observed",)),
    "times": (_F8, ("times",)),
}
assert tuple(SPEC) == RunArrays._fields, "SPEC must list RunArrays' fields in order"

_BUFFER_SIZES = ("snapshots", "diagnostics", "events")
# the output buffers: the fields sized by the buffers' row counts
BUFFERS = tuple(name for name, (_, dims) in SPEC.items() if dims[0] in _BUFFER_SIZES)
# the run's inputs that the loop only reads: the GPU passes them as device arrays that
# every thread of a launch shares, rather than local arrays
INPUTS = ("times",)


def sizes(n1: int, scheme, snapshots: int, diagnostics: int, events: int,
          times: int = 0, observed: int = 0) -> dict:
    """The named sizes of a run's shapes (module docstring); ``times`` listed snapshot
    times (``output.times``), ``observed`` the entries of the observer's array (each array
    has an entry even when there are none)."""
    return {"n1": int(n1), "work": int(work_rows(scheme)), "snapshots": int(snapshots),
            "diagnostics": int(diagnostics), "events": int(events),
            "times": max(1, int(times)), "observed": max(1, int(observed))}


def shape(name: str, size: dict) -> tuple:
    """Field ``name``'s shape for the sizes ``size`` (``sizes``; the names its shape uses
    suffice)."""
    return tuple(d if isinstance(d, int) else size[d] for d in SPEC[name][1])


def allocate(n1: int, scheme, snapshots: int, diagnostics: int, events: int,
             times=(), observed: int = 0) -> RunArrays:
    """Zeroed arrays for a run of ``n1`` nodes with ``scheme`` and output buffers of
    ``snapshots``, ``diagnostics`` and ``events`` rows, its ``times`` the listed snapshot
    times (``output.times``), ``observed`` entries for its observer
    (``observers.state_size``)."""
    size = sizes(n1, scheme, snapshots, diagnostics, events, len(times), observed)
    arrays = RunArrays(*(np.zeros(shape(name, size), dtype=dt)
                         for name, (dt, _) in SPEC.items()))
    arrays.times[:len(times)] = times
    return arrays


def aot_type(name: str) -> str:
    """Numba's type string of field ``name`` (C-contiguous), for ``numba.pycc``."""
    dt, dims = SPEC[name]
    nd = len(dims)
    return f"{'f8' if dt == _F8 else 'i8'}[{','.join([':'] * (nd - 1) + ['::1'])}]"
