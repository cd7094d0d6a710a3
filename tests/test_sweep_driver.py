"""rodjit.sweep: backends agree, the file layout, failures, dying workers, resume, memory."""
import math
import os
import signal
import subprocess
import sys
import threading
import tracemalloc

import h5py
import numpy as np
import pytest

import killer_law  # noqa: F401  (registers "kill-test", which kills its worker)
import rodjit
from rodjit.output import h5files, hdf5
from rodjit.sweeps import sweep_file
from rodjit.sweeps.executors import WORKER_ENV, ProcessPool
from rodjit.sweeps.grid import Grid
from rodjit.sweeps.point import BOUNCE_COLUMNS, SUMMARY_COLUMNS, PointTask, run_point

from conftest import assert_same_files

BASE = rodjit.Config().override({"time.t_end": 0.8})       # the fall and one impact
GRID = {"rod.mu": [0.0, 10.0], "floor.beta": [0.01, 0.05]}
TIMINGS = ("wall_time", "compile_time", "run_time")
FAILING = {"time.dt": 1e-3, "time.integrator": "verlet"}   # with initial.velocity = -100


def same_values(a, b, skip=TIMINGS):
    """Two tables (or column dicts) hold the same results, timings apart."""
    a = getattr(a, "columns", a)
    b = getattr(b, "columns", b)
    assert list(a) == list(b)
    for name in a:
        if name in skip:
            continue
        x, y = np.asarray(a[name]), np.asarray(b[name])
        if x.dtype.kind == "f":
            assert np.array_equal(x, y, equal_nan=True), name
        else:
            assert list(x) == list(y), name


@pytest.fixture(scope="module")
def inline_table():
    return rodjit.sweep(BASE, GRID, scheduler="inline")


def test_each_row_is_its_point_run_alone(inline_table):
    t = inline_table
    grid = Grid.from_spec(GRID)
    assert len(t) == 4 and t.status == "completed" and t.counts["completed"] == 4
    assert list(t.columns)[:2] == ["rod.mu", "floor.beta"]
    assert list(t.columns)[2:] == list(SUMMARY_COLUMNS)
    assert list(t["rod.mu"]) == [0.0, 0.0, 10.0, 10.0]
    assert list(t["floor.beta"]) == [0.01, 0.05, 0.01, 0.05]
    for i in range(len(t)):
        alone = run_point(PointTask(i, grid.config(t.base, i), None, ()))
        row = {name: t[name][i] for name in SUMMARY_COLUMNS}
        same_values({k: [v] for k, v in row.items()}, {k: [v] for k, v in alone.values.items()})
        for name in BOUNCE_COLUMNS:
            assert np.array_equal(t.bounces(i)[name], alone.bounces[name], equal_nan=True)
    assert t.config(3).rod.mu == 10.0 and t.config(3).floor.beta == 0.05


def test_process_pool_writes_the_same_table_to_the_file(tmp_path, inline_table):
    path = tmp_path / "sweep.h5"
    table = rodjit.sweep(BASE, GRID, output=path, jobs=2, command="test sweep")
    same_values(table, inline_table)
    assert table.stats["backend"] == "processes" and table.stats["jobs"] == 2
    assert table.stats["points_run"] == 4 and table.stats["worker_deaths"] == 0
    loaded = rodjit.load_sweep(path)
    same_values(loaded, inline_table)
    with h5py.File(path, "r") as f:
        a = f.attrs
        assert a["rodjit_kind"] == "sweep" and a["format_version"] == sweep_file.FORMAT_VERSION
        assert a["status"] == "completed" and a["command"] == "test sweep"
        assert rodjit.Config.from_toml_string(a["base_config_toml"]) == BASE.resolve()
        assert Grid.from_json(a["grid"]) == Grid.from_spec(GRID)
        assert list(a["grid_keys"]) == ["rod.mu", "floor.beta"] and a["n_points"] == 4
        s = f["summary"]
        # the dimension, then table order, then where each point's bounce rows are and
        # the digest that proves each row
        assert list(s) == ["point", "rod.mu", "floor.beta", *SUMMARY_COLUMNS,
                           "bounce_start", "bounce_count", "row_digest"]
        assert s["rod.mu"].dtype == np.float64 and s["steps"].dtype == np.int64
        assert h5py.check_string_dtype(s["status"].dtype)
        assert all(s[c].shape == (4,) for c in s)
        assert "points" not in f                # format 3: one bounce table for all points
        g = f["bounces"]
        assert list(g) == ["bounce", "point_index", *BOUNCE_COLUMNS]
        for i in range(4):
            start, count = int(s["bounce_start"][i]), int(s["bounce_count"][i])
            assert count == inline_table.bounces(i)["t_impact"].size
            rows = slice(start, start + count)
            assert np.all(g["point_index"][rows] == i)
            for name in BOUNCE_COLUMNS:
                assert np.array_equal(g[name][rows], inline_table.bounces(i)[name],
                                      equal_nan=True)
    df = rodjit.load_sweep(path).to_pandas()                # the README's one line
    assert list(df.columns) == list(loaded.columns) and len(df) == 4
    assert df.loc[3, "status"] == "completed" and df["steps"].dtype == np.int64
    ds = loaded.to_xarray()
    assert ds["restitution_first"].dims == ("mu", "beta")      # identifiers: ds.sel(mu=...)
    assert (ds["mu"].attrs["key"], ds["beta"].attrs["key"]) == ("rod.mu", "floor.beta")
    assert float(ds["steps"].sel({"mu": 10.0, "beta": 0.05})) == loaded["steps"][3]


