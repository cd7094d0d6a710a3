"""The run file layout (the public contract), its reader, and the checkpoint slots."""
import h5py
import numpy as np
import pytest

import rodjit
from rodjit.output import hdf5
from rodjit.stepping import layout as L

from conftest import final_state


def _mid_episode_t_end():
    """An end time inside the first contact episode: the run stops with a bounce open."""
    res = rodjit.simulate(rodjit.Config().override({"time.t_end": 1.0}))
    i = int(np.argmax(res.episodes["t_end"] - res.episodes["t_start"]))
    return 0.5 * (res.episodes["t_start"][i] + res.episodes["t_end"][i])


@pytest.mark.parametrize("t_end, over", [
    (1.0, {}), ("mid-episode", {}),
    pytest.param(0.5, {"rod.N": 200, "output.snapshot_interval": 1e-3},
                 marks=pytest.mark.slow),   # many whole chunks of u, v
    pytest.param(0.5, {"rod.N": 200, "output.snapshot_interval": 1e-3,
                       "output.compression": "gzip"}, marks=pytest.mark.slow),
], ids=["default", "mid-episode", "N200", "N200-gzip"])
def test_file_equals_simulate_bit_for_bit(tmp_path, t_end, over):
    t_end = _mid_episode_t_end() if t_end == "mid-episode" else t_end
    cfg = rodjit.Config().override({"time.t_end": t_end, **over})
    mem = rodjit.simulate(cfg)
    rodjit.run_to_file(cfg, tmp_path / "r.h5")
    disk = rodjit.load_file(tmp_path / "r.h5")
    for name in ("x", "t", "u", "v", "u_final", "v_final"):
        assert np.array_equal(getattr(disk, name), getattr(mem, name)), name
    for table in ("diagnostics", "episodes", "bounces"):
        a, b = getattr(disk, table), getattr(mem, table)
        assert sorted(a) == sorted(b)
        for col in b:
            assert a[col].dtype == b[col].dtype, (table, col)
            assert np.array_equal(a[col], b[col], equal_nan=a[col].dtype.kind == "f"), col
    assert disk.t_final == mem.t_final and disk.energy0 == mem.energy0
    assert disk.dissipated == mem.dissipated
    assert disk.stats["steps"] == mem.stats["steps"]
    assert disk.config == mem.config == cfg.resolve() and disk.status == "completed"
    assert disk.config.choice == mem.config.choice
    if t_end != 1.0:   # stopped in contact: the last bounce is listed, flagged open
        assert disk.bounces["open"][-1] and np.isnan(disk.bounces["restitution"][-1])


def test_layout_attributes_and_datasets(tmp_path):
    cfg = rodjit.Config().override({"time.t_end": 0.6, "rod.N": 7})
    rodjit.run_to_file(cfg, tmp_path / "r.h5", command="rodjit run test")
    with h5py.File(tmp_path / "r.h5", "r") as f:
        a = f.attrs
        assert a["rodjit_kind"] == "run" and a["format_version"] == hdf5.FORMAT_VERSION
        assert a["rodjit_version"] == rodjit.__version__
        assert a["command"] == "rodjit run test"
        assert a["status"] == "completed" and a["message"] == ""
        # the configuration as it ran ("auto" resolved), and why
        assert rodjit.Config.from_toml_string(a["config_toml"]) == cfg.resolve()
        assert a["integrator_choice"] == cfg.resolve().choice
        assert a["created"].startswith("20") and "T" in a["created"]
        n1 = cfg.rod.N + 1
        assert np.array_equal(f["snapshots/x"][()], np.arange(n1) / cfg.rod.N)   # format 2
        for group, cols in hdf5.TABLES.items():
            lengths = {f[group][c].shape[0] for c in cols}
            assert len(lengths) == 1, group
            for c in cols:
                ds = f[group][c]
                assert ds.maxshape[0] is None and ds.chunks is not None, (group, c)
        u = f["snapshots/u"]
        assert u.shape[1] == n1 and u.chunks[0] >= 1000   # a chunk holds many snapshots
        assert f["snapshots/step"].dtype == np.int64
        assert f["bounces/n_episodes"].dtype == np.int64 and f["bounces/open"].dtype == np.int8
        assert set(f["diagnostics"]) == set(L.DIAG_COLUMNS)
        assert set(f["bounces"]) == set(L.BOUNCE_ROW_COLUMNS) | {"open"}
        assert set(f["episodes"]) == {"t_start", "t_end"}
        # steps land exactly on the output grid t0 + k * interval
        t = f["snapshots/t"][()]
        assert np.array_equal(t, np.arange(t.size) * cfg.output.snapshot_interval)
        # the checkpoint names its entries and matches the tables (the pending bounce aside)
        ck = hdf5.read_checkpoint(f)
        slot = f[f"checkpoint/slot{f['checkpoint/current'][()]}"]
        assert list(slot["clock"].attrs["names"]) == list(hdf5.CLOCK_NAMES)
        assert ck["clock"][L.T] == 0.6 and ck["count"][L.STARTED] == 1
        for group in ("snapshots", "diagnostics", "episodes"):
            assert ck["lengths"][group] == f[group][hdf5.TABLES[group][0]].shape[0]
        assert ck["lengths"]["bounces"] == ck["count"][L.BOUNCES_TOTAL]


