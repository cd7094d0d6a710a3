"""Sweep-file format 3: every point's bounce rows in one table (a CF indexed ragged array),
so the file's number of HDF5 objects does not grow with the number of points; format-2
files (tests/fixtures/apex_sweep.h5, one group per point) still read, point by point and as
one table, and are not continued.
"""
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.sweeps import sweep_file

FIXTURES = Path(__file__).parent / "fixtures"
BASE = rodjit.load_preset("paper-mu100").override({"rod.N": 5, "time.t_end": 1.5})
GRID = {"rod.mu": [0.0, 100.0], "floor.kappa_b": [1000.0, 3000.0]}


def objects(path) -> int:
    names = []
    with h5py.File(path, "r") as f:
        f.visit(names.append)
    return len(names)


def same_bounces(a: dict, b: dict) -> bool:
    return set(a) == set(b) and all(np.array_equal(a[k], b[k], equal_nan=True) for k in a)


@pytest.fixture(scope="module")
def today(tmp_path_factory):
    path = tmp_path_factory.mktemp("f3") / "s.h5"
    rodjit.sweep(BASE, GRID, output=path, scheduler="inline", handle_signals=False)
    return rodjit.load_sweep(path)


def test_the_object_count_does_not_grow_with_the_points(tmp_path):
    short = BASE.override({"time.t_end": 0.6})
    counts = []
    for n in (4, 240):
        path = tmp_path / f"s{n}.h5"
        rodjit.sweep(short, {"rod.mu": list(np.linspace(0, 100, n))}, output=path,
                     scheduler="inline", handle_signals=False)
        counts.append(objects(path))
        assert rodjit.load_sweep(path).bounce_rows()["point"].size > 0
    assert counts[0] == counts[1] <= 300


def test_each_points_rows_are_where_the_summary_says(today):
    with h5py.File(today.path, "r") as f:
        s, g = f["summary"], f["bounces"]
        assert f.attrs["format_version"] == 3 and "points" not in f
        assert int(g.attrs["rows"]) == g["t_impact"].shape[0] == int(s["bounce_count"][()].sum())
        for i in range(len(today)):
            a, c = int(s["bounce_start"][i]), int(s["bounce_count"][i])
            assert c == today.bounces(i)["t_impact"].size > 0
            assert np.all(g["point_index"][a:a + c] == i)


def test_the_rows_read_as_one_table_ordered_by_point(today):
    rows = today.bounce_rows()
    assert np.all(np.diff(rows["point"]) >= 0)
    for i in range(len(today)):
        one = today.bounces(i)
        assert same_bounces({k: v[rows["point"] == i] for k, v in rows.items() if k != "point"},
                            one)
    assert rows["ambiguous"].dtype == bool and rows["open"].dtype == bool


def test_a_format_2_file_reads_as_one_table_and_is_not_continued(tmp_path):
    path = tmp_path / "old.h5"
    shutil.copy(FIXTURES / "apex_sweep.h5", path)
    old = rodjit.load_sweep(path)
    assert old.attrs["format_version"] == 2
    rows = old.bounce_rows()
    assert rows["point"].size == sum(old.bounces(i)["t_impact"].size for i in range(len(old))) > 0
    for i in range(len(old)):
        assert same_bounces({k: v[rows["point"] == i] for k, v in rows.items() if k != "point"},
                            old.bounces(i))
    before = path.read_bytes()
    with pytest.raises(ValueError, match="continues format 3 only"):
        rodjit.sweep(output=path, resume=True, scheduler="inline", handle_signals=False)
    assert path.read_bytes() == before


def test_rows_a_cut_write_left_are_dropped_on_resume(tmp_path, today):
    """A write cut short after its bounce rows but before its points were marked done:
    the rows stay in the file, the points stay pending; resume drops the rows and runs
    the points again, to the table of an uninterrupted sweep."""
    path = tmp_path / "cut.h5"
    shutil.copy(today.path, path)
    with h5py.File(path, "r+") as f:
        s = f["summary"]
        s["status"][2:] = np.array(["pending", "pending"], dtype=object)
        first = int(s["bounce_start"][2])
    table = rodjit.sweep(output=path, resume=True, scheduler="inline", handle_signals=False)
    assert table.stats["points_run"] == 2
    with h5py.File(path, "r") as f:
        g, s = f["bounces"], f["summary"]
        assert g["t_impact"].shape[0] == int(g.attrs["rows"]) == int(s["bounce_count"][()].sum())
        assert int(s["bounce_start"][2]) == first                 # written again in place
    for i in range(len(today)):
        assert same_bounces(table.bounces(i), today.bounces(i))
    assert same_bounces(rodjit.load_sweep(path).bounce_rows(), today.bounce_rows())


def test_a_sweep_without_a_file_gives_the_same_rows(today):
    table = rodjit.sweep(BASE, GRID, scheduler="inline", handle_signals=False)
    assert same_bounces(table.bounce_rows(), today.bounce_rows())
