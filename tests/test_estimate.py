"""Estimates before writing: sizes parsed, rows and bytes counted from the configuration,
runs that could never finish or fit refused with the estimate in the message."""
from __future__ import annotations

import math

import numpy as np
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
    ({"time.dt": 1e-9, "time.t_end": 100.0}, "max_steps="),
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


@pytest.mark.parametrize("dt,ok", [(1e-3, True), (2e-4, True), (1.25e-5, True),
                                   (3e-4, False), (2e-3, False), (2.5e-3, False)])
def test_a_fixed_step_must_divide_the_output_intervals(tmp_path, dt, ok):
    """A fixed time.dt that does not divide an output interval would have its steps
    shortened before every output time: refused (in memory too), naming the interval and
    a step that divides them all."""
    c = rodjit.Config().override({"time.dt": dt, "time.t_end": 0.01})
    if ok:
        E.check_fixed_step(c)
        return
    with pytest.raises(ValueError, match=r"does not divide output\.\w+_interval .*e\.g\. "
                                         r"time\.dt = ([0-9.e-]+)") as info:
        rodjit.run_to_file(c, tmp_path / "x.h5")
    assert not (tmp_path / "x.h5").exists()
    suggested = float(info.value.args[0].split("e.g. time.dt = ")[1].split(")")[0])
    E.check_fixed_step(c.override({"time.dt": suggested}))     # the suggestion divides
    with pytest.raises(ValueError, match="does not divide"):
        rodjit.simulate(c)
    # without outputs every step is time.dt but the last, which ends on time.t_end
    E.check_fixed_step(c.override({"output.snapshot_interval": 0.0,
                                   "output.diagnostics_interval": 0.0}))


def test_every_step_of_a_dividing_fixed_step_is_that_step():
    """What the file reports is what was done: the steps of a dividing fixed dt are all
    dt (their count is t_end / dt) and /diagnostics/dt holds that value."""
    c = rodjit.Config().override({"time.dt": 2.5e-4, "time.t_end": 0.02,
                                  "time.integrator": "verlet"})
    res = rodjit.simulate(c)
    assert res.stats["steps"] == 80
    assert np.all(res.diagnostics["dt"] == 2.5e-4)


def test_plan_run_says_what_would_be_written_and_writes_nothing(tmp_path):
    c = rodjit.Config().override({"time.t_end": 1.0, "time.dt": 1e-3})
    plan = rodjit.plan_run(c, tmp_path / "sub.h5")
    assert (plan.estimate.snapshots, plan.estimate.diagnostics) == (201, 1001)
    assert plan.estimate.steps == pytest.approx(1000) and not plan.replaces
    text = plan.report()
    assert "201 rows" in text and "1000 fixed steps" in text and str(tmp_path) in text
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match="limit of 1 KiB"):
        rodjit.plan_run(c, tmp_path / "x.h5", max_output=1024)
    with pytest.raises(ValueError, match="does not exist"):
        rodjit.plan_run(c, tmp_path / "nodir" / "x.h5")
    assert list(tmp_path.iterdir()) == []
