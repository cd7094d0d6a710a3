"""The records floor: one bounce table and one stats dict for every sink and reader."""
import numpy as np

import rodjit
import rodjit.output.run_writer
import rodjit.records.result
import rodjit.sweeps.point
from rodjit.driver.run import Run
from rodjit.records import bounces as B
from rodjit.records.columns import BOUNCE_COLUMNS, BOUNCE_ROW_COLUMNS
from rodjit.records.stats import run_stats
from rodjit.sweeps.point import PointTask, run_point


def rows(n, start=0.0):
    """``n`` bounce rows of the loop's layout, every entry distinct."""
    return start + np.arange(n * len(BOUNCE_ROW_COLUMNS), dtype=float).reshape(n, -1)


def test_bounce_table_columns_dtypes_and_the_pending_bounce():
    blocks = [rows(2), rows(1, 100.0)]
    blocks[0][0, BOUNCE_ROW_COLUMNS.index("ambiguous")] = 0.0    # the loop writes 0 or 1
    pending = (rows(1, 200.0)[0], True)
    t = B.bounce_table(blocks, pending)
    assert tuple(t) == BOUNCE_COLUMNS and BOUNCE_COLUMNS[-1] == "open"
    assert t["n_episodes"].dtype == np.int64 and t["open"].dtype == bool
    assert t["ambiguous"].dtype == bool
    assert all(t[c].dtype == np.float64 for c in BOUNCE_ROW_COLUMNS
               if c not in ("n_episodes", "ambiguous"))
    assert t["open"].tolist() == [False, False, False, True]
    # the row's flag, and the pending bounce always (it may not be over)
    assert t["ambiguous"].tolist() == [False, True, True, True]
    whole = np.vstack(blocks + [pending[0][None, :]])
    for j, c in enumerate(BOUNCE_ROW_COLUMNS):
        if c not in ("ambiguous", "restitution_energy"):
            assert np.array_equal(t[c], whole[:, j].astype(t[c].dtype)), c
    e_energy = whole[:, BOUNCE_ROW_COLUMNS.index("restitution_energy")]
    assert np.array_equal(t["restitution_energy"][:-1], e_energy[:-1])
    assert np.isnan(t["restitution_energy"][-1])             # the pending bounce
    blocks[0][:] = -1.0                          # the table owns its arrays
    assert t["t_impact"][0] == 0.0
    closed = B.bounce_table(blocks[1:], (rows(1)[0], False))
    assert closed["open"].tolist() == [False, False]   # a pending bounce need not be open
    assert closed["ambiguous"].tolist() == [True, True]


def test_empty_bounces_have_the_columns_and_dtypes_of_a_full_table():
    empty, full = B.empty_bounces(), B.bounce_table([rows(3)])
    assert tuple(empty) == tuple(full)
    assert all(empty[c].shape == (0,) and empty[c].dtype == full[c].dtype for c in full)


def mid_episode_config():
    """A run that stops inside a contact episode: its last bounce is pending and open."""
    res = rodjit.simulate(rodjit.Config().override({"time.t_end": 1.0}))
    i = int(np.argmax(res.episodes["t_end"] - res.episodes["t_start"]))
    t_end = 0.5 * (res.episodes["t_start"][i] + res.episodes["t_end"][i])
    return rodjit.Config().override({"time.t_end": t_end})


