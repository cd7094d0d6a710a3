"""The summary table of a sweep: what ``rodjit.sweep`` returns and ``load_sweep`` reads."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

import numpy as np

from .._display import aligned, html_table, number, text
from .._extras import need
from ..config import Config, field_spec
from ..output import cf
from ..records.bounces import empty_bounces
from . import sweep_file
from .grid import Grid, format_value
from .point import SUMMARY_COLUMNS
from .sweep_check import read_sweep

if TYPE_CHECKING:
    import pandas
    import xarray

__all__ = ["SweepTable", "load_sweep", "TABLE_COLUMNS", "dimension_names"]

# the columns `report` prints after the swept keys (messages of failed points follow)
TABLE_COLUMNS = ("status", "n_bounces", "restitution_first", "restitution_mean",
                 "contact_time_first", "min_u0", "max_floor_force", "min_strain",
                 "energy_error", "steps", "wall_time")


def _key_attrs(key: str) -> dict:
    """The attributes of a swept key's coordinate: the key, its meaning and its unit (as
    the sweep file's ``/summary`` columns carry them)."""
    spec = field_spec(key)
    attrs = {"key": key, "long_name": key}
    if getattr(spec, "meaning", None):
        attrs["description"] = spec.meaning
    if getattr(spec, "unit", None):
        attrs["units"] = spec.unit
    return attrs


def dimension_names(keys) -> dict[str, str]:
    """Swept key -> its dimension name in ``SweepTable.to_xarray``: a Python identifier
    (``rod.mu`` -> ``mu``; ``rod_mu`` when two keys share their last part).  ``rodjit plot``
    takes either name for a swept key."""
    last = [k.rpartition(".")[2] for k in keys]
    return {k: (short if last.count(short) == 1 else k.replace(".", "_"))
            for k, short in zip(keys, last)}


def _csv_cell(value) -> str:
    """A CSV cell: a float at full precision (``repr``), anything else as ``str``."""
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    return str(value.item() if isinstance(value, np.generic) else value)


