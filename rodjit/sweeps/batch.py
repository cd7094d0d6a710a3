"""A batch of sweep points run in one call of an engine, as columns: what the batch engines
(the CPU ensemble engine, the GPU engine ``rodjit.gpu``) hand to the sweep's driver."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["BatchResult"]


@dataclass
class BatchResult:
    """The summary rows and bounce tables of a batch of points, column by column.

    Attributes
    ----------
    index : ndarray
        (n,) int64 grid indices of the batch's points.
    values : dict
        Every ``sweeps.point.SUMMARY_COLUMNS`` name -> (n,) array, dtypes as
        ``point.empty_columns``.
    bounces : dict
        Every ``records.columns.BOUNCE_COLUMNS`` name -> (m,) array: the points' bounce rows
        in point order.
    bounce_count : ndarray
        (n,) int64 rows of each point in ``bounces``.
    warnings : tuple of str
        The distinct ModelWarning texts the batch's runs issued.
    worker : dict
        Where the batch ran.
    """

    index: np.ndarray
    values: dict[str, np.ndarray]
    bounces: dict[str, np.ndarray]
    bounce_count: np.ndarray
    warnings: tuple[str, ...] = ()
    worker: dict = field(default_factory=dict)
