"""Files in format 1, written by rodjit 0.1.0 (tests/fixtures, README there), still open,
summarize, plot and resume bit for bit with the current code."""
from __future__ import annotations

import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.output import hdf5
from rodjit.reports import info
from rodjit.stepping import layout as L
from rodjit.sweeps import sweep_file

FIXTURES = Path(__file__).parent / "fixtures"
RUN, PARTIAL, KILLED, SWEEP = (FIXTURES / f"format1_{n}.h5"
                               for n in ("run", "partial", "killed", "sweep"))


def _copy(path: Path, tmp_path: Path) -> Path:
    out = tmp_path / path.name
    shutil.copyfile(path, out)
    return out


# what a format-1 checkpoint did not carry: the vibration energy at the impact of a bounce
# it had open, so a bounce open at the checkpoint has NaN there and what follows from it
NOT_CARRIED = ("energy_vibration_impact", "restitution_energy", "ambiguous")


EXTREMES = ("min_u0", "max_floor_force", "min_strain")


def _assert_same_results(a: rodjit.Result, b: rodjit.Result, open_before=None,
                         sampled_before=None) -> None:
    """Same tables and final state, bit for bit (the two files' layouts may differ);
    ``open_before``: bounces of ``a`` with an impact before this time came from a format-1
    checkpoint: their vibration energy at impact is NaN in ``a``, and the NOT_CARRIED
    columns are not compared there.  ``sampled_before``: bounces of ``a`` with an impact
    before this time were open at a checkpoint of code that took their extremes at the
    step points only (today's search inside the steps, ``stepping.extremes``, finds them a
    little deeper): those extremes agree to 1e-5."""
    for name in ("t", "u", "v", "x", "u_final", "v_final"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for table in ("diagnostics", "episodes", "bounces"):
        ta, tb = getattr(a, table), getattr(b, table)
        assert list(ta) == list(tb)
        for col in ta:
            assert ta[col].dtype == tb[col].dtype, (table, col)
            x, y = ta[col], tb[col]
            if table == "bounces" and col in NOT_CARRIED and open_before is not None:
                old = ta["t_impact"] < open_before
                assert np.all(np.isnan(ta["energy_vibration_impact"][old]))
                x, y = x[~old], y[~old]
            if table == "bounces" and col in EXTREMES and sampled_before is not None:
                old = ta["t_impact"] < sampled_before
                np.testing.assert_allclose(x[old], y[old], rtol=1e-5, err_msg=col)
                x, y = x[~old], y[~old]
            np.testing.assert_array_equal(x, y, err_msg=f"{table}/{col}")
    assert (a.t_final, a.dissipated, a.energy0) == (b.t_final, b.dissipated, b.energy0)


def test_fixtures_are_format_1_and_small():
    for path in (RUN, PARTIAL, KILLED, SWEEP):
        assert path.stat().st_size < 200_000
        with hdf5.open_file(path) as f:
            assert int(f.attrs["format_version"]) == 1


def test_format_1_run_loads():
    r = rodjit.load_file(RUN)
    assert r.status == "completed" and r.config.rod.N == 5
    np.testing.assert_array_equal(r.x, np.arange(6) / 5)
    assert r.t.size == 11 and r.u.shape == (11, 6)
    assert r.bounces["open"].dtype == bool
    with hdf5.open_file(RUN) as f:
        assert hdf5.read_checkpoint(f)["lengths"]["snapshots"] == 11
        assert np.array_equal(hdf5.read_x(f), r.x)


def test_format_1_run_equals_the_same_run_today(tmp_path):
    """The current code computes what 0.1.0 wrote (only the layout changed)."""
    with h5py.File(RUN, "r") as f:   # the configuration as that run resolved it
        cfg = rodjit.Config.from_stored_toml(f.attrs["config_toml"])
    rodjit.run_to_file(cfg, tmp_path / "now.h5", handle_signals=False)
    _assert_same_results(rodjit.load_file(RUN), rodjit.load_file(tmp_path / "now.h5"))


def test_format_1_partial_resumes_bit_for_bit(tmp_path):
    path = _copy(PARTIAL, tmp_path)
    assert rodjit.load_file(path).t_final == pytest.approx(0.1)
    rodjit.resume_file(path, t_end=0.2, handle_signals=False)
    with h5py.File(path, "r") as f:
        # rebuilt in the current layout to be continued (its bounce columns are new)
        assert int(f.attrs["format_version"]) == hdf5.FORMAT_VERSION
        assert f["bounces/open"].dtype == np.int8 and "restitution_energy" in f["bounces"]
    with h5py.File(RUN, "r") as f:   # the configuration as that run resolved it
        cfg = rodjit.Config.from_stored_toml(f.attrs["config_toml"])
    rodjit.run_to_file(cfg, tmp_path / "ref.h5", handle_signals=False)
    _assert_same_results(rodjit.load_file(path), rodjit.load_file(tmp_path / "ref.h5"))
    _assert_same_results(rodjit.load_file(path), rodjit.load_file(RUN))


def test_format_1_killed_file_reads_recovers_and_resumes(tmp_path):
    path = _copy(KILLED, tmp_path)
    r = rodjit.load_file(path)                     # SWMR-read, as the writer left it
    assert r.status == "running" and r.t.size > 3
    with hdf5.open_file(path) as f:
        t_ck = float(hdf5.read_checkpoint(f)["clock"][L.T])
    t_end = t_ck + 20.0
    rodjit.resume_file(path, t_end=t_end, handle_signals=False)   # recovers, then continues
    with h5py.File(path, "r") as f:
        assert int(f.attrs["format_version"]) == hdf5.FORMAT_VERSION   # the current layout
    cfg = rodjit.load_file(path).config.override({"time.t_end": t_end})
    rodjit.run_to_file(cfg, tmp_path / "ref.h5", handle_signals=False)
    _assert_same_results(rodjit.load_file(path), rodjit.load_file(tmp_path / "ref.h5"),
                         open_before=t_ck, sampled_before=t_ck)


def test_format_1_files_summarize():
    text = info(RUN)
    assert "format 1" in text
    text = info(SWEEP)
    assert "format 1" in text


def test_format_1_sweep_reads(tmp_path):
    with sweep_file.open_sweep(SWEEP) as f:
        header = sweep_file.read_header(f)
        summary = sweep_file.read_summary(f)
        assert list(summary)[:2] == ["rod.mu", "floor.kappa_b"]
        assert list(summary["status"]) == ["completed"] * 4
        b = sweep_file.read_bounces(f, 0)
        assert b["open"].dtype == bool
    assert list(header["grid"].keys) == ["rod.mu", "floor.kappa_b"]
    table = rodjit.load_sweep(SWEEP)
    assert list(table.columns["status"]) == ["completed"] * 4
    assert table.columns["restitution_mean"].dtype == np.float64


def test_format_1_files_plot(tmp_path):
    pytest.importorskip("matplotlib")
    from rodjit.plotting import run as plot_run
    from rodjit.plotting import sweep as plot_sweep
    for kind in plot_run.KINDS:
        out = plot_run.plot_file(RUN, tmp_path / f"{kind}.png", kind=kind)
        assert Path(out).stat().st_size > 0
    for kind in plot_sweep.KINDS:
        # the fixture's short points end before a complete bounce: restitutions are NaN
        out = plot_sweep.plot_sweep_file(SWEEP, tmp_path / f"sweep_{kind}.png", kind=kind,
                                         quantity="min_u0")
        assert Path(out).stat().st_size > 0
