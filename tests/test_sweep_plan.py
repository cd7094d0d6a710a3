"""A sweep checked before it starts: every point's fixed step, the sweep file and the run
files against the size limit and the free disk, what ``plan_sweep`` (``--dry-run``) says."""
from __future__ import annotations

import shutil
from collections import namedtuple

import pytest

import rodjit
from rodjit.sweeps import plan as P

BASE = rodjit.Config().override({"time.t_end": 0.02, "rod.N": 3})


def _nothing_in(d):
    return [p.name for p in d.iterdir()] == []


def test_the_plan_counts_points_files_and_the_worst_point(tmp_path):
    grid = {"rod.N": [3, 30], "rod.mu": [0.0, 1.0, 2.0], "time.t_end": [0.01, 0.02]}
    plan = rodjit.plan_sweep(BASE, grid, output=tmp_path / "s.h5", save_runs=tmp_path / "runs")
    assert len(plan.grid) == 12 and plan.grid.keys == ("rod.N", "rod.mu", "time.t_end")
    worst = rodjit.plan_run(BASE.override({"rod.N": 30, "time.t_end": 0.02})).estimate
    assert plan.worst == worst and plan.grid.point(plan.worst_index) == {
        "rod.N": 30, "rod.mu": 0.0, "time.t_end": 0.02}
    each = [rodjit.plan_run(plan.grid.config(BASE, i)).estimate.file_bytes for i in range(12)]
    assert plan.runs_bytes == pytest.approx(sum(each))
    text = plan.report()
    assert "12: rod.N (2 values) x rod.mu (3 values) x time.t_end (2 values)" in text
    assert "run files    12 in" in text and "worst point  " in text
    assert _nothing_in(tmp_path)


def test_the_sweep_file_estimate_bounds_a_real_file(tmp_path):
    grid = {"rod.mu": "linspace(0, 1, 16)"}
    plan = rodjit.plan_sweep(BASE, grid, output=tmp_path / "s.h5")
    rodjit.sweep(BASE, grid, output=tmp_path / "s.h5", scheduler="inline")
    assert 0.5 < plan.sweep_bytes / (tmp_path / "s.h5").stat().st_size < 2.0


@pytest.mark.parametrize("over,save,match", [
    ({"max_output": 50_000}, False, r"the sweep file would hold 4 points, about .* limit of"),
    ({"max_output": 1_000_000}, True, r"the run file of grid point 0 \(rod.mu=0\) would write"),
    ({"max_points": 3}, False, "the grid has 4 points"),
    ({}, False, None),
])
def test_a_sweep_that_would_not_fit_is_refused_before_it_starts(tmp_path, over, save, match):
    big = BASE.override({"time.t_end": 1.0, "rod.N": 100})
    kwargs = dict(output=tmp_path / "s.h5", save_runs=tmp_path / "runs" if save else None,
                  scheduler="inline", **over)
    if match is None:
        rodjit.plan_sweep(big, {"rod.mu": [0, 1, 2, 3]}, output=tmp_path / "s.h5")
        return
    with pytest.raises(ValueError, match=match):
        rodjit.sweep(big, {"rod.mu": [0, 1, 2, 3]}, **kwargs)
    assert _nothing_in(tmp_path)     # no file, no lock, no directory


def test_the_free_space_counts_sweep_and_run_files_together(tmp_path, monkeypatch):
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(10**9, 10**9 - 300_000, 300_000))
    grid = {"rod.mu": [0, 1, 2, 3]}
    rodjit.plan_sweep(BASE, grid, output=tmp_path / "s.h5")         # the sweep file fits
    with pytest.raises(ValueError, match="the sweep file and the run files would take about "
                                         ".* more than the 293 KiB free on the disk"):
        rodjit.sweep(BASE, grid, output=tmp_path / "s.h5", save_runs=tmp_path / "runs",
                     scheduler="inline")
    assert _nothing_in(tmp_path)


