"""The bounce table: bounce rows drained from a run, plus the bounce still collecting
episodes when it stopped (the *pending* bounce), as columns with their dtypes.

Every sink that keeps bounces (memory, the run file, a sweep point) builds its table here,
so all of them agree on the ``open`` and ``ambiguous`` columns and the integer
``n_episodes``; the pending bounce is always ambiguous (it may not be over), its
``restitution_energy`` NaN.
"""
from __future__ import annotations

import numpy as np

from .columns import BOUNCE_ROW_COLUMNS, columns_of

__all__ = ["bounce_table", "empty_bounces"]


def bounce_table(blocks, pending=None) -> dict[str, np.ndarray]:
    """Columns (``BOUNCE_COLUMNS`` order) of the bounce rows in ``blocks`` (arrays of shape
    (rows, len(BOUNCE_ROW_COLUMNS)), closed bounces) followed by ``pending``, the
    ``(row, open)`` of ``Run.pending_bounce`` or None.  The columns are new arrays."""
    rows = [r for r in blocks if len(r)]
    if pending is not None:
        rows.append(np.asarray(pending[0])[None, :])
    b = (rows[0] if len(rows) == 1 else np.concatenate(rows)) if rows \
        else np.zeros((0, len(BOUNCE_ROW_COLUMNS)))
    out = columns_of(b, BOUNCE_ROW_COLUMNS)
    out["n_episodes"] = out["n_episodes"].astype(np.int64)
    out["ambiguous"] = ambiguous = out["ambiguous"] != 0.0
    out["open"] = is_open = np.zeros(len(b), bool)
    if pending is not None:
        # not over yet: its flight (or its release) is still to come, so its restitution
        # is provisional and the energy it takes away not known
        ambiguous[-1] = True
        out["restitution_energy"][-1] = np.nan
        if pending[1]:
            is_open[-1] = True       # only the pending bounce can be open
    return out


def empty_bounces() -> dict[str, np.ndarray]:
    """A bounce table with no rows (a point that has not run)."""
    return bounce_table(())
