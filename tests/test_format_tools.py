"""Run and sweep files (format 2) read cleanly by the HDF5 and netCDF command-line tools and
by xarray: a completed run, an interrupted one, one whose writer was killed, a sweep.  Every
dataset carries a long name (and units where one unit applies), booleans are flagged int8,
every axis is a netCDF dimension."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
import warnings

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.output import cf, hdf5

from conftest import quiet

TOOLS = {"h5dump": ["h5dump", "-H"], "h5ls": ["h5ls", "-r"], "ncdump": ["ncdump", "-h"]}
SMALL = {"rod.N": 5, "time.t_end": 0.4, "output.snapshot_interval": 0.02,
         "output.diagnostics_interval": 0.01}


def _tool_output(tool: str, path) -> str:
    exe = shutil.which(TOOLS[tool][0])
    if exe is None:
        pytest.skip(f"{TOOLS[tool][0]} is not installed (Debian: hdf5-tools, netcdf-bin)")
    r = subprocess.run([exe, *TOOLS[tool][1:], str(path)], capture_output=True, text=True,
                       timeout=120)
    text = r.stdout + r.stderr
    assert r.returncode == 0, text
    for sign in ("*ERROR*", " error: ", "HDF5-DIAG", "NetCDF:", "internal error"):
        assert sign not in text, text          # what the tools print for what they cannot read
    return text


def _open_everything(path) -> None:
    import xarray as xr
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tree = xr.open_datatree(path, engine="h5netcdf")
        try:
            for node in tree.subtree:
                node.to_dataset().load()
        finally:
            tree.close()


def _check_attributes(path) -> None:
    """Every dataset names what it holds; a unit unless it mixes units, is text or flags."""
    with hdf5.open_file(path) as f:
        assert f.attrs["Conventions"] == cf.CONVENTIONS
        for key in ("title", "source", "history", "references"):
            assert key in f.attrs
        found = []

        def visit(name, obj):
            if not isinstance(obj, h5py.Dataset):
                return
            if obj.attrs.get("CLASS") == b"DIMENSION_SCALE" and str(
                    obj.attrs.get("NAME", b"").decode()).startswith("This is a netCDF"):
                return                       # a dimension without values
            found.append(name)
            assert "long_name" in obj.attrs, name
            if obj.dtype == bool:
                raise AssertionError(f"{name} is stored as bool")
            if "flag_values" in obj.attrs:
                assert obj.dtype == np.int8 and "flag_meanings" in obj.attrs, name
        f.visititems(visit)
        assert found


@pytest.fixture(scope="module")
def run_files(tmp_path_factory):
    """A completed run, an interrupted one (stopped through the API by SIGINT) and one whose
    writer was killed with SIGKILL."""
    tmp = tmp_path_factory.mktemp("files")
    done = tmp / "done.h5"
    rodjit.run_to_file(quiet(**SMALL), done, handle_signals=False)

    stopped = tmp / "stopped.h5"
    calls = {"n": 0}

    def progress(run):
        calls["n"] += 1
        if calls["n"] == 3:
            os.kill(os.getpid(), signal.SIGINT)
    import rodjit.driver.run as run_module
    old = run_module.NODE_STEPS_PER_CALL
    run_module.NODE_STEPS_PER_CALL = 600
    try:
        with pytest.raises(rodjit.RunInterrupted):
            rodjit.run_to_file(quiet(**(SMALL | {"time.t_end": 5.0})), stopped,
                               progress=progress)
    finally:
        run_module.NODE_STEPS_PER_CALL = old

    killed = tmp / "killed.h5"
    code = ("import rodjit; rodjit.run_to_file(rodjit.Config().override({'rod.N': 5, "
            "'time.t_end': 1e6, 'output.snapshot_interval': 1.0, "
            "'output.diagnostics_interval': 1.0}), %r, flush_interval=0.05)" % str(killed))
    proc = subprocess.Popen([sys.executable, "-c", code])
    deadline = time.monotonic() + 240
    try:
        while time.monotonic() < deadline:
            assert proc.poll() is None
            try:
                with hdf5.open_file(killed) as f:
                    if hdf5.read_checkpoint(f)["lengths"]["snapshots"] > 3:
                        break
            except (ValueError, OSError, KeyError):
                pass
            time.sleep(0.1)
        else:
            pytest.fail("the run to kill made no progress")
    finally:
        proc.kill()
        proc.wait(60)
    with h5py.File(killed, "r", swmr=True) as f:
        assert f.attrs["status"] == "running"
    # HDF5's tools refuse a file whose SWMR writer died (its superblock still says "open
    # for writing"); the two ways README gives: h5clear -s, or rodjit's recovery
    cleared = tmp / "killed_cleared.h5"
    shutil.copyfile(killed, cleared)
    h5clear = shutil.which("h5clear")
    if h5clear is not None:
        subprocess.run([h5clear, "-s", str(cleared)], check=True, timeout=60)
    recovered = tmp / "killed_recovered.h5"
    shutil.copyfile(killed, recovered)
    hdf5.recover(recovered)
    return {"completed": done, "interrupted": stopped, "killed": cleared,
            "recovered": recovered, "killed_raw": killed}


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("sweep") / "sweep.h5"
    base = quiet(**(SMALL | {"time.t_end": 0.8}))
    rodjit.sweep(base, {"rod.mu": [0.0, 10.0], "floor.kappa_b": [1000.0, 3000.0]},
                 output=path, jobs=1, scheduler="inline", handle_signals=False)
    return path


@pytest.mark.parametrize("tool", sorted(TOOLS))
@pytest.mark.parametrize("kind", ["completed", "interrupted", "killed", "recovered"])
def test_tools_read_run_files(run_files, kind, tool):
    if kind == "killed" and shutil.which("h5clear") is None:
        pytest.skip("h5clear is not installed (Debian: hdf5-tools)")
    text = _tool_output(tool, run_files[kind])
    if tool == "ncdump":
        assert "u(t, x)" in text and "t = UNLIMITED" in text
        assert 'Conventions = "CF-1.10"' in text


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_tools_read_sweep_file(sweep_file, tool):
    text = _tool_output(tool, sweep_file)
    if tool == "ncdump":
        assert "point = 4" in text and "status(point)" in text


@pytest.mark.parametrize("kind", ["completed", "interrupted", "recovered"])
def test_xarray_opens_every_group_of_a_run_file(run_files, kind):
    _open_everything(run_files[kind])
    _check_attributes(run_files[kind])


def test_xarray_opens_every_group_of_a_sweep_file(sweep_file):
    _open_everything(sweep_file)
    _check_attributes(sweep_file)
    import xarray as xr
    with xr.open_dataset(sweep_file, group="summary", engine="h5netcdf") as ds:
        assert ds["restitution_mean"].dims == ("point",)
        assert {"rod.mu", "floor.kappa_b"} <= set(ds.coords)      # swept keys: coordinates
        assert ds["rod.mu"].attrs["units"] == rodjit.config.field_spec("rod.mu").unit
    with xr.open_dataset(sweep_file, group="bounces", engine="h5netcdf") as ds:
        assert ds["t_impact"].dims == ("bounce",) and ds["t_impact"].size > 0
        assert ds["point_index"].attrs["instance_dimension"] == "point"
    with h5py.File(sweep_file, "r") as f:
        assert f.attrs["format_version"] == 4
        b = f["bounces"]
        assert b["open"].dtype == np.int8 and b["t_impact"].size > 0


def test_a_killed_writers_file_reads_with_swmr_as_it_is(run_files):
    """Before any clearing: h5py in SWMR-read mode (and so rodjit) reads every group."""
    with h5py.File(run_files["killed_raw"], "r", swmr=True) as f:
        assert f.attrs["format_version"] == hdf5.FORMAT_VERSION
        assert f["snapshots/u"].shape[0] >= hdf5.read_checkpoint(f)["lengths"]["snapshots"]
    assert rodjit.load_file(run_files["killed_raw"]).t.size > 3


def test_run_file_layout_format_3(run_files):
    import xarray as xr
    path = run_files["completed"]
    with h5py.File(path, "r") as f:
        assert f.attrs["format_version"] == 3
        assert "grid" not in f                          # one x coordinate, /snapshots/x
        assert f["bounces/open"].dtype == np.int8
        assert f["bounces/ambiguous"].dtype == np.int8
        assert list(f["bounces/open"].attrs["flag_values"]) == [0, 1]
        assert f["diagnostics/energy_total"].attrs["units"] == "J"
        assert f["snapshots/u"].attrs["units"] == "m"
    with xr.open_dataset(path, group="snapshots", engine="h5netcdf") as ds:
        assert ds["u"].dims == ("t", "x") and ds["u"].attrs["long_name"]
        np.testing.assert_array_equal(ds["x"].values, np.arange(6) / 5)
    r = rodjit.load_file(path)
    assert r.bounces["open"].dtype == bool
    np.testing.assert_array_equal(r.x, np.arange(6) / 5)



def test_installed_h5dump_is_the_distributions_1_10_or_newer():
    """What the tool tests above prove: the h5dump they ran (HDF5 1.10 on Debian 12)."""
    exe = shutil.which("h5dump")
    if exe is None:
        pytest.skip("h5dump is not installed (Debian: hdf5-tools)")
    out = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout
    major, minor = (int(x) for x in out.split("Version")[1].split(".")[:2])
    assert (major, minor) >= (1, 10)