@pytest.mark.parametrize("grid,match", [
    ({"time.dt": [1e-3, 1e-30]}, r"grid point 1 \(time.dt=1e-30\): .*resolution of t"),
    ({"time.dt": [1e-3, 3e-4]}, r"grid point 1 \(time.dt=0.0003\): .*does not divide"),
    ({"time.t_end": [0.02, 100.0], "time.dt": [1e-3, 1e-9]},
     r"grid point 3 \(time.t_end=100 time.dt=1e-09\): .*max_steps="),
])
def test_every_point_is_checked_before_workers_start(tmp_path, grid, match):
    """The fixed-step checks of a run, at every point, before any worker or file."""
    with pytest.raises(ValueError, match=match):
        rodjit.sweep(BASE, grid, output=tmp_path / "s.h5", jobs=1)
    with pytest.raises(ValueError, match=match):
        rodjit.sweep(BASE, grid, scheduler="inline")                # in memory too
    assert _nothing_in(tmp_path)


def test_checks_of_a_large_grid_run_per_combination():
    """10^6 points over one key outside the estimate: the point checks run once."""
    plan = rodjit.plan_sweep(BASE, {"rod.kappa": "linspace(1, 2, 1000)",
                                    "rod.mu": "linspace(0, 1, 1000)"})
    assert len(plan.grid) == 10**6 and plan.runs_bytes == 0.0
    assert P.SWEEP_OVERHEAD > 0


@pytest.mark.parametrize("to_file", [False, True])
def test_a_sweep_that_would_not_fit_in_memory_is_refused_on_every_path(tmp_path, monkeypatch,
                                                                       to_file):
    """The points' table is held in memory (a quarter as much with a sweep file): a grid
    under max_points can still need more than the machine has. plan_sweep, sweep and a
    resume refuse it in one line, before a file or a worker; the dry run says the
    estimate."""
    from click.testing import CliRunner

    from rodjit.cli import main

    grid = {"rod.mu": [1.0, 2.0, 3.0, 4.0]}
    base = rodjit.Config().override({"time.t_end": 0.01, "rod.N": 3})
    out = tmp_path / "s.h5" if to_file else None
    assert P.plan_sweep(base, grid, output=out).memory == 4 * (
        P.MEMORY_POINT_BYTES_FILE if to_file else P.MEMORY_POINT_BYTES)
    if to_file:
        rodjit.sweep(base, {"rod.mu": [1.0, 2.0]}, output=out, scheduler="inline",
                     handle_signals=False)
        before = out.read_bytes()
    monkeypatch.setattr(P, "physical_memory", lambda: 3.5 * (
        P.MEMORY_POINT_BYTES_FILE if to_file else P.MEMORY_POINT_BYTES))
    target = tmp_path / "new.h5" if to_file else None
    with pytest.raises(ValueError, match=r"^a sweep of 4 points would hold about .* in memory"):
        P.plan_sweep(base, grid, output=target)
    with pytest.raises(ValueError, match=r"more than the .* of this machine"):
        rodjit.sweep(base, grid, output=target, scheduler="inline", handle_signals=False)
    if to_file:
        assert not target.exists()
        r = CliRunner().invoke(main, ["sweep", "--grid", "rod.mu=1,2,3,4", "--set",
                                      "time.t_end=0.01", "-o", str(target), "--dry-run"])
        assert r.exit_code == 2 and "in memory" in r.stderr and not target.exists()
        monkeypatch.setattr(P, "physical_memory", lambda: 1.0)
        with pytest.raises(ValueError, match=r"^a sweep of 2 points would hold"):
            rodjit.sweep(output=out, resume=True, scheduler="inline", handle_signals=False)
        assert out.read_bytes() == before


def test_the_dry_run_says_the_memory(tmp_path):
    plan = P.plan_sweep(rodjit.Config(), {"rod.mu": [1.0, 2.0]}, output=tmp_path / "s.h5")
    line = [ln for ln in plan.report().splitlines() if ln.startswith("memory")][0]
    assert "in the sweep's process" in line