@pytest.mark.slow
def test_a_failing_point_is_recorded_and_the_sweep_goes_on(tmp_path):
    base = BASE.override(FAILING)
    table = rodjit.sweep(base, {"initial.velocity": [0.0, -100.0, -1.0]}, scheduler="inline",
                         output=tmp_path / "s.h5")
    assert list(table["status"]) == ["completed", "failed", "completed"]
    assert "fixed step time.dt = 0.001 failed" in table["message"][1]
    assert table["message"][0] == "" and table["steps"][1] > 0
    assert table.status == "completed"
    assert "failed points (1):" in table.report() and "initial.velocity=-100" in table.report()
    assert rodjit.load_sweep(tmp_path / "s.h5")["status"][1] == "failed"


KILLER = {"rod.law": "kill-test"}
KILLER_GRID = {"rod.kappa": [100.0, 13.0], "initial.velocity": [0.0, -100.0]}


@pytest.mark.slow
def test_a_dying_worker_fails_its_point_only():
    grid = {"rod.kappa": [100.0, 50.0, 13.0], "rod.mu": [0.0, 1.0]}
    # batches of two: the last one kills its worker, runs again point by point, and each
    # of its points kills a worker again
    table = rodjit.sweep(BASE.override(KILLER), grid, jobs=2, batch_size=2)
    assert list(table["status"]) == ["completed"] * 4 + ["failed"] * 2
    for i in (4, 5):
        assert "worker process" in table["message"][i]
        assert "died while running this point (killed by SIGKILL)" in table["message"][i]
    assert table.stats["worker_deaths"] == 3
    assert np.all(table["steps"][:4] > 0)


@pytest.mark.slow
def test_points_waiting_behind_a_dying_point_run_elsewhere():
    """One worker, batches of two queued two deep: the batch of the two killers kills its
    worker, each of its points runs again alone and fails alone, and the batch queued
    behind it goes to a replacement worker."""
    table = rodjit.sweep(BASE.override(KILLER), {"rod.kappa": [13.0, 100.0],
                                                 "rod.mu": [0.0, 1.0]}, jobs=1)
    assert list(table["status"]) == ["failed", "failed", "completed", "completed"]
    assert table.stats["worker_deaths"] == 3


def test_workers_run_numba_single_threaded_with_kernels_loaded_before_the_first_point():
    before = {k: os.environ.get(k) for k in WORKER_ENV}
    task = PointTask(0, BASE, None, ())
    pool = ProcessPool(1, warm=BASE)
    results = [r for r in pool.results([task]) if r is not None]
    assert len(results) == 1 and results[0].status == "completed"
    assert results[0].worker["numba_threads"] == 1 and results[0].worker["pid"] != os.getpid()
    # loading the kernels (~0.3 s from the disk cache) happened at start-up, not in the point
    assert results[0].values["compile_time"] < 0.05 < pool.startup_time
    assert {k: os.environ.get(k) for k in WORKER_ENV} == before   # the caller's env restored
    assert pool.startup_time is not None and not pool.workers


def _interrupt_after(k):
    state = {"sent": False}

    def progress(p):
        if p.run >= k and not state["sent"]:
            state["sent"] = True
            os.kill(os.getpid(), signal.SIGINT)
    return progress


