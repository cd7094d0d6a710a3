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


def test_the_ambiguous_bounce_s_threshold_is_the_one_the_events_apply(tmp_path):
    """The file's ``/bounces/ambiguous`` said "0.1 of the vibration speed" where the code
    (``stepping.events.AMBIGUOUS_SPEED``) and docs/MODEL.md say 0.2."""
    import re
    from pathlib import Path

    import h5py

    import rodjit
    from rodjit.stepping.events import AMBIGUOUS_SPEED

    path = tmp_path / "r.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.02, "rod.N": 3}), path)
    with h5py.File(path) as f:
        attrs = f["bounces/ambiguous"].attrs
        texts = [str(attrs["description"]), str(attrs["long_name"])]
    for text in texts:
        said = re.findall(r"below ([0-9.]+) of the|slower than ([0-9.]+) of the", text)
        assert said and float("".join(said[0])) == AMBIGUOUS_SPEED, text
    model = (Path(__file__).resolve().parents[1] / "docs" / "MODEL.md").read_text()
    assert f"|w_impact| < {AMBIGUOUS_SPEED:g} √(2 E_vib,impact/m)" in model