@dataclass(repr=False)
class SweepTable:
    """One row per grid point, in grid order: the swept keys, then ``SUMMARY_COLUMNS``.

    What ``rodjit.sweep`` returns and ``load_sweep`` reads.  ``table["restitution_first"]``
    is a column; ``len(table)`` the number of points; ``to_pandas()`` a DataFrame indexed by
    point; ``to_xarray()`` a Dataset with one dimension per swept key; ``bounces(i)`` point
    i's bounce table (read from the file, or kept in memory for a sweep without one);
    ``bounce_rows()`` every point's bounce rows in one table.

    Attributes
    ----------
    grid : Grid
        The swept keys and their values (the points are their Cartesian product).
    base : Config
        The configuration every point starts from.
    columns : dict of str to numpy.ndarray
        Column name -> one value per point: the swept keys, then the summary columns
        (``status``, ``message``, ``restitution_first``, ...; see *Output formats*).
    path : str or None
        The sweep file, None for a sweep kept in memory.
    status : str
        The sweep's state: ``"completed"``, ``"running"``, ``"interrupted"`` or
        ``"failed"``.
    message : str
        Why the sweep stopped, for a status other than ``"completed"``.
    stats : dict
        Wall time, points run here, points per second and the executor backend of the
        call that ran it (empty for a table read from a file).
    attrs : dict
        The sweep file's root attributes (format version, configuration, command).
    """

    grid: Grid
    base: Config                       # the base rodjit.Config
    columns: dict[str, np.ndarray]
    path: str | None = None
    status: str = "completed"
    message: str = ""
    stats: dict = field(default_factory=dict)
    attrs: dict = field(default_factory=dict)
    _bounces: dict = field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return len(self.grid)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    @property
    def counts(self) -> dict[str, int]:
        """Number of points per status: ``{"completed": .., "failed": .., "pending": ..}``."""
        status = self.columns["status"]
        return {s: int(np.sum(status == s)) for s in ("completed", "failed", "pending")}

    def config(self, index: int) -> Config:
        """The configuration point ``index`` ran.

        Parameters
        ----------
        index : int
            The point number (row), from 0.

        Returns
        -------
        Config
            ``base`` with the point's swept values.
        """
        return self.grid.config(self.base, index)

    def keep_bounces(self, index: int, bounces: dict[str, np.ndarray]) -> None:
        """Hold point ``index``'s bounce table in memory (a sweep without a file).

        Parameters
        ----------
        index : int
            The point number, from 0.
        bounces : dict of str to numpy.ndarray
            Its bounce table (``records.bounces.bounce_table`` columns).
        """
        self._bounces[index] = bounces

    def bounces(self, index: int) -> dict[str, np.ndarray]:
        """Point ``index``'s bounce table: kept in memory, else read from the file.

        Parameters
        ----------
        index : int
            The point number, from 0.

        Returns
        -------
        dict of str to numpy.ndarray
            The bounce table's columns (empty for a point that has not run).
        """
        if index in self._bounces:
            return self._bounces[index]
        if self.path is None or self.columns["status"][index] == "pending":
            return empty_bounces()      # (pending here, whatever the file says since)
        with sweep_file.open_sweep(self.path) as f:
            return sweep_file.read_bounces(f, index)

    def bounce_rows(self) -> dict[str, np.ndarray]:
        """Every point's bounce table in one: the bounce columns and ``point`` (each row's
        grid point), ordered by point and, within a point, by time.

        Returns
        -------
        dict of str to numpy.ndarray
            ``point``, then the run file's ``/bounces`` columns (``t_impact``,
            ``restitution``, ...); the rows of the points that have run (by this table:
            a point that has run in a sweep still going since it was read is left out).

        Raises
        ------
        ValueError
            The file no longer proves itself (``load_sweep``).
        """
        if self.path is None or self._bounces:
            return sweep_file.join_bounces(sorted(self._bounces.items()))
        with sweep_file.open_sweep(self.path) as f:
            read_sweep(f)
            return sweep_file.read_all_bounces(f, self.columns["status"] != "pending")

    def to_pandas(self) -> pandas.DataFrame:
        """A pandas DataFrame, one row per point (index: the point number)."""
        pd = need("pandas", "analysis", "SweepTable.to_pandas")
        df = pd.DataFrame(self.columns)
        df.index.name = "point"
        return df

    def to_csv(self, path: str | os.PathLike[str], columns: Sequence[str] | None = None,
               overwrite: bool = False) -> Path:
        """Write the table as CSV (one row per point, a header of column names; floats at
        full precision, ``nan``/``inf`` as Python writes them), for a spreadsheet or a
        reader without h5py.  Written to ``path.part`` and renamed: a failed write leaves
        no half file.

        Parameters
        ----------
        path : str or os.PathLike
            The CSV file.
        columns : sequence of str, optional
            The columns, in order (default: all, the swept keys first).
        overwrite : bool
            Replace an existing file.

        Returns
        -------
        pathlib.Path
            ``path``.

        Raises
        ------
        ValueError
            An unknown column, or ``path`` exists and ``overwrite`` is false, or its
            directory is missing.
        """
        import csv

        names = list(self.columns) if columns is None else list(columns)
        unknown = [c for c in names if c not in self.columns]
        if unknown:
            raise ValueError(f"columns: {unknown[0]!r} is not a column of this sweep (one "
                             f"of {', '.join(self.columns)})")
        out = Path(path)
        if out.exists() and not overwrite:
            raise ValueError(f"output file {str(out)!r} exists (overwrite=True replaces it)")
        if not out.parent.is_dir():
            raise ValueError(f"output directory {str(out.parent)!r} does not exist")
        tmp = out.with_name(out.name + ".part")
        try:
            with open(tmp, "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(names)
                cols = [self.columns[c] for c in names]
                for i in range(len(self)):
                    w.writerow([_csv_cell(col[i]) for col in cols])
            os.replace(tmp, out)
        finally:
            tmp.unlink(missing_ok=True)
        return out

    def dimension_names(self) -> dict[str, str]:
        """Swept key -> its dimension name in ``to_xarray``: a Python identifier (``rod.mu``
        -> ``mu``; ``rod_mu`` when two keys share their last part)."""
        return dimension_names(self.grid.keys)

    def to_xarray(self) -> xarray.Dataset:
        """An xarray Dataset over the grid: one dimension per swept key, named by
        ``dimension_names`` (``ds.sel(mu=10)``) with the full key as the ``key``
        attribute; every summary column with its ``description`` (and ``units``)."""
        xr = need("xarray", "analysis", "SweepTable.to_xarray")
        dims = self.dimension_names()
        shape = tuple(len(v) for v in self.grid.values)
        coords = {dims[k]: (dims[k], np.asarray(values), _key_attrs(k))
                  for k, values in zip(self.grid.keys, self.grid.values)}
        data = {}
        for name, values in self.columns.items():
            if name in self.grid.keys:
                continue
            kind, description = SUMMARY_COLUMNS.get(name, ("", ""))
            attrs = {"long_name": name, "description": description}
            try:
                units = cf.column_attrs("summary", name).get("units")   # as in the file
            except KeyError:        # a column this version does not know
                units = None
            if units:
                attrs["units"] = units
            data[name] = (tuple(dims[k] for k in self.grid.keys),
                          np.asarray(values).reshape(shape), attrs)
        return xr.Dataset(data, coords, {"status": self.status, "points": len(self),
                                         "base_config_toml": self.base.to_toml(),
                                         **({"source": self.path} if self.path else {})})

    # ---- showing it ---------------------------------------------------------------------
    def _overview(self) -> tuple[str, list[tuple[str, str]]]:
        c = self.counts
        title = (f"rodjit.SweepTable: {self.status}, {len(self)} points ({c['completed']} "
                 f"completed, {c['failed']} failed, {c['pending']} not run)")
        b = self.base
        rows = [(k, ", ".join(format_value(v) for v in values))
                for k, values in zip(self.grid.keys, self.grid.values)]
        rows.append(("base", f"N = {b.rod.N}, mu = {b.rod.mu:g}, {b.time.integrator}, "
                             f"t_end = {b.time.t_end:g} s"))
        for name in ("restitution_first", "energy_error", "steps", "wall_time"):
            values = np.asarray(self.columns[name], float)
            finite = values[np.isfinite(values)]
            if name == "wall_time" and finite.size:
                text = f"{finite.sum():.3g} s in all"
            elif finite.size:
                text = f"{number(finite.min())} to {number(finite.max())}"
            else:
                text = "-"
            rows.append((name, text))
        if self.path:
            rows.append(("file", self.path))
        if self.message:
            rows.append(("message", self.message))
        return title, rows

    def __repr__(self) -> str:
        return text(*self._overview())

    def _repr_html_(self) -> str:
        return html_table(*self._overview())

    def report(self, max_rows: int | None = None) -> str:
        """The table as text: one line per point, then the failures' messages.

        Parameters
        ----------
        max_rows : int or None
            Most points shown (the first and last halves, ``...`` between) and failures
            listed; None shows all.

        Returns
        -------
        str
        """
        keys = list(self.grid.keys)
        shown = list(TABLE_COLUMNS)
        if self.base.output.observer != "none":      # then the observer's columns
            shown += [c for c in self.columns if c not in keys and c not in SUMMARY_COLUMNS]
        head = ["#"] + keys + shown
        n = len(self)
        show = list(range(n))
        if max_rows is not None and n > max_rows:
            half = max(1, max_rows // 2)
            show = show[:half] + [-1] + show[n - half:]
        rows = []
        for i in show:
            if i < 0:
                rows.append(["..."] + [""] * (len(head) - 1))
                continue
            rows.append([str(i)] + [_cell(self.columns[c][i], c) for c in keys + shown])
        lines = aligned(head, rows)
        failed = np.flatnonzero(self.columns["status"] == "failed")
        if failed.size:
            lines.append(f"failed points ({failed.size}):")
            for i in failed[:max_rows] if max_rows else failed:
                lines.append(f"  {i}: {self.grid.describe(int(i))}: {self.columns['message'][i]}")
            if max_rows and failed.size > max_rows:
                lines.append(f"  ... and {failed.size - max_rows} more (rodjit info shows all)")
        return "\n".join(lines)

    def headline(self) -> str:
        """One line: where the sweep is, its status, the points per status and, for a sweep
        run by this call, its wall time and throughput (what ``rodjit sweep`` prints)."""
        c = self.counts
        where = self.path or "in memory"
        text = (f"{where}: sweep {self.status}, {len(self)} points ({c['completed']} completed, "
                f"{c['failed']} failed, {c['pending']} not run)")
        if self.stats.get("wall_time"):
            s = self.stats
            text += (f" in {s['wall_time']:.3g} s ({s['points_run']} run here, "
                     f"{s['points_per_second']:.3g} points/s, {s['backend']})")
        return text


def _cell(value, column: str) -> str:
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    value = float(value)
    if value != value:
        return "-"
    if column in ("wall_time",):
        return f"{value:.3g}"
    if column in SUMMARY_COLUMNS or "." not in column:    # a swept key has a dot
        return f"{value:.5g}"
    return format_value(value)


def load_sweep(path: str | os.PathLike[str]) -> SweepTable:
    """Read a sweep file's summary table (also while the sweep is still running).

    Parameters
    ----------
    path : str or os.PathLike
        A sweep file written by ``rodjit sweep`` or ``rodjit.sweep``.

    Returns
    -------
    SweepTable

    Raises
    ------
    ValueError
        One line: the file is missing, not a sweep file, or does not prove itself (a
        column, attribute or bounce row that is not what rodjit wrote: the file was
        changed or damaged since; ``sweep_check``).
    """
    with sweep_file.open_sweep(path) as f:
        header, columns = read_sweep(f)
        attrs = header["attrs"]
    return SweepTable(grid=header["grid"], base=header["base"], columns=columns,
                      path=str(Path(path)), status=str(attrs["status"]),
                      message=str(attrs.get("message", "")), attrs=attrs)
