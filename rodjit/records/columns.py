"""The columns of a run's tables, in the order the compiled loop writes them.

``stepping.layout`` stays the source of the names (the loop writes rows by those
positions); this module gives the record floors one place to take them from, plus the
columns a table of bounces adds.
"""
from __future__ import annotations

import numpy as np

from ..stepping.layout import BOUNCE_ROW_COLUMNS, DIAG_COLUMNS, EPISODE_COLUMNS

__all__ = ["DIAG_COLUMNS", "EPISODE_COLUMNS", "BOUNCE_ROW_COLUMNS", "BOUNCE_COLUMNS",
           "INT_COLUMNS", "BOOL_COLUMNS", "columns_of"]

# a bounce table: the loop's bounce row (MODEL.md §3), then whether the bounce was still
# open (its last contact episode not ended) when the run stopped
BOUNCE_COLUMNS = BOUNCE_ROW_COLUMNS + ("open",)
INT_COLUMNS = frozenset({"step", "n_episodes"})      # integer columns of every table
BOOL_COLUMNS = frozenset({"open", "ambiguous"})


def columns_of(rows: np.ndarray, names) -> dict[str, np.ndarray]:
    """``{name: column}`` of a table of ``rows`` (one row per record, a column per name),
    from one transposed copy: each column is contiguous and owned by the table, never a
    view of ``rows`` (a one-row table's transpose would otherwise be one)."""
    return dict(zip(names, np.array(rows.T, order="C")))
