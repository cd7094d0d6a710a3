"""A table of the run file: the datasets of one group, growing together along axis 0 in
chunk-sized blocks.

Rows wait in a buffer of one chunk per column: a full chunk is written once, a partial one
is written (and kept) at each flush.  Memory stays at one chunk per column.  Without
compression a whole chunk goes to the file as it is (``write_direct_chunk``: one write, no
pass through HDF5's chunk cache, so closing the file has no backlog of cached chunks to
write); compressed chunks take HDF5's filter pipeline.
"""
from __future__ import annotations

import numpy as np

__all__ = ["Table"]


class Table:
    """``append`` rows (one array per column), ``flush`` the partial chunk; ``length`` rows
    so far, ``written`` of them in the datasets."""

    def __init__(self, datasets, *, cap: int, rows, dtypes, direct: bool, length: int = 0):
        """Columns ``datasets`` (chunks of ``cap`` rows; ``rows``, ``dtypes``: each column's
        row shape and dtype; ``direct``: whole chunks may go straight to the file) holding
        ``length`` rows.  ``Table.of`` asks the datasets themselves."""
        self.ds = list(datasets)
        self.rows = list(rows)
        self.cap = cap
        self.direct = direct
        self.start = length - length % cap      # first row held in the buffer
        self.fill = length - self.start
        self.buf = [np.zeros((cap,) + row, dtype) for row, dtype in zip(self.rows, dtypes)]
        if self.fill:
            for b, d in zip(self.buf, self.ds):
                b[:self.fill] = d[self.start:length]
        self.written = length                   # rows present in the datasets

    @classmethod
    def of(cls, datasets) -> "Table":
        """The table of existing columns, cut to the rows present in all of them."""
        datasets = list(datasets)
        rows = [d.shape[1:] for d in datasets]
        cap = datasets[0].chunks[0]
        direct = all(d.chunks == (cap,) + row and d.id.get_create_plist().get_nfilters() == 0
                     for d, row in zip(datasets, rows))       # unfiltered chunks of whole rows
        return cls(datasets, cap=cap, rows=rows, dtypes=[d.dtype for d in datasets],
                   direct=direct, length=min(d.shape[0] for d in datasets))

    @property
    def length(self) -> int:
        return self.start + self.fill

    def append(self, cols) -> None:
        k = len(cols[0])
        i = 0
        while i < k:
            if self.fill == 0 and k - i >= self.cap:   # whole chunks: write them directly
                m = (k - i) // self.cap * self.cap
                self._put([c[i:i + m] for c in cols], m)
                self.start += m
                i += m
                continue
            m = min(k - i, self.cap - self.fill)
            for b, c in zip(self.buf, cols):
                b[self.fill:self.fill + m] = c[i:i + m]
            self.fill += m
            i += m
            if self.fill == self.cap:
                self._put(self.buf, self.cap)
                self.start += self.cap
                self.fill = 0

    def flush(self) -> None:
        """Write the rows not in the datasets yet (the partial chunk; directly, its unused
        rows zeroed as HDF5 would fill them)."""
        if self.written == self.length:
            return
        if not self.direct:
            end = self.length
            self._resize(end)
            for d, b in zip(self.ds, self.buf):
                d[self.start:end] = b[:self.fill]
            self.written = end
            return
        for b in self.buf:
            b[self.fill:] = 0
        self._put(self.buf, self.fill)

    def _resize(self, n: int) -> None:
        for d, row in zip(self.ds, self.rows):
            d.id.set_extent((n,) + row)

    def _put(self, cols, m: int) -> None:
        """Write ``m`` rows of ``cols`` at ``start``: whole chunks, or (directly) a last
        partial one whose column arrays still span a whole chunk (the buffer)."""
        end = self.start + m
        self._resize(end)
        for d, b, c in zip(self.ds, self.buf, cols):
            if not self.direct:
                d[self.start:end] = c[:m]
                continue
            chunks = -(-m // self.cap)            # m rows rounded up to whole chunks
            c = np.ascontiguousarray(c[:chunks * self.cap], dtype=b.dtype)
            zeros = (0,) * (c.ndim - 1)
            for a in range(0, m, self.cap):
                d.id.write_direct_chunk((self.start + a,) + zeros, c[a:a + self.cap])
        self.written = end
