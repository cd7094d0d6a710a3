"""``open_run``: a run file as an ``xarray.Dataset`` read lazily, the layout of
``Result.to_xarray`` (``records.datasets``).  The snapshots (``u``, ``v`` and the strain
derived from ``u``) stay in the file and are read when indexed or computed, so a long run
opens at once; the small tables (diagnostics, episodes, bounces) are read in full."""
from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from .._extras import need
from ..records.datasets import run_dataset, strain_of
from .run_reader import check_run_file, read_config, read_table, read_x
from .h5files import open_file

if TYPE_CHECKING:
    import xarray

__all__ = ["open_run"]


def _lazy_arrays(xr):
    """BackendArray classes bound to the installed xarray (imported on demand)."""
    from xarray.backends import BackendArray
    from xarray.core import indexing

    class H5Rows(BackendArray):
        """The first ``rows`` rows of a 2-D h5py dataset, read on indexing; ``derive``
        maps the rows read (all columns) to the values shown (e.g. strains)."""

        def __init__(self, dataset, rows: int, columns: int, derive=None):
            self.dataset, self.rows, self.derive = dataset, rows, derive
            self.shape = (rows, columns)
            self.dtype = np.dtype("float64")

        def __getitem__(self, key):
            return indexing.explicit_indexing_adapter(
                key, self.shape, indexing.IndexingSupport.BASIC, self._raw)

        def _raw(self, key):
            rows, cols = key
            if isinstance(rows, (int, np.integer)):
                rows = slice(int(rows), int(rows) + 1)
                squeeze = True
            else:
                squeeze = False
            start, stop, step = rows.indices(self.rows)
            data = self.dataset[start:stop:step]    # xarray makes steps positive
            if self.derive is not None:
                data = self.derive(data)
            data = data[:, cols]
            return data[0] if squeeze else data

    return H5Rows, indexing.LazilyIndexedArray


def open_run(path: str | os.PathLike[str]) -> xarray.Dataset:
    """The run file ``path`` as a lazily read ``xarray.Dataset`` (``Result.to_xarray``'s
    layout); the file stays open until ``ds.close()`` (or the Dataset is collected).
    ``ds.u.isel(t=-1)`` reads one snapshot; ``ds.load()`` reads them all.

    Parameters
    ----------
    path : str or os.PathLike
        A run file (format 1 or 2), also one still being written.

    Returns
    -------
    xarray.Dataset
        Snapshots on (t, x), strain on (t, x_segment), diagnostics on t_diag, bounces and
        episodes along their own dimensions, every variable with units and long_name.
    """
    xr = need("xarray", "analysis", "rodjit.open_run")
    f = open_file(path)
    try:
        check_run_file(f, path)
        config = read_config(f)
        H5Rows, Lazy = _lazy_arrays(xr)
        g = f["snapshots"]
        rows = min(g[c].shape[0] for c in ("t", "u", "v"))
        x = read_x(f)
        n = x.size - 1
        u = Lazy(H5Rows(g["u"], rows, n + 1))
        v = Lazy(H5Rows(g["v"], rows, n + 1))
        strain = Lazy(H5Rows(g["u"], rows, n, derive=lambda block: strain_of(block, n)))
        ds = run_dataset(
            x=x, t=g["t"][:rows], u=u, v=v, strain=strain,
            diagnostics=read_table(f, "diagnostics"), episodes=read_table(f, "episodes"),
            bounces=read_table(f, "bounces"),
            attrs={"status": str(f.attrs["status"]), "config_toml": config.to_toml(),
                   "source": str(path)},
            what="rodjit.open_run")
    except BaseException:
        f.close()
        raise
    ds.set_close(f.close)
    return ds
