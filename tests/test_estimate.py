"""Estimates before writing: sizes parsed, rows and bytes counted from the configuration,
runs that could never finish or fit refused with the estimate in the message."""
from __future__ import annotations

import math

import pytest

import rodjit
from rodjit.output import estimate as E
from rodjit.output.run_layout import TABLES


def test_sizes_parse_and_format():
    assert E.parse_size("1K") == 1024 and E.parse_size("2GB") == 2e9
    assert E.parse_size("10GiB") == 10 * 2**30 and E.parse_size("inf") == math.inf
    for bad in ("lots", "-1M", "0"):
        with pytest.raises(ValueError, match="size"):
            E.parse_size(bad)
    assert E.format_size(1536) == "1.5 KiB"


def test_rows_and_bytes_follow_the_intervals():
    c = rodjit.Config().override({"time.t_end": 1.0, "output.snapshot_interval": 0.25,
                                  "output.diagnostics_interval": 0.5, "rod.N": 9})
    e = E.estimate_run(c)
    assert (e.snapshots, e.diagnostics) == (5, 3)
    assert e.file_bytes == E._OVERHEAD + 5 * (2 * 10 + 2) * 8 + 3 * len(TABLES["diagnostics"]) * 8


def test_the_estimate_bounds_a_real_file(tmp_path):
    c = rodjit.Config().override({"time.t_end": 0.5})
    rodjit.run_to_file(c, tmp_path / "r.h5")
    size = (tmp_path / "r.h5").stat().st_size
    assert 0.5 < E.estimate_run(c).file_bytes / size < 2.0


@pytest.mark.parametrize("over,match", [
    ({"time.dt": 1e-30}, "resolution of t"),
    ({"time.dt": 1e-9, "time.t_end": 100.0}, "max-steps"),
    ({"output.snapshot_interval": 1e-12}, "more than the limit"),
    ({"time.t_end": 1e300}, "more than the limit"),
])
def test_runs_that_cannot_finish_or_fit_are_refused_before_writing(tmp_path, over, match):
    with pytest.raises(ValueError, match=match):
        rodjit.run_to_file(rodjit.Config().override(over), tmp_path / "x.h5")
    assert not (tmp_path / "x.h5").exists()


def test_the_limits_can_be_raised(tmp_path):
    c = rodjit.Config().override({"time.t_end": 0.05})
    with pytest.raises(ValueError, match="limit of 1 KiB"):
        rodjit.run_to_file(c, tmp_path / "x.h5", max_output=1024)
    assert rodjit.run_to_file(c, tmp_path / "x.h5", max_output=math.inf).status == "completed"


def test_a_file_larger_than_the_free_space_is_refused(tmp_path, monkeypatch):
    import shutil
    from collections import namedtuple

    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(10**6, 10**6 - 1000, 1000))
    with pytest.raises(ValueError, match="free on the disk"):
        rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.05}), tmp_path / "x.h5")
