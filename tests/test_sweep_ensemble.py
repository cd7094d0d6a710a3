"""The ensemble engine: a batch of points in one compiled call gives each point's row and
bounce table exactly as the per-point path (``point.run_point``, the NumPy observables)."""
import math

import numpy as np
import pytest

import rodjit
import custom_law  # noqa: F401  (registers the law "raise-test")
from rodjit.presets import load_preset
from rodjit.sweeps import ensemble
from rodjit.sweeps.batch import BatchResult
from rodjit.sweeps.ensemble import BatchTask, run_batch, split_bounces
from rodjit.sweeps.grid import Grid
from rodjit.sweeps.point import BOUNCE_COLUMNS, SUMMARY_COLUMNS, PointTask, run_point

TIMINGS = ("wall_time", "compile_time", "run_time")
BASE = rodjit.Config().override({"time.t_end": 0.8})
# lift-off, a contact still running at the end (open), no impact yet, no diagnostics
# (undefined), and a point that fails (fixed verlet steps at -100 m/s): several compiled
# families in one batch
MIXED = {"time.t_end": [0.8, 0.52, 0.05], "output.diagnostics_interval": [1e-3, 0.0],
         "initial.velocity": [0.0, -100.0]}
PAPER = {"rod.mu": [0.0, 25.0, 100.0], "floor.kappa_b": [1000.0, 3000.0],
         "floor.beta": [0.03, 0.12]}


def _equal(x, y) -> bool:
    if isinstance(x, float) or isinstance(y, float):
        return (math.isnan(x) and math.isnan(y)) or x == y
    return x == y


def _check_against_points(base, spec, **point_changes):
    grid = Grid.from_spec(spec)
    idx = np.arange(len(grid))
    batch = run_batch(BatchTask(idx, base, grid, ()))
    assert isinstance(batch, BatchResult)
    assert list(batch.values) == list(SUMMARY_COLUMNS)
    assert list(batch.bounces) == list(BOUNCE_COLUMNS)
    tables = split_bounces(batch)
    for k, i in enumerate(idx):
        ref = run_point(PointTask(int(i), grid.config(base, int(i)), None, ()))
        for name in SUMMARY_COLUMNS:
            if name not in TIMINGS:
                assert _equal(batch.values[name][k], ref.values[name]), (i, name)
        assert batch.bounce_count[k] == ref.bounces["t_impact"].size
        for name in BOUNCE_COLUMNS:
            a, b = tables[k][name], np.asarray(ref.bounces[name])
            assert a.dtype == b.dtype, name
            assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), (i, name)
    assert np.all(batch.values["run_time"] >= 0)
    return batch


def test_the_papers_grid_equals_its_points_run_alone_to_the_bit():
    batch = _check_against_points(load_preset("paper-mu100"), PAPER)
    status = set(batch.values["impact_status"])
    assert {"lift-off", "no lift-off"} <= status
    assert np.all(batch.values["steps"] > 100)


def test_every_first_contact_status_and_a_failing_point_equal_the_per_point_path():
    batch = _check_against_points(BASE.override({"time.dt": 1e-3,
                                                 "time.integrator": "verlet"}), MIXED)
    v = batch.values
    assert {"lift-off", "open", "no impact", "undefined"} <= set(v["impact_status"])
    assert "failed" in set(v["status"]) and "completed" in set(v["status"])
    failed = v["status"] == "failed"
    assert all("fixed step time.dt = 0.001 failed" in m for m in v["message"][failed])


@pytest.mark.slow
def test_a_point_that_cannot_start_fails_alone_with_the_per_point_message():
    base = BASE.override({"rod.law": "raise-test"})
    batch = _check_against_points(base, {"rod.kappa": [100.0, 13.0, 50.0]})
    assert list(batch.values["status"]) == ["completed", "failed", "completed"]
    assert batch.values["message"][1] == "ValueError: this law refuses rod.kappa = 13"


def test_a_point_with_more_bounces_than_the_batch_holds_goes_on_and_keeps_them_all(
        monkeypatch):
    """A call returns when the batch's bounce rows are full, and the next goes on with the
    point where it stopped: every bounce row is kept, each row and table equal the
    per-point path's, and no point runs twice (nor on the per-point path)."""
    monkeypatch.setattr(ensemble, "BOUNCE_ROWS", 1)     # room for one row a point
    monkeypatch.setattr(ensemble, "run_point", None)    # never called
    calls = []
    take = ensemble.decode.take_rows
    monkeypatch.setattr(ensemble.decode, "take_rows",
                        lambda *a, **k: calls.append(1) or take(*a, **k))
    batch = _check_against_points(BASE.override({"time.t_end": 2.0}),
                                  {"initial.height": [0.1, 0.2]})
    assert batch.bounce_count.sum() > 2 * len(batch.bounce_count)   # more than it holds
    assert len(calls) > 2                  # calls that returned with the rows full