@pytest.mark.parametrize("compression", ["gzip", "lzf", "none"])
def test_layout_objects_are_stored_as_h5py_stores_them(tmp_path, compression):
    """The layout makes its attributes and most columns with low-level calls (cheaper): each
    attribute has the type and shape h5py gives the same value, each link the encoding of
    h5py's, and every column of a table the dtype and creation properties h5py gives it."""
    path = tmp_path / "r.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.2, "rod.N": 7,
                                                 "output.compression": compression}), path)
    with h5py.File(path, "r") as f, h5py.File(tmp_path / "ref.h5", "w") as ref:
        ref.create_dataset("probe", data=0)
        cset = ref.id.links.get_info(b"probe").cset
        objects = [("/", f)]
        f.visititems(lambda name, obj: objects.append((name, obj)))
        ref.attrs["text"], ref.attrs["texts"], ref.attrs["int"] = "a", ["a", "b"], 1
        as_h5py = {kind: ref.attrs.get_id(kind).get_type() for kind in ("text", "int")}
        assert ref.attrs.get_id("texts").get_type() == as_h5py["text"]
        for name, obj in objects:
            for key in obj.attrs:
                if key in ("DIMENSION_LIST", "REFERENCE_LIST", "CLASS", "NAME"):
                    continue                       # written by HDF5's dimension scale API
                value, attr = obj.attrs[key], obj.attrs.get_id(key)
                probe = f"{name}:{key}"            # as h5py stores it (flags: int8 arrays)
                ref.attrs[probe] = value
                same = ref.attrs.get_id(probe)
                assert attr.get_type() == same.get_type(), (name, key)
                assert attr.shape == same.shape, (name, key)
                if isinstance(value, (str, np.integer)):
                    kind = "int" if isinstance(value, np.integer) else "text"
                    assert attr.get_type() == as_h5py[kind], (name, key)
                if key in ("history", "names"):
                    assert attr.shape == (len(value),) and all(isinstance(v, str) for v in value)
            if name != "/":
                parent = f[name.rsplit("/", 1)[0]] if "/" in name else f
                info = parent.id.links.get_info(name.rsplit("/", 1)[-1].encode())
                assert info.cset == cset, name
        for group, cols in hdf5.TABLES.items():
            for c in cols:
                ds = f[group][c]
                made = ref.create_dataset(f"{group}/{c}", shape=(0,) + ds.shape[1:],
                                          maxshape=(None,) + ds.shape[1:], chunks=ds.chunks,
                                          dtype=ds.dtype, compression=ds.compression,
                                          compression_opts=ds.compression_opts,
                                          shuffle=ds.shuffle)
                assert _creation(ds) == _creation(made), (group, c)
                assert ds.id.get_type() == made.id.get_type(), (group, c)


def _creation(ds):
    """A dataset's creation properties that matter: chunks, filters and their parameters,
    fill and allocation times, time tracking."""
    p = ds.id.get_create_plist()
    return (p.get_chunk(), [p.get_filter(i)[:3] for i in range(p.get_nfilters())],
            p.get_fill_time(), p.get_alloc_time(), p.get_obj_track_times(), p.get_layout())


