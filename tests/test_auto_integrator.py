"""``time.integrator = "auto"``: the default picks its integrator from the registry's table
(``registry.AUTO_TABLE``, documented in docs/integrators.md), once per study, and says so in
the summary and the files."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.stepping import registry

DOCS = Path(__file__).resolve().parents[1] / "docs" / "integrators.md"
SHORT = {"time.t_end": 0.3, "output.snapshot_interval": 0.0,
         "output.diagnostics_interval": 0.0}


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rodjit.config.ModelWarning)
        yield


def test_the_default_and_the_presets_are_auto():
    assert rodjit.Config().time.integrator == "auto"
    from rodjit.presets import load_preset

    for name in ("paper-mu0", "paper-mu100"):
        assert load_preset(name).time.integrator == "auto"


@pytest.mark.parametrize("mu, gamma, n, expected, row", [
    (0.0, 0.0, 5, "dop853", 0), (0.0, 0.0, 320, "dop853", 0),
    (1.0, 0.0, 5, "dop853", 1), (0.5, 0.0, 4, "dop853", 1),
    (1.0, 0.0, 20, "radau5", 2), (100.0, 0.0, 5, "radau5", 2),
    (0.0, 1e-3, 5, "radau5", 2), (1.0, 1e-3, 5, "radau5", 2)])
def test_the_choice_follows_the_table(mu, gamma, n, expected, row):
    cfg = rodjit.Config().override({"rod.mu": mu, "rod.gamma": gamma, "rod.N": n,
                                    "time.t_end": 0.5}).resolve()
    assert cfg.time.integrator == expected
    assert cfg.choice == f"chosen by 'auto' for {registry.AUTO_TABLE[row].when}"


def test_the_docs_table_is_the_registry_table():
    """docs/integrators.md's table of "auto" lists the registry's rows, in order."""
    text = DOCS.read_text()
    section = text[text.index("## What `auto` chooses"):]
    section = section[:section.index("\n## ", 4)]
    rows = [line.split("|")[1:-1] for line in section.splitlines()
            if line.startswith("| ") and not line.startswith("| regime")]
    found = [(cells[0].strip(), cells[1].strip().strip("`")) for cells in rows]
    assert found == [(c.when, c.integrator) for c in registry.AUTO_TABLE]


@pytest.mark.parametrize("t_end, factor", [(0.5, 1.0), (1.0, 1.0), (5.0, 5.0),
                                           (200.0, 200.0)])
def test_a_conservative_rod_tightens_its_tolerances_with_the_run(t_end, factor):
    base = rodjit.Config().override({"time.t_end": t_end})
    cfg = base.resolve()
    assert cfg.time.rtol == base.time.rtol / factor
    assert cfg.time.atol == base.time.atol / factor
    assert ("tolerances /" in cfg.choice) == (factor > 1.0)


def test_tightening_stops_at_the_smallest_tolerance():
    cfg = rodjit.Config().override({"time.t_end": 1e6, "time.rtol": 1e-10,
                                    "time.atol": 1e-13}).resolve()
    assert cfg.time.rtol == pytest.approx(registry.AUTO_RTOL_MIN)
    assert cfg.time.atol == pytest.approx(1e-15)


def test_a_viscous_rod_keeps_its_tolerances():
    base = rodjit.Config().override({"rod.mu": 100.0, "time.t_end": 200.0})
    assert base.resolve().time.rtol == base.time.rtol


def test_a_named_integrator_is_left_alone():
    cfg = rodjit.Config().override({"time.integrator": "energy", "time.t_end": 200.0})
    assert cfg.resolve() is cfg and cfg.choice == ""


def test_the_choice_is_dropped_when_a_key_it_set_changes():
    cfg = rodjit.Config().resolve()
    assert cfg.override({"rod.mu": 3.0}).choice == cfg.choice     # still its choice
    for key, value in (("time.integrator", "radau5"), ("time.rtol", 1e-3)):
        assert cfg.override({key: value}).choice == ""


def test_simulate_records_what_ran_and_why():
    res = rodjit.simulate(rodjit.Config().override(SHORT))
    assert res.config.time.integrator == "dop853"
    assert res.config.choice.startswith("chosen by 'auto'")
    assert repr(res).splitlines()[0].endswith("dop853 (auto)")
    # the same run as the integrator it chose, named
    named = rodjit.simulate(res.config)
    np.testing.assert_array_equal(named.u, res.u)


def test_the_run_file_records_the_choice_and_a_resume_keeps_it(tmp_path):
    out = tmp_path / "r.h5"
    summary = rodjit.run_to_file(rodjit.Config().override(SHORT), out)
    assert "integrator dop853, chosen by 'auto'" in summary.report()
    with h5py.File(out) as f:
        assert str(f.attrs["integrator_choice"]).startswith("chosen by 'auto'")
        assert 'integrator = "dop853"' in f.attrs["config_toml"]
    loaded = rodjit.load_file(out)
    assert loaded.config.choice.startswith("chosen by 'auto'")
    # a resume to a later end keeps the integrator and the tolerances chosen at the start
    rtol = loaded.config.time.rtol
    rodjit.resume_file(out, t_end=2.0)
    again = rodjit.load_file(out).config
    assert (again.time.integrator, again.time.rtol, again.time.t_end) == ("dop853", rtol, 2.0)


def test_a_file_of_a_named_integrator_has_no_choice(tmp_path):
    out = tmp_path / "r.h5"
    rodjit.run_to_file(rodjit.Config().override({**SHORT, "time.integrator": "dop853"}), out)
    with h5py.File(out) as f:
        assert "integrator_choice" not in f.attrs
    assert rodjit.load_file(out).config.choice == ""


def test_a_sweep_runs_the_base_choice_at_every_point(tmp_path):
    """A rod.mu sweep from μ = 0 keeps the integrator chosen at μ = 0 (it does not switch
    to radau5 halfway), and the sweep file says why."""
    base = rodjit.Config().override(SHORT)
    table = rodjit.sweep(base, {"rod.mu": [0.0, 100.0]}, output=tmp_path / "s.h5", jobs=1,
                         scheduler="inline")
    assert table.base.time.integrator == "dop853"
    assert table.base.choice.startswith("chosen by 'auto'")
    alone = rodjit.simulate(base.resolve().override({"rod.mu": 100.0}))
    assert table.columns["steps"][1] == alone.stats["steps"]
    assert rodjit.load_sweep(tmp_path / "s.h5").base.choice == table.base.choice
    from rodjit.reports import info

    assert f"integrator dop853, {table.base.choice}" in info(tmp_path / "s.h5")


def test_a_ladder_keeps_one_integrator_across_its_rungs():
    """A rod.N ladder from μ = 1, N = 5 (dop853's row) runs dop853 at N = 20 too, where
    a run of its own would choose radau5."""
    base = rodjit.Config().override({"rod.mu": 1.0, "rod.N": 5, "time.t_end": 0.8})
    assert base.override({"rod.N": 20}).resolve().time.integrator == "radau5"
    rep = rodjit.converge(base, {"rod.N": [5, 10, 20]}, also=False, jobs=1,
                         scheduler="inline")
    assert rep.base.time.integrator == "dop853"
    alone = rodjit.simulate(base.resolve().override({"rod.N": 20}))
    assert rep.runs[-1]["steps"] == alone.stats["steps"]


# ---- where an integrator is impractical ----------------------------------------------------
@pytest.mark.parametrize("name", ["dp54", "dop853"])
def test_an_explicit_pair_capped_by_the_viscosity_is_refused_in_one_line(name):
    cfg = rodjit.Config().override({"time.integrator": name, "rod.mu": 100.0, "rod.N": 200})
    with pytest.raises(ValueError) as info:
        cfg.check_runnable()
    text = str(info.value)
    assert "\n" not in text and "rod.mu*rod.N^2 = 4e+06" in text
    assert "'radau5' or 'auto'" in text
    # the same rod where the cap admits the run, with a fixed step, or chosen by auto
    cfg.override({"rod.N": 20}).check_runnable()
    cfg.override({"time.dt": 1e-6}).check_runnable()
    auto = cfg.override({"time.integrator": "auto"})
    auto.check_runnable()
    assert auto.resolve().time.integrator == "radau5"


@pytest.mark.parametrize("name", ["dp54", "dop853"])
def test_the_registry_s_step_count_of_the_viscous_cap_is_measured(name):
    """``Scheme.viscous_steps``: steps per simulated second over μN², as a run counts."""
    cfg = rodjit.Config().override({**SHORT, "time.integrator": name, "rod.mu": 100.0,
                                    "rod.N": 20, "time.t_end": 0.1})
    steps = rodjit.simulate(cfg).stats["steps"]
    expected = registry.get(name).viscous_steps * 100.0 * 20 ** 2 * 0.1
    assert steps == pytest.approx(expected, rel=0.05)


def test_the_command_line_refuses_an_impractical_pair(tmp_path):
    from click.testing import CliRunner

    from rodjit.cli import main

    r = CliRunner().invoke(main, ["run", "-o", str(tmp_path / "r.h5"), "--set",
                                  "time.integrator=dop853", "--set", "rod.mu=100", "--set",
                                  "rod.N=200"])
    assert r.exit_code == 2 and "impractical at rod.mu = 100, rod.N = 200" in r.output
    assert len(r.output.strip().splitlines()) == 1 and not (tmp_path / "r.h5").exists()


def test_a_study_from_an_auto_base_refuses_a_point_its_integrator_cannot_run():
    """The study keeps the base's choice (dop853 at μ = 0); a point where that is
    impractical is named before anything runs, as docs/integrators.md says."""
    with pytest.raises(ValueError, match=r"grid point 1 \(rod.mu=100\): time.integrator = "
                                         r"'dop853' is impractical"):
        rodjit.plan_sweep(rodjit.Config().override({"rod.N": 200}), {"rod.mu": [0.0, 100.0]})
    plan = rodjit.plan_sweep(rodjit.Config().override({"rod.N": 200, "rod.mu": 100.0}),
                             {"rod.mu": [0.0, 100.0]})
    assert plan.config.time.integrator == "radau5"