def test_pool_dask_and_inline_give_the_same_table(tmp_path):
    base = load_preset("paper-mu100").override({"time.t_end": 1.0})
    grid = {"rod.mu": [0.0, 50.0, 100.0], "floor.beta": [0.03, 0.1]}
    inline = rodjit.sweep(base, grid, scheduler="inline", batch_size=4)
    pool = rodjit.sweep(base, grid, jobs=2, batch_size=2, output=tmp_path / "p.h5")
    dask = rodjit.sweep(base, grid, scheduler="local", jobs=2, output=tmp_path / "d.h5")
    for other in (pool, rodjit.load_sweep(tmp_path / "p.h5"), dask,
                  rodjit.load_sweep(tmp_path / "d.h5")):
        for name in SUMMARY_COLUMNS:
            if name in TIMINGS:
                continue
            x, y = np.asarray(inline[name]), np.asarray(other[name])
            if x.dtype.kind == "f":
                assert np.array_equal(x, y, equal_nan=True), name
            else:
                assert list(x) == list(y), name
        for i in range(6):
            a, b = inline.bounces(i), other.bounces(i)
            for name in BOUNCE_COLUMNS:
                assert np.array_equal(np.asarray(a[name]), np.asarray(b[name]),
                                      equal_nan=np.asarray(a[name]).dtype.kind == "f"), name


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, 10**9])
def test_a_batch_size_out_of_range_is_refused(bad):
    with pytest.raises(ValueError, match=r"batch_size = .* is out of range \(a whole number "
                                         r"from 1 to 100000\)"):
        rodjit.sweep(BASE, {"rod.mu": [0.0]}, batch_size=bad)


def test_a_batched_workers_start_loads_the_batch_kernel(monkeypatch):
    """``start_worker(cfg, batched=True)`` loads the batch kernel of cfg's family (the JIT's
    here), not a run's loop: the worker's first batch then loads nothing."""
    from rodjit.driver.run import Run
    from rodjit.sweeps.workers import start_worker

    monkeypatch.setattr(ensemble, "_LOADED", set())
    runs = []
    monkeypatch.setattr("rodjit.sweeps.workers.Run", lambda cfg: runs.append(cfg) or Run(cfg))
    cfg = load_preset("paper-mu100").override({"time.t_end": 0.5})
    info = start_worker(cfg, batched=True)
    assert info["pid"] > 0 and not runs
    assert len(ensemble._LOADED) == 1
    first = run_batch(BatchTask(np.array([0]), cfg, Grid.from_spec({"rod.mu": [10.0]}), ()))
    assert first.values["compile_time"][0] == 0.0 and first.values["status"][0] == "completed"
    start_worker(cfg)                     # the per-point path: a run's loop
    assert len(runs) == 1


def test_batches_start_small_then_carry_the_measured_cost_and_shrink_at_the_end():
    base = load_preset("paper-mu100")
    grid = Grid.from_spec({"rod.mu": "linspace(0, 100, 1000)"})
    timing = {"points": 0, "wall": 0.0}
    gen = ensemble.batches(np.arange(1000), base, grid, (), None, timing, 2)
    sizes = [len(next(gen).index) for _ in range(4)]
    assert sizes == [ensemble.FIRST_BATCH] * 4 and ensemble.FIRST_BATCH <= 2
    timing.update(points=100, wall=1.0)              # 10 ms a point
    k = int(ensemble.BATCH_SECONDS / 0.01)
    assert len(next(gen).index) == k
    rest = [t.index for t in gen]
    seen = np.concatenate([np.arange(4 * ensemble.FIRST_BATCH + k), *rest])
    assert np.array_equal(seen, np.arange(1000))     # every point once, in order
    left = 1000 - 4 * ensemble.FIRST_BATCH - k
    for idx in rest:                                 # never more than a quarter of what
        assert len(idx) <= max(1, -(-left // 4))     # is left: the workers end together
        left -= len(idx)
    assert len(rest[-1]) == 1
    fixed = ensemble.batches(np.arange(10), base, grid, (), 4, timing, 2)
    assert [len(t.index) for t in fixed] == [4, 4, 2]