@pytest.mark.parametrize("compression", ["gzip", "lzf", "none"])
def test_compression(tmp_path, compression):
    cfg = rodjit.Config().override({"time.t_end": 0.3, "output.compression": compression})
    rodjit.run_to_file(cfg, tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5", "r") as f:
        expected = None if compression == "none" else compression
        for group, cols in hdf5.TABLES.items():
            for c in cols:
                assert f[group][c].compression == expected, (group, c)
                assert f[group][c].shuffle == (expected is not None), (group, c)
    assert rodjit.load_file(tmp_path / "r.h5").u.shape == (61, 6)


def test_xarray_sees_time_coordinates(tmp_path, small_config):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    path = tmp_path / "r.h5"
    rodjit.run_to_file(small_config, path)
    res = rodjit.load_file(path)
    with xr.open_dataset(path, group="snapshots", engine="h5netcdf") as ds:
        assert ds["u"].dims == ("t", "x")
        assert np.array_equal(ds["t"].values, res.t)
        assert np.array_equal(ds["x"].values, res.x)
        assert np.array_equal(ds["u"].sel(t=0.5).values, res.u[res.t == 0.5][0])
    with xr.open_dataset(path, group="diagnostics", engine="h5netcdf") as ds:
        assert ds["energy_total"].dims == ("t",)
        assert np.array_equal(ds["energy_total"].values, res.diagnostics["energy_total"])
    with xr.open_dataset(path, group="bounces", engine="h5netcdf") as ds:
        assert np.array_equal(ds["t_impact"].values, res.bounces["t_impact"])


def test_checkpoint_slots_alternate_and_stay_valid(tmp_path, small_config):
    from rodjit.driver.run import Run

    run = Run(small_config)
    writer = hdf5.create_run_file(tmp_path / "r.h5", run.config, run, command="test")
    try:
        assert writer.current == 0                     # a checkpoint exists from the start
        run.start(writer)
        seen = []
        while run.advance(writer, max_steps=30) != L.DONE:
            writer.save(run)
            seen.append(writer.current)
            f = writer.file
            other = f[f"checkpoint/slot{1 - writer.current}/lengths"][()]
            now = f[f"checkpoint/slot{writer.current}/lengths"][()]
            assert np.all(other <= now)                # the previous slot is kept intact
            for group, n in zip(hdf5.TABLES, now):
                assert f[group][hdf5.TABLES[group][0]].shape[0] == n
        assert seen[:4] == [1, 0, 1, 0]
    finally:
        writer.close(run, "completed")
    assert final_state(tmp_path / "r.h5")["clock"][L.T] == 1.0


def test_not_a_run_file(tmp_path):
    text = tmp_path / "notes.txt"
    text.write_text("hello")
    with pytest.raises(hdf5.NotARunFile, match="not an HDF5 file"):
        rodjit.load_file(text)
    with pytest.raises(hdf5.NotARunFile, match="does not exist"):
        rodjit.load_file(tmp_path / "missing.h5")
    with h5py.File(tmp_path / "plain.h5", "w") as f:
        f["x"] = 1
    with pytest.raises(hdf5.NotARunFile, match="no 'rodjit_kind' attribute"):
        rodjit.load_file(tmp_path / "plain.h5")
    with h5py.File(tmp_path / "sweep.h5", "w") as f:
        f.attrs["rodjit_kind"] = "sweep"
    with pytest.raises(hdf5.NotARunFile, match="'sweep' file, not a run file"):
        rodjit.load_file(tmp_path / "sweep.h5")


def test_layout_names_cover_the_stepper_arrays():
    assert len(hdf5.CLOCK_NAMES) == L.CLOCK_SIZE and hdf5.CLOCK_NAMES[L.T] == "t"
    assert len(hdf5.COUNT_NAMES) == L.COUNT_SIZE and hdf5.COUNT_NAMES[L.STEP] == "step"
    assert len(hdf5.EV_NAMES) == L.EV_SIZE and hdf5.EV_NAMES[L.IN_CONTACT] == "in_contact"
    assert len(set(hdf5.CLOCK_NAMES + hdf5.COUNT_NAMES + hdf5.EV_NAMES)) == (
        L.CLOCK_SIZE + L.COUNT_SIZE + L.EV_SIZE)


def test_no_checkpoint_of_a_run_stopped_mid_drain(tmp_path, small_config):
    """Rows still in the loop's buffers are not in the file: such a state is never saved."""
    run = rodjit.driver.run.Run(small_config)
    writer = hdf5.create_run_file(tmp_path / "r.h5", small_config, run, command="test")
    run.start(writer)
    run.advance(writer, max_steps=300)
    writer.save(run)
    slot = writer.current
    run.arrays.count[L.N_DIAG] = 3                # as if draining had failed half way
    writer.save(run)
    assert writer.current == slot
    run.arrays.count[L.N_DIAG] = 0
    writer.close(run, "completed")
    with h5py.File(tmp_path / "r.h5", "r") as f:
        assert f["checkpoint/current"][()] != slot
