"""Results, summaries, sweep tables and configurations in a notebook: short reprs, HTML
tables, conversion to xarray / pandas, and lazy views of run files."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import h5py
import numpy as np
import pytest

import rodjit
from conftest import module_runs
from rodjit._extras import MissingExtra, need
from rodjit.output.summary import summarize
from rodjit.records.metadata import COLUMN_MEANINGS

xr = pytest.importorskip("xarray")
pd = pytest.importorskip("pandas")


CFG = rodjit.Config().override({"time.t_end": 1.0})

result, run_file = module_runs(CFG)


def test_result_repr_is_a_few_lines_with_the_headline_numbers(result):
    text = repr(result)
    lines = text.split("\n")
    assert 3 <= len(lines) <= 8 and len(text) < 600
    assert lines[0] == (f"rodjit.Result: completed, N = 5, mu = 0, "
                        f"{result.config.time.integrator} (auto)")
    e = result.bounces["restitution"][0]
    assert f"{result.n_bounces} (restitution {e:.4f}" in text
    assert f"{result.energy_error():.3g}" in text
    assert f"{result.stats['steps']} (" in text
    html = result._repr_html_()
    assert html.startswith("<table>") and f"{e:.4f}" in html and "energy drift" in html


def test_result_report_matches_the_file_summary(result, run_file):
    s = summarize(run_file)
    # the same run, in memory and on file: the same report but for the name and timings
    body = lambda text: [l for l in text.split("\n")[1:] if "time" not in l]
    assert body(result.report()) == body(s.report())
    assert repr(s).split("\n")[0].endswith(f"completed, N = 5, mu = 0, "
                                            f"{result.config.time.integrator} (auto)")
    assert "<table>" in s._repr_html_()


def test_config_and_sweep_table_reprs():
    c = rodjit.Config().override({"rod.mu": 3.0})
    assert repr(c).split("\n")[0] == (f"rodjit.Config: N = 5, mu = 3, "
                                       f"{c.time.integrator}, t_end = 5")
    assert "kappa_b = 1000.0" in repr(c) and "<table>" in c._repr_html_()
    t = rodjit.sweep(CFG.override({"time.t_end": 0.3}), {"rod.mu": [0, 10]},
                     scheduler="inline")
    text = repr(t)
    assert text.startswith("rodjit.SweepTable: completed, 2 points (2 completed")
    assert "rod.mu" in text and len(text.split("\n")) < 12
    assert "<table>" in t._repr_html_()


def test_to_xarray_layout_units_and_values(result):
    ds = result.to_xarray()
    assert ds.u.dims == ("t", "x") and ds.strain.dims == ("t", "x_segment")
    assert ds.energy_total.dims == ("t_diag",) and ds.bounce_restitution.dims == ("bounce",)
    assert ds.episode_t_start.dims == ("episode",)
    np.testing.assert_array_equal(ds.u.values, result.u)
    np.testing.assert_array_equal(ds.t_diag.values, result.diagnostics["t"])
    n = result.config.rod.N
    np.testing.assert_allclose(ds.strain.values, (result.u[:, 1:] - result.u[:, :-1]) * n - 1)
    np.testing.assert_allclose(ds.x_segment.values, (np.arange(n) + 0.5) / n)
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert ds.energy_total.attrs["units"] == COLUMN_MEANINGS["diagnostics"]["energy_total"].units
    assert "SI" in ds.attrs["units_system"]


def test_to_pandas_tables(result):
    tables = result.to_pandas()
    d, b = tables["diagnostics"], tables["bounces"]
    assert d.index.name == "t" and len(d) == result.diagnostics["t"].size
    assert b.index.name == "bounce" and list(b.index) == list(range(1, result.n_bounces + 1))
    np.testing.assert_array_equal(b["restitution"].to_numpy(), result.bounces["restitution"])


def test_open_run_gives_the_same_dataset_lazily(result, run_file):
    with rodjit.open_run(run_file) as ds:
        # the snapshot variables are not NumPy arrays until read
        assert not isinstance(ds.u.variable._data, np.ndarray)
        eager = result.to_xarray()
        assert set(ds.data_vars) == set(eager.data_vars)
        for name in ("u", "v", "strain", "energy_total", "bounce_restitution"):
            np.testing.assert_allclose(ds[name].values, eager[name].values, rtol=0, atol=0)
            assert ds[name].attrs["units"] == eager[name].attrs["units"]
        np.testing.assert_array_equal(ds.strain.isel(t=slice(3, 90, 7), x_segment=[0, 4]),
                                      eager.strain.isel(t=slice(3, 90, 7), x_segment=[0, 4]))
        np.testing.assert_array_equal(ds.u.isel(t=slice(None, None, -5)).values,
                                      eager.u.isel(t=slice(None, None, -5)).values)


@pytest.mark.slow
def test_open_run_does_not_read_every_snapshot(tmp_path, monkeypatch):
    path = tmp_path / "long.h5"
    rodjit.run_to_file(CFG.override({"time.t_end": 2.0, "rod.N": 40,
                                     "output.snapshot_interval": 0.001}), path)
    read = []
    original = h5py.Dataset.__getitem__

    def counting(self, key):
        out = original(self, key)
        if self.name in ("/snapshots/u", "/snapshots/v"):
            read.append(np.asarray(out).size)
        return out

    monkeypatch.setattr(h5py.Dataset, "__getitem__", counting)
    with rodjit.open_run(path) as ds:
        total = ds.u.size
        assert ds.sizes["t"] > 1500 and not read          # opening reads no snapshot
        last = ds.strain.isel(t=-1).values                 # one snapshot, one row
        assert sum(read) == 41 and last.shape == (40,)


def test_sweep_table_to_xarray_selects_by_identifier():
    t = rodjit.sweep(CFG.override({"time.t_end": 0.7}),
                     {"rod.mu": [0, 10], "floor.kappa_b": [500, 1000]}, scheduler="inline")
    ds = t.to_xarray()
    assert ds.restitution_first.dims == ("mu", "kappa_b")
    assert ds.mu.attrs["key"] == "rod.mu" and ds.kappa_b.attrs["key"] == "floor.kappa_b"
    assert ds.restitution_first.attrs["units"] == "1"
    assert "first bounce" in ds.restitution_first.attrs["description"]
    cell = ds.sel(mu=10, kappa_b=500).restitution_first.item()
    row = [i for i in range(len(t)) if t["rod.mu"][i] == 10 and t["floor.kappa_b"][i] == 500]
    assert cell == t["restitution_first"][row[0]] or (np.isnan(cell) and
                                                      np.isnan(t["restitution_first"][row[0]]))
    assert t.dimension_names() == {"rod.mu": "mu", "floor.kappa_b": "kappa_b"}


def test_clashing_last_parts_fall_back_to_the_full_key():
    t = rodjit.sweep(CFG.override({"time.t_end": 0.2}),
                     {"rod.law": ["aiki-kosugi"], "floor.law": ["aiki-kosugi"]},
                     scheduler="inline")
    assert t.dimension_names() == {"rod.law": "rod_law", "floor.law": "floor_law"}
    assert t.to_xarray().sel(rod_law="aiki-kosugi").status.size == 1


def test_a_missing_extra_names_it():
    with pytest.raises(MissingExtra, match=r"^Result.to_xarray needs nosuchmodule; install it "
                                           r"with: pip install 'rodjit\[analysis\]'$"):
        need("nosuchmodule", "analysis", "Result.to_xarray")


def _script(tmp_path, body: str):
    script = tmp_path / "script.py"
    script.write_text(textwrap.dedent(body))
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=600, cwd=tmp_path)


def test_a_script_without_main_guard_gets_one_clear_error(tmp_path):
    r = _script(tmp_path, """\
        import rodjit
        table = rodjit.sweep(rodjit.Config().override({"time.t_end": 0.2}),
                             {"rod.mu": [0, 1]}, jobs=2)
        print("returned")
        """)
    assert r.returncode == 1 and "returned" not in r.stdout
    last = r.stderr.strip().split("\n")[-1]
    assert last.startswith("rodjit.sweeps.main_guard.MissingMainGuard: ")
    assert 'if __name__ == "__main__":' in last and "line 2" in last
    # raised before any worker started: none re-ran the script
    assert "bootstrapping phase" not in r.stderr and "died" not in r.stderr


def test_a_guarded_script_runs(tmp_path):
    r = _script(tmp_path, """\
        import rodjit

        def main():
            t = rodjit.sweep(rodjit.Config().override({"time.t_end": 0.2}),
                             {"rod.mu": [0, 1]}, jobs=2)
            print(t.counts["completed"])

        if __name__ == "__main__":
            main()
        """)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "2"


def test_a_sweep_whose_points_all_failed_raises():
    # an explicit fixed step that overshoots the barrier (the energy step cannot)
    bad = CFG.override({"time.t_end": 0.5, "time.dt": 1e-3, "initial.velocity": -100.0,
                        "time.integrator": "verlet"})
    with pytest.raises(rodjit.SweepFailed, match="every point of the sweep failed") as info:
        rodjit.sweep(bad, {"rod.mu": [0, 1]}, scheduler="inline")
    assert info.value.table.counts["failed"] == 2
