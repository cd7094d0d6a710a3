"""One sweep point: its summary row against an independent reading of the same run."""
import math

import numpy as np
import pytest

import custom_law  # noqa: F401  (registers "log-test")
import rodjit
from rodjit.sweeps.point import BOUNCE_COLUMNS, PointTask, SUMMARY_COLUMNS, user_modules, run_point

from conftest import assert_same_files

# a fixed explicit step through the floor (the energy step stays admissible)
FAILING = {"time.dt": 1e-3, "initial.velocity": -100.0, "time.integrator": "verlet"}
TIMINGS = ("wall_time", "compile_time", "run_time", "run_file")


def expected_row(res):
    """The summary columns, computed here from a Result of rodjit.simulate."""
    b, d = res.bounces, res.diagnostics
    done = ~b["open"]
    e = b["restitution"][done]
    first = np.flatnonzero(done)[0] if done.any() else None
    return {
        "n_bounces": res.n_bounces, "n_complete_bounces": int(done.sum()),
        "restitution_first": e[0] if e.size else math.nan,
        "restitution_mean": e.mean() if e.size else math.nan,
        "contact_time_first": (b["t_release"][first] - b["t_impact"][first]
                               if first is not None else math.nan),
        "min_u0": min(d["u_bottom"].min(), np.nanmin(b["min_u0"], initial=np.inf)),
        "max_floor_force": max(d["floor_force"].max(), np.nanmax(b["max_floor_force"],
                                                                 initial=-np.inf)),
        "min_strain": min(d["min_strain"].min(), np.nanmin(b["min_strain"], initial=np.inf)),
        "energy_error": res.energy_error(), "steps": res.stats["steps"],
        "rejected_steps": res.stats["rejected_steps"], "t_final": res.t_final,
    }


def assert_row(values, expected):
    for name, value in expected.items():
        assert values[name] == pytest.approx(value, rel=1e-12, nan_ok=True), name


@pytest.mark.parametrize("over", [{}, {"rod.mu": 100.0, "time.integrator": "semi-implicit"},
                                  {"rod.law": "log-test", "time.t_end": 2.0}])
def test_row_matches_the_run(over, tmp_path):
    cfg = rodjit.Config().override({"time.t_end": 3.0, **over})
    res = rodjit.simulate(cfg)
    got = run_point(PointTask(0, cfg, None, user_modules(cfg)))
    assert got.status == "completed" and got.values["message"] == ""
    assert_row(got.values, expected_row(res))
    assert got.values["wall_time"] > 0 and got.values["run_file"] == ""
    for name in BOUNCE_COLUMNS:
        assert np.array_equal(got.bounces[name], res.bounces[name], equal_nan=True), name
    # saved: the run file is the one run_to_file writes, and the row is the same
    path = tmp_path / "p.h5"
    saved = run_point(PointTask(0, cfg, str(path), user_modules(cfg)))
    assert saved.values["run_file"] == "p.h5"
    assert {k: v for k, v in saved.values.items() if k not in TIMINGS} == pytest.approx(
        {k: v for k, v in got.values.items() if k not in TIMINGS}, nan_ok=True)
    rodjit.run_to_file(cfg, tmp_path / "ref.h5")
    assert_same_files(path, tmp_path / "ref.h5")


def test_every_summary_column_is_filled():
    got = run_point(PointTask(0, rodjit.Config().override({"time.t_end": 1.0}), None, ()))
    assert list(got.values) == list(SUMMARY_COLUMNS)
    assert got.values["n_bounces"] == 1 and got.values["min_u0"] < 0


def test_a_failing_point_keeps_its_numbers_up_to_the_failure(tmp_path):
    cfg = rodjit.Config().override(FAILING)
    with pytest.raises(rodjit.SimulationError) as info:
        rodjit.simulate(cfg)
    partial = info.value.result
    for save in (None, str(tmp_path / "f.h5")):
        got = run_point(PointTask(3, cfg, save, ()))
        assert got.index == 3 and got.status == "failed"
        assert "fixed step time.dt = 0.001 failed" in got.values["message"]
        assert got.values["steps"] == partial.stats["steps"] > 0
        assert got.values["t_final"] == partial.t_final
        assert got.values["n_bounces"] == partial.n_bounces


def test_an_unexpected_error_fails_only_the_point():
    got = run_point(PointTask(0, rodjit.Config(), None, ("no_such_law_module",)))
    assert got.status == "failed"
    assert got.values["message"].startswith("ModuleNotFoundError: No module named")
    assert got.values["steps"] == 0 and math.isnan(got.values["restitution_first"])


def test_law_modules_name_user_laws_only():
    assert user_modules(rodjit.Config()) == ()
    assert user_modules(rodjit.Config().override({"rod.law": "log-test"})) == ("custom_law",)