def test_every_sink_builds_its_bounce_table_with_the_one_function(tmp_path, monkeypatch):
    """simulate's MemorySink, the run file's RunWriter and a sweep point's sink all call
    ``records.bounces.bounce_table`` and so agree, column for column and dtype for dtype,
    on a table that ends with an open bounce."""
    calls = {}

    def spy(module):
        real = module.bounce_table

        def counted(*args, **kwargs):
            calls[module.__name__] = calls.get(module.__name__, 0) + 1
            return real(*args, **kwargs)
        monkeypatch.setattr(module, "bounce_table", counted)

    for module in (rodjit.records.result, rodjit.output.run_writer, rodjit.sweeps.point):
        spy(module)
    cfg = mid_episode_config()
    mem = rodjit.simulate(cfg).bounces
    rodjit.run_to_file(cfg, tmp_path / "r.h5")
    disk = rodjit.load_file(tmp_path / "r.h5").bounces
    point = run_point(PointTask(0, cfg, None, ())).bounces
    assert set(calls) == {"rodjit.records.result", "rodjit.output.run_writer",
                          "rodjit.sweeps.point"}
    assert mem["open"][-1] and mem["open"].sum() == 1
    for other in (disk, point):
        assert tuple(other) == tuple(mem) == BOUNCE_COLUMNS
        for c in mem:
            assert other[c].dtype == mem[c].dtype, c
            assert np.array_equal(other[c], mem[c], equal_nan=mem[c].dtype.kind == "f"), c


def test_stats_of_a_run_and_of_its_file_agree(tmp_path, small_config):
    """``run_stats`` builds ``Result.stats`` from a live run and from a file's checkpoint."""
    mem = rodjit.simulate(small_config).stats
    rodjit.run_to_file(small_config, tmp_path / "r.h5")
    disk = rodjit.load_file(tmp_path / "r.h5").stats
    assert list(disk) == list(mem)
    for key in ("steps", "rejected_steps"):
        assert disk[key] == mem[key]
    run = Run(small_config)
    assert run.stats() == run_stats(steps=0, rejected=0, compile_time=0.0, run_time=0.0,
                                    nodes=small_config.rod.N + 1, scheme_counts=run.arrays.sstats)


def test_run_stats_fields():
    s = run_stats(steps=10, rejected=2, compile_time=1.5, run_time=0.5, nodes=4,
                  scheme_counts=np.array([7, 1]))
    assert s["wall_time"] == 2.0 and s["node_steps_per_second"] == 80.0
    assert s["steps"] == 10 and s["rejected_steps"] == 2
    assert run_stats(steps=0, rejected=0, compile_time=0.0, run_time=0.0, nodes=4,
                     scheme_counts=())["node_steps_per_second"] == 0.0
    from rodjit.stepping.schemes import SCHEME_STATS
    assert [s[name] for name in SCHEME_STATS] == [7, 1][:len(SCHEME_STATS)]
    # the counters are Python ints whether they come as an int64 array or a list
    listed = run_stats(steps=10, rejected=2, compile_time=1.5, run_time=0.5, nodes=4,
                       scheme_counts=[7, 1])
    assert listed == s and all(type(s[name]) is int for name in SCHEME_STATS)


def test_a_one_row_table_owns_its_arrays_too():
    """A single bounce row transposes to a contiguous view of its block; the table copies
    it all the same, so the sink's block and the table never share memory."""
    block = rows(1)
    t = B.bounce_table([block])
    block[:] = -1.0
    assert t["t_impact"][0] == 0.0
    assert not any(np.shares_memory(t[c], block) for c in BOUNCE_ROW_COLUMNS)


# the public names of records.observables before it was split by job, and their homes now
OBSERVABLES_NAMES = {
    "physics": ["Physics", "physics_of", "physics_for", "wave_speed", "flight_time",
                "lift_energy"],
    "contacts": ["energy_vibration", "merge_episodes", "flight_groups", "macroscopic_contacts",
                 "FirstImpact", "first_impact", "STATUSES"],
    "impact": ["TRACK_COLUMNS", "IMPACT_COLUMNS", "impact_values", "impact_line"],
    "observables": ["observables", "OBSERVABLES"],
}


def test_records_observables_still_exports_every_name_from_its_job_module():
    """``from rodjit.records.observables import X`` keeps working for every name it had,
    and gives the object of the module that now holds it (one definition, no copy)."""
    import importlib

    import rodjit.records.observables as obs

    for home, names in OBSERVABLES_NAMES.items():
        mod = importlib.import_module(f"rodjit.records.{home}")
        for name in names:
            assert name in obs.__all__, name
            assert getattr(obs, name) is getattr(mod, name), name
            if home != "observables":
                assert name in mod.__all__, name
    assert rodjit.observables is obs.observables