@pytest.mark.parametrize("scheduler", ["inline", "processes"])
def test_interrupt_keeps_finished_points_and_resume_runs_the_rest(tmp_path, inline_table,
                                                                  scheduler):
    path = tmp_path / "cut.h5"
    with pytest.raises(rodjit.SweepInterrupted) as info:
        rodjit.sweep(BASE, GRID, output=path, scheduler=scheduler, jobs=1,
                     progress=_interrupt_after(2))
    assert info.value.signum == signal.SIGINT
    assert str(info.value) == (f"interrupted by SIGINT after 2 of 4 points; continue with "
                               f"resume=True (output={str(path)!r})")
    assert info.value.output == str(path)
    cut = rodjit.load_sweep(path)
    assert cut.status == "interrupted"
    # the file keeps the command that continues it (file contents are a contract)
    assert cut.message == (f"interrupted by SIGINT after 2 of 4 points; continue with: "
                           f"rodjit sweep --resume -o {path}")
    assert list(cut["status"]) == ["completed", "completed", "pending", "pending"]
    same_values({k: v[:2] for k, v in cut.columns.items()},
                {k: v[:2] for k, v in inline_table.columns.items()})
    walls = cut["wall_time"][:2].copy()
    table = rodjit.sweep(output=path, resume=True, scheduler=scheduler, jobs=1)
    assert table.stats["points_run"] == 2 and table.status == "completed"
    final = rodjit.load_sweep(path)
    same_values(final, inline_table)
    assert np.array_equal(final["wall_time"][:2], walls)      # finished points were not rerun
    with h5py.File(path, "r") as f:
        assert "resumed (2 points to run)" in f.attrs["history"][-1]


def test_resume_reruns_failed_points_only(tmp_path, inline_table):
    path = tmp_path / "s.h5"
    rodjit.sweep(BASE, GRID, output=path, scheduler="inline")
    with h5py.File(path, "r+") as f:        # as if point 1 had failed
        s = f["summary"]
        s["status"][1] = "failed"
        s["message"][1] = "made to fail"
        for name in ("steps", "n_bounces", "n_complete_bounces", "bounce_count"):
            s[name][1] = 0                    # a failed point has no bounce rows
        s["bounce_start"][1] = -1
        values = {name: (s[name].asstr()[1:2] if h5py.check_string_dtype(s[name].dtype)
                         else s[name][1:2]) for name in SUMMARY_COLUMNS}
        s["row_digest"][1] = sweep_file.row_digests([1], values, [-1], [0], {
            name: f["bounces"][name][()] for name in f["bounces"]})[0]
    walls = rodjit.load_sweep(path)["wall_time"].copy()
    table = rodjit.sweep(BASE, GRID, output=path, resume=True, scheduler="inline")
    assert table.stats["points_run"] == 1
    same_values(rodjit.load_sweep(path), inline_table)
    now = rodjit.load_sweep(path)["wall_time"]
    assert now[1] != walls[1] and np.array_equal(np.delete(now, 1), np.delete(walls, 1))
    assert rodjit.sweep(output=path, resume=True).stats["points_run"] == 0


def test_a_live_sweeps_file_is_not_replaced(tmp_path):
    """A sweep file whose writer is alive (here: a sleeping process posing as it) is
    replaced neither by another sweep nor by a run, even with overwrite."""
    path = tmp_path / "live.h5"
    rodjit.sweep(BASE, {"rod.mu": [0.0]}, output=path, scheduler="inline")
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        with h5py.File(path, "r+") as f:
            f.attrs.update(status="running", **h5files.writer_attrs(proc.pid))
        before = path.read_bytes()
        with pytest.raises(hdf5.FileBusy, match="being written by a running rodjit process"):
            rodjit.sweep(BASE, {"rod.mu": [1.0]}, output=path, overwrite=True)
        with pytest.raises(hdf5.FileBusy, match="being written by a running rodjit process"):
            rodjit.run_to_file(BASE, path, overwrite=True)
        assert path.read_bytes() == before
    finally:
        proc.kill()
        proc.wait()
    assert len(rodjit.sweep(BASE, {"rod.mu": [1.0]}, output=path, overwrite=True)) == 1


