"""What a run figure reads, the same from a ``Result`` in memory and from a run file: the
configuration, the grid, strided snapshots and diagnostics, episodes and bounces.  A file
is read only as far as a figure needs (strided rows, chosen columns), so long runs draw in
bounded memory."""
from __future__ import annotations

import math

import numpy as np

from ..output import hdf5
from ..records.result import Result

__all__ = ["RunSource", "MAX_POINTS"]

MAX_POINTS = 20_000    # time samples drawn at most per curve (strided read)


def _stride(n: int, limit: int) -> int:
    return max(1, math.ceil(n / limit))


class RunSource:
    """A Result or an open run file, behind one reading interface; use as a context
    manager (a file is closed on exit)."""

    def __init__(self, obj):
        self._file = None
        if isinstance(obj, Result):
            self.result = obj
            self.config = obj.config
            self.x = obj.x
        else:
            self.result = None
            self._file = hdf5.open_file(obj)
            try:
                hdf5.check_run_file(self._file, obj)
                self.config = hdf5.read_config(self._file)
                self.x = hdf5.read_x(self._file)
            except BaseException:
                self._file.close()
                raise

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    # ---- snapshots ----------------------------------------------------------------------
    def n_snapshots(self) -> int:
        if self.result is not None:
            return int(self.result.t.size)
        g = self._file["snapshots"]
        return min(g[c].shape[0] for c in ("t", "u", "v"))

    def snapshot_times(self) -> np.ndarray:
        if self.result is not None:
            return self.result.t
        return self._file["snapshots/t"][:self.n_snapshots()]

    def snapshots(self, quantity: str, rows: slice | np.ndarray, nodes=None) -> np.ndarray:
        """``u`` or ``v`` at the snapshot ``rows`` (a slice or increasing indices), all nodes
        or the listed ``nodes``."""
        if self.result is not None:
            data = getattr(self.result, quantity)[rows]
            return data if nodes is None else data[:, nodes]
        ds = self._file["snapshots"][quantity]
        data = ds[rows] if isinstance(rows, slice) else ds[np.asarray(rows)]
        return data if nodes is None else data[:, nodes]

    def snapshot_row(self, quantity: str, i: int) -> np.ndarray:
        """One snapshot (a frame of an animation), read on its own."""
        if self.result is not None:
            return getattr(self.result, quantity)[i]
        return self._file["snapshots"][quantity][i]

    def strided_rows(self, limit: int = MAX_POINTS, window=None) -> slice:
        """Snapshot rows to draw: all of them (or those in the time ``window``), strided
        to at most ``limit``."""
        n = self.n_snapshots()
        start, stop = 0, n
        if window is not None:
            t = self.snapshot_times()
            start = int(np.searchsorted(t, window[0], "left"))
            stop = int(np.searchsorted(t, window[1], "right"))
        return slice(start, stop, _stride(stop - start, limit))

    # ---- tables -------------------------------------------------------------------------
    def diagnostics(self, columns, limit: int = MAX_POINTS) -> dict[str, np.ndarray]:
        if self.result is not None:
            d = self.result.diagnostics
            n = d["t"].size
            s = _stride(n, limit)
            return {c: d[c][::s] for c in columns}
        g = self._file["diagnostics"]
        n = min(g[c].shape[0] for c in hdf5.TABLES["diagnostics"])
        s = _stride(n, limit)
        return {c: g[c][0:n:s] for c in columns}

    def table(self, name: str) -> dict[str, np.ndarray]:
        """``episodes`` or ``bounces``."""
        if self.result is not None:
            return getattr(self.result, name)
        return hdf5.read_table(self._file, name)
