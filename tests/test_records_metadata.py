"""Every column of every table has a long name and a unit, and no description is stale."""
from __future__ import annotations

import pytest

from rodjit.records.columns import BOUNCE_COLUMNS, DIAG_COLUMNS, EPISODE_COLUMNS
from rodjit.records.metadata import COLUMN_MEANINGS, meaning

TABLES = {"diagnostics": DIAG_COLUMNS, "episodes": EPISODE_COLUMNS, "bounces": BOUNCE_COLUMNS,
          "snapshots": ("t", "step", "u", "v"), "grid": ("x",)}


@pytest.mark.parametrize("table", sorted(TABLES))
def test_every_column_is_described_and_nothing_else(table):
    assert set(COLUMN_MEANINGS[table]) == set(TABLES[table])
    for column in TABLES[table]:
        m = meaning(table, column)
        assert m.long_name and m.units


def test_unknown_column_names_table_and_column():
    with pytest.raises(KeyError, match="'nope'.*'bounces'"):
        meaning("bounces", "nope")


def test_every_sweep_summary_column_is_described():
    from rodjit.sweeps.point import SUMMARY_COLUMNS

    assert set(SUMMARY_COLUMNS) <= set(COLUMN_MEANINGS["summary"])