def test_resume_refuses_another_grid_or_config(tmp_path):
    path = tmp_path / "s.h5"
    rodjit.sweep(BASE, GRID, output=path, scheduler="inline")
    before = path.read_bytes()
    with pytest.raises(ValueError, match="the grid differs from the one in"):
        rodjit.sweep(BASE, {"rod.mu": [0.0]}, output=path, resume=True)
    with pytest.raises(ValueError, match=r"the configuration differs .*\(rod.kappa\)"):
        rodjit.sweep(BASE.override({"rod.kappa": 50.0}), GRID, output=path, resume=True)
    with pytest.raises(ValueError, match="resume needs the sweep file"):
        rodjit.sweep(resume=True)
    assert path.read_bytes() == before


def test_bad_input_writes_nothing(tmp_path):
    out = tmp_path / "s.h5"
    runs = tmp_path / "runs"
    cases = [
        ({"grid": {"rod.mu": [-1.0]}}, r"rod.mu = -1.0 is out of range"),
        ({"grid": {"floor.beta": [0.1, 0.001], "initial.height": [-0.01]}},
         r"grid point 1 \(floor.beta=0.001 initial.height=-0.01\)"),
        ({"grid": GRID, "jobs": 0}, r"jobs = 0 is out of range \(a whole number >= 1\)"),
        ({"grid": GRID, "scheduler": "mpi"}, "scheduler = 'mpi' is not allowed"),
        ({"grid": None}, "a sweep needs a grid"),
        ({"grid": GRID, "output": tmp_path / "missing" / "s.h5"}, "does not exist"),
    ]
    for kwargs, message in cases:
        kwargs = {"output": out, "save_runs": runs, **kwargs}
        with pytest.raises(ValueError, match=message):
            rodjit.sweep(BASE, **kwargs)
    assert not out.exists() and not runs.exists()
    (tmp_path / "file").write_text("")
    with pytest.raises(ValueError, match="is not a directory"):
        rodjit.sweep(BASE, GRID, save_runs=tmp_path / "file")
    out.write_bytes(b"x")
    with pytest.raises(rodjit.OutputExists, match="already exists"):
        rodjit.sweep(BASE, GRID, output=out)
    with pytest.raises(TypeError, match="config must be a rodjit.Config"):
        rodjit.sweep({"rod.mu": 1.0}, GRID)


def test_save_runs_writes_each_points_run_file(tmp_path, inline_table):
    runs = tmp_path / "runs"
    table = rodjit.sweep(BASE, GRID, output=tmp_path / "s.h5", save_runs=runs, jobs=2)
    same_values(table, inline_table, skip=TIMINGS + ("run_file",))
    grid = Grid.from_spec(GRID)
    names = [grid.run_name(i) for i in range(len(grid))]
    assert sorted(p.name for p in runs.iterdir()) == names
    assert list(table["run_file"]) == names
    for i, name in enumerate(names):
        ref = tmp_path / f"ref{i}.h5"
        rodjit.run_to_file(grid.config(table.base, i), ref)
        assert_same_files(runs / name, ref)
    with h5py.File(tmp_path / "s.h5", "r") as f:
        assert f.attrs["save_runs"] == str(runs.resolve())
    with pytest.raises(ValueError, match=r"already holds '0_rod.mu=0_floor.beta=0.01.h5'; pass "
                                         r"overwrite=True"):
        rodjit.sweep(BASE, GRID, output=tmp_path / "t.h5", save_runs=runs)


def _peak_traced(n_values, tmp_path):
    tracemalloc.start()
    try:
        rodjit.sweep(BASE.override({"time.t_end": 0.05, "output.diagnostics_interval": 0.01}),
                     {"rod.mu": np.linspace(0, 1, n_values)}, output=tmp_path / f"{n_values}.h5",
                     jobs=2)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_memory_does_not_grow_with_the_number_of_points(tmp_path):
    """Python-level peak memory of the sweep's process: 400 points vs 40."""
    small = _peak_traced(40, tmp_path)
    large = _peak_traced(400, tmp_path)
    assert large - small < 2 * 2**20, (small, large)


