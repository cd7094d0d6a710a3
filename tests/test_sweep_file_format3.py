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
        assert f.attrs["format_version"] == sweep_file.FORMAT_VERSION == 4 and "points" not in f
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
    with pytest.raises(ValueError, match="continues formats 3 and 4 only"):
        rodjit.sweep(output=path, resume=True, scheduler="inline", handle_signals=False)
    assert path.read_bytes() == before


def test_a_point_marked_pending_with_its_rows_left_is_refused(tmp_path, today):
    """A write is whole or undone (the journal), so rows of a point marked pending are an
    edit: the resume refuses the file, untouched, naming the dataset."""
    path = tmp_path / "cut.h5"
    shutil.copy(today.path, path)
    with h5py.File(path, "r+") as f:
        s = f["summary"]
        s["status"][2:] = np.array(["pending", "pending"], dtype=object)
    before = path.read_bytes()
    with pytest.raises(ValueError, match=r"/summary/\w+\[2\] = .* in a pending row"):
        rodjit.sweep(output=path, resume=True, scheduler="inline", handle_signals=False)
    assert path.read_bytes() == before


def test_a_sweep_without_a_file_gives_the_same_rows(today):
    table = rodjit.sweep(BASE, GRID, scheduler="inline", handle_signals=False)
    assert same_bounces(table.bounce_rows(), today.bounce_rows())


def test_a_format_3_file_reads_and_resumes_in_format_3(tmp_path, today):
    """Format 3 (a header_digest over base, grid and n_points only, no row_digest) reads
    and continues without row digests, staying format 3; a format-4 file does not pass
    for one, nor one for a format-4 file."""
    path = tmp_path / "old3.h5"
    shutil.copy(today.path, path)
    with h5py.File(path, "r+") as f:
        f.attrs["format_version"] = 3
        with pytest.raises(ValueError, match="fails its integrity check"):
            from rodjit.sweeps.sweep_check import read_sweep
            read_sweep(f)       # format 3 with a format-4 digest
        f.attrs["format_version"] = 4
        del f["summary/row_digest"]
        f["summary/status"][2:] = np.array(["pending", "pending"], dtype=object)
        s = f["summary"]
        for name in ("bounce_start", "bounce_count"):
            s[name][2:] = -1 if name == "bounce_start" else 0
        for name, ds in s.items():
            if name in ("restitution_first", "contact_time_first") or ds.dtype.kind == "f" \
                    and name not in GRID:
                ds[2:] = np.nan
            elif ds.dtype.kind == "i" and name not in ("point", "bounce_start"):
                ds[2:] = 0
            elif h5py.check_string_dtype(ds.dtype) and name != "status":
                ds[2:] = np.array(["", ""], dtype=object)
        with pytest.raises(ValueError, match="row_digest is missing"):
            from rodjit.sweeps.sweep_check import read_sweep
            read_sweep(f)
        f.attrs["header_digest"] = sweep_file.header_digest(
            f.attrs["base_config_toml"], f.attrs["grid"], f.attrs["n_points"])
        with pytest.raises(ValueError, match="fails its integrity check"):
            read_sweep(f)       # format 4 with a format-3 digest
        f.attrs["format_version"] = 3
    assert rodjit.load_sweep(path).counts["pending"] == 2
    table = rodjit.sweep(output=path, resume=True, scheduler="inline", handle_signals=False)
    assert table.stats["points_run"] == 2
    assert same_bounces(rodjit.load_sweep(path).bounce_rows(), today.bounce_rows())
    with h5py.File(path, "r") as f:
        assert f.attrs["format_version"] == 3 and "row_digest" not in f["summary"]


def test_a_format_3_file_written_by_the_release_before_shows_and_resumes(tmp_path):
    """tests/fixtures/format3_sweep.h5, written by the code before format 4 and interrupted
    after three of six points: info shows it, load_sweep reads it, --resume runs the other
    three into it (still format 3), and the table is that of the same sweep run whole now
    (to rounding where the fixture's CPU differs from this one)."""
    from click.testing import CliRunner

    from rodjit.cli import main

    path = tmp_path / "f3.h5"
    shutil.copy(FIXTURES / "format3_sweep.h5", path)
    old = rodjit.load_sweep(path)
    assert old.attrs["format_version"] == 3 and old.counts == {
        "completed": 3, "failed": 0, "pending": 3}
    r = CliRunner().invoke(main, ["info", str(path)])
    assert r.exit_code == 0 and "format 3" in r.output and "interrupted" in r.output, r.output
    r = CliRunner().invoke(main, ["sweep", "--resume", "-o", str(path), "--scheduler",
                                  "inline", "-q"])
    assert r.exit_code == 0, r.output
    resumed = rodjit.load_sweep(path)
    assert resumed.status == "completed" and resumed.attrs["format_version"] == 3
    with h5py.File(path, "r") as f:
        assert "row_digest" not in f["summary"]
    whole = rodjit.sweep(old.base, old.grid, scheduler="inline",
                         handle_signals=False)
    for name in ("restitution_first", "contact_time_first", "min_u0", "steps"):
        assert np.allclose(resumed[name], whole[name], rtol=1e-6, equal_nan=True), name
    assert list(resumed["status"]) == ["completed"] * 6