@pytest.mark.slow
def test_dask_local_cluster_of_two_workers(tmp_path, inline_table):
    distributed = pytest.importorskip("distributed")

    table = rodjit.sweep(BASE, GRID, output=tmp_path / "d.h5", scheduler="local", jobs=2)
    same_values(table, inline_table)
    assert table.stats["backend"] == "dask LocalCluster (2 workers)"
    same_values(rodjit.load_sweep(tmp_path / "d.h5"), inline_table)
    # two points that kill their worker first: each worker holds two points, so both others
    # start beside a killer; only the killers fail (each dies again when re-run alone)
    t = rodjit.sweep(BASE.override({**FAILING, **KILLER}),
                     {"rod.kappa": [13.0, 100.0], "initial.velocity": [0.0, -100.0]},
                     scheduler="local", jobs=2)
    assert list(t["status"]) == ["failed", "failed", "completed", "failed"]
    assert "fixed step time.dt" in t["message"][3]
    for i in (0, 1):
        assert "the Dask worker process running this point died, also when it ran alone" \
            in t["message"][i]
        assert math.isnan(t["restitution_first"][i]) and t["steps"][i] == 0
    assert t["steps"][2] > 0 and t["steps"][3] > 0


@pytest.mark.slow     # a Dask cluster whose worker is killed, then each point alone (about a minute)
def test_dask_runs_short_points_several_to_a_task_and_isolates_a_killer_among_them(
        monkeypatch):
    """Batching given the durations (here: every point counts as far shorter than a task,
    whatever the machine's load), and the killer isolated among its batch."""
    pytest.importorskip("distributed")
    import rodjit.sweeps.dask_cluster as dask_cluster

    monkeypatch.setattr(dask_cluster, "TASK_SECONDS", 1e9)
    kappas = [100.0 + i for i in range(40)]
    kappas[25] = 13.0                      # kills its worker, inside a task of several points
    base = BASE.override({**KILLER, "time.t_end": 0.2})
    grid = {"rod.kappa": kappas}
    t = rodjit.sweep(base, grid, scheduler="local", jobs=2)
    # after the first timed point, tasks hold ceil(remaining / (2 tasks x 2 workers)) points
    assert t.stats["tasks"] < 40           # batched (without: 40 tasks, and re-runs)
    assert t.stats["worker_deaths"] >= 2   # in its task, then alone
    assert [i for i in range(40) if t["status"][i] != "completed"] == [25]
    assert "died, also when it ran alone" in t["message"][25]
    healthy = dict(grid, **{"rod.kappa": kappas[:25] + kappas[26:]})
    inline = rodjit.sweep(base, healthy, scheduler="inline")
    for name in ("steps", "n_bounces", "min_u0", "energy_error"):
        got = np.delete(np.asarray(t[name]), 25)
        assert np.array_equal(got, np.asarray(inline[name]), equal_nan=True), name


def test_an_existing_dask_cluster_by_address(tmp_path, inline_table, monkeypatch):
    distributed = pytest.importorskip("distributed")
    import logging

    import rodjit.sweeps.dask_cluster as dask_cluster

    monkeypatch.setattr(dask_cluster, "CONNECT_TIMEOUT", 1.0)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=logging.ERROR,
                                  scheduler_kwargs={"dashboard_address": ":0"}) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tcp://")
        table = rodjit.sweep(BASE, GRID, output=tmp_path / "d.h5", scheduler=address)
        assert table.stats["backend"] == f"dask {address}" and table.stats["jobs"] == 2
        same_values(table, inline_table)
        assert len(cluster.scheduler_info["workers"]) == 2     # the cluster is left running
    with pytest.raises(ValueError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        rodjit.sweep(BASE, GRID, output=tmp_path / "e.h5", scheduler="tcp://127.0.0.1:9")
    assert not (tmp_path / "e.h5").exists()


def test_progress_reports_points_failures_and_time_left():
    seen = []
    base = BASE.override(FAILING)
    rodjit.sweep(base, {"initial.velocity": [0.0, -100.0, -1.0]}, scheduler="inline",
                 progress=seen.append, batch_size=1)
    done = [(p.done, p.failed, p.total) for p in seen]
    assert done == [(1, 0, 3), (2, 1, 3), (3, 1, 3)]
    seen.clear()       # batches (of two, then one: the default for one job) report each
    rodjit.sweep(base, {"initial.velocity": [0.0, -100.0, -1.0]}, scheduler="inline",
                 progress=seen.append)
    assert [(p.done, p.failed, p.total) for p in seen] == [(2, 1, 3), (3, 1, 3)]
    assert seen[-1].eta == 0.0 and seen[0].eta > 0 and seen[0].elapsed > 0


@pytest.mark.slow
def test_the_same_sweep_with_jit_disabled(tmp_path):
    """A sweep in a process with NUMBA_DISABLE_JIT=1 (the kernels as plain Python) writes
    the same table as the compiled one, to rounding."""
    import subprocess
    import sys

    over = {"time.t_end": 0.5, "rod.N": 4}
    grid = {"rod.mu": [0.0, 1.0]}
    path = tmp_path / "nojit.h5"
    code = ("import rodjit; rodjit.sweep(rodjit.Config().override(%r), %r, output=%r, "
            "scheduler='inline')" % (over, grid, str(path)))
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=600)
    plain = rodjit.load_sweep(path)
    compiled = rodjit.sweep(rodjit.Config().override(over), grid, scheduler="inline")
    assert list(plain["steps"]) == list(compiled["steps"])
    # to rounding, not bit for bit: compiled kernels fuse multiply-adds (rodjit._jit)
    for name in ("restitution_first", "min_u0", "max_floor_force"):
        assert np.allclose(plain[name], compiled[name], rtol=1e-12, atol=0, equal_nan=True)
    # the energy error is a relative difference of O(1) energies: rounding is 1e-12 absolute
    assert np.allclose(plain["energy_error"], compiled["energy_error"], rtol=0, atol=1e-12)


def test_a_reader_holding_the_file_delays_writes_but_loses_nothing(tmp_path, monkeypatch,
                                                                  inline_table):
    """Another process keeps the sweep file open (HDF5 locks it): batch writes wait and
    retry, and the finished file holds every point."""
    import subprocess
    import sys

    path = tmp_path / "s.h5"
    busy = []
    write = sweep_file.write_results

    def counting(*args, **kwargs):
        try:
            return write(*args, **kwargs)
        except rodjit.output.hdf5.FileBusy:
            busy.append(1)
            raise
    monkeypatch.setattr(sweep_file, "write_results", counting)
    reader = {}

    def progress(p):
        if "proc" not in reader:
            code = ("import h5py, sys, time; f = h5py.File(sys.argv[1], 'r'); print('open', "
                    "flush=True); time.sleep(2.5); f.close()")
            reader["proc"] = subprocess.Popen([sys.executable, "-c", code, str(path)],
                                              stdout=subprocess.PIPE, text=True)
            assert reader["proc"].stdout.readline().strip() == "open"
    table = rodjit.sweep(BASE, GRID, output=path, scheduler="inline", progress=progress,
                         flush_interval=1e-3)
    reader["proc"].wait(timeout=30)
    assert busy, "no write met the reader's lock"
    same_values(rodjit.load_sweep(path), inline_table)
    assert table.status == "completed"


@pytest.mark.parametrize("resume", [False, True])
def test_a_signal_while_the_sweep_file_layout_is_written_waits_for_the_layout(
        tmp_path, resume):
    """SIGINT in the middle of writing the sweep file's layout (or its reopening) is held
    until the layout is whole, then acts: KeyboardInterrupt, not an h5py TypeError from a
    handler raising inside its callbacks; a new file is removed, a reopened one stays
    resumable.  Run in a fresh interpreter: in a test worker that had run many files first,
    the signal was not seen (the whole suite only, in whichever worker drew this file)."""
    # Python's own SIGINT handler, even where the suite was started with SIGINT ignored
    # (a background job of a non-interactive shell), which the child would inherit
    code = ("import signal, sys; sys.path[:0] = [sys.argv[1]]\n"
            "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
            "import test_sweep_driver as t\n"
            "t._signal_during_layout(sys.argv[2], sys.argv[3] == 'True')\nprint('ok')\n")
    here = os.path.dirname(os.path.abspath(__file__))
    p = subprocess.run([sys.executable, "-c", code, here, str(tmp_path), str(resume)],
                       capture_output=True, text=True, timeout=600,
                       cwd=os.path.dirname(here))
    assert p.returncode == 0 and p.stdout.strip().endswith("ok"), p.stderr


def _signal_during_layout(tmp: str, resume: bool) -> None:
    """The body of the test above, in its own process."""
    from pathlib import Path

    path = Path(tmp) / "s.h5"
    if resume:                                        # a sweep cut before its first point
        sweep_file.create(path, BASE, Grid.from_spec({"rod.mu": [0.0]}), command="test",
                          attrs={"save_runs": "", "scheduler": "inline", "jobs": 1})
        sweep_file.finish(path, "interrupted")
    name = "reopen" if resume else "create"
    original = getattr(sweep_file, name)
    written = []

    seen = {}

    def signalled(*args, **kwargs):
        # what the signal meets, said if it is not seen (the handler, the blocked signals,
        # the threads that could take it)
        seen.update(handler=signal.getsignal(signal.SIGINT),
                    blocked=signal.pthread_sigmask(signal.SIG_BLOCK, []),
                    threads=[t.name for t in threading.enumerate()])
        os.kill(os.getpid(), signal.SIGINT)          # lands while h5py writes attributes
        written.append(original(*args, **kwargs))
        return written[-1]

    setattr(sweep_file, name, signalled)
    try:
        with pytest.raises(KeyboardInterrupt):
            rodjit.sweep(BASE, {"rod.mu": [0.0]}, output=path, resume=resume,
                         scheduler="inline")
            raise AssertionError(f"the signal was not seen: {seen}, "
                                 f"SIGINT then {signal.getsignal(signal.SIGINT)}")
    finally:
        setattr(sweep_file, name, original)
    assert len(written) == 1                          # the layout was written to its end
    if resume:
        table = rodjit.sweep(BASE, {"rod.mu": [0.0]}, output=path, resume=True,
                             scheduler="inline")
        assert table.status == "completed" and table.counts["completed"] == 1
    else:
        assert not path.exists()


def test_a_sweep_whose_every_point_failed_ends_failed_with_the_first_cause(tmp_path):
    path = tmp_path / "s.h5"
    with pytest.raises(rodjit.SweepFailed) as info:
        rodjit.sweep(BASE.override({**FAILING, "initial.velocity": -100.0}),
                     {"rod.mu": [0.0, 1.0]}, scheduler="inline", output=path)
    message = str(info.value)
    assert message.startswith("every point of the sweep failed (2); the first: rod.mu=0")
    assert "fixed step time.dt = 0.001 failed" in message
    assert info.value.table.status == "failed" and info.value.table.message == message
    on_disk = rodjit.load_sweep(path)
    assert on_disk.status == "failed" and on_disk.message == message
    with h5py.File(path, "r") as f:
        assert f.attrs["status"] == "failed"


_SWEEP_SCRIPT = """\
import rodjit
if __name__ == "__main__":
    t = rodjit.sweep(rodjit.Config().override({"time.t_end": 0.2}), {"rod.mu": [0, 1]},
                     jobs=2)
    print("completed", t.counts["completed"])
"""


def _python(args, tmp_path, stdin=None):
    return subprocess.run([sys.executable, *args], input=stdin, capture_output=True,
                          text=True, timeout=600, cwd=tmp_path)


def test_a_script_read_from_stdin_gets_missing_main_guard_before_any_worker(tmp_path):
    """Spawned workers import the main script again by its path, which for ``python3 -``
    is ``<stdin>``: every worker would die of FileNotFoundError. The sweep says so first."""
    r = _python(["-"], tmp_path, stdin=_SWEEP_SCRIPT)
    assert r.returncode == 1 and "completed" not in r.stdout
    last = r.stderr.strip().splitlines()[-1]
    assert last.startswith("rodjit.sweeps.main_guard.MissingMainGuard: ")
    assert "standard input" in last and "save the script to a file" in last
    assert "FileNotFoundError" not in r.stderr and "<stdin>" not in r.stderr.replace(
        'File "<stdin>"', "")


def test_python_c_and_a_script_file_sweep_with_workers(tmp_path):
    """``python3 -c`` has no main script to import again (as a notebook): no guard needed."""
    assert _python(["-c", _SWEEP_SCRIPT], tmp_path).stdout.split() == ["completed", "2"]
    (tmp_path / "s.py").write_text(_SWEEP_SCRIPT)
    assert _python(["s.py"], tmp_path).stdout.split() == ["completed", "2"]


def test_a_main_module_no_worker_can_read_again_is_refused(monkeypatch, tmp_path):
    from rodjit.sweeps import main_guard

    main = type(sys)("__main__")
    main.__file__ = str(tmp_path / "gone.py")        # deleted since it started
    main.__spec__ = None
    monkeypatch.setitem(sys.modules, "__main__", main)
    with pytest.raises(rodjit.MissingMainGuard, match="gone.py.*which is not a file"):
        main_guard.check_main()
    (tmp_path / "gone.py").write_text("x = 1\n")
    main_guard.check_main()                          # a file: its guard is checked instead
