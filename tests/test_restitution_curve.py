"""Restitution against impact speed: ``initial.impact_speed``, ``restitution_curve``, its
table, CSV and figure, and ``rodjit restitution``."""
from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from click.testing import CliRunner

import rodjit
from rodjit.analysis import curve_report, observables, restitution_curve
from rodjit.analysis.restitution import SPEED_KEY, curve_grid
from rodjit.cli import main
from rodjit.config import ConfigError
from rodjit.model.system import start_velocity

PAPER = rodjit.load_preset("paper-mu100").override({"time.t_end": 1.5})
G = 9.81


def test_an_impact_speed_starts_the_rod_with_the_velocity_of_its_fall():
    """The rod started 1 cm above the floor at the velocity a fall needs meets it at the
    impact speed asked for, and bounces as the rod dropped from rest from V²/(2|g|)."""
    v = math.sqrt(2 * G * 2.0)
    cfg = PAPER.override({"initial.height": 0.01, SPEED_KEY: v})
    r = rodjit.simulate(cfg)
    assert r.bounces["w_impact"][0] == pytest.approx(-v, rel=1e-12)
    dropped = rodjit.simulate(PAPER.override({"initial.height": 2.0}))
    assert observables(r)["restitution_first"] == pytest.approx(
        observables(dropped)["restitution_first"], rel=1e-7)
    # w² − 2g·u is constant in free flight; without gravity the start is the impact speed
    assert start_velocity(0.2, 0.0, 3.0, -G) == pytest.approx(-math.sqrt(9.0 - 2 * G * 0.2))
    assert start_velocity(0.2, 0.0, 3.0, 0.0) == -3.0
    assert start_velocity(0.2, -1.5, None, -G) == -1.5
    assert math.isnan(start_velocity(0.5, 0.0, 3.0, -G))    # a fall from 0.5 m is faster
    # started at its own drop height: from rest, not a rounding error's NaN
    for v in (0.7, 3.0, 7.3):
        w = start_velocity(v * v / (2 * G), 0.0, v, -G)
        assert not math.isnan(w) and abs(w) < 1e-7 * v


@pytest.mark.parametrize("changes, words", [
    ({SPEED_KEY: -1.0}, "initial.impact_speed = -1.0 is out of range (float > 0"),
    ({SPEED_KEY: 0.0}, "initial.impact_speed = 0.0 is out of range"),
    ({SPEED_KEY: 1.0, "initial.height": 1.0},
     "initial.impact_speed = 1.0 is out of range (>= 4.42945 m/s, the speed of a fall from "
     "rest from initial.height = 1.0): lower initial.height"),
    ({SPEED_KEY: 5.0, "initial.velocity": -1.0},
     "initial.impact_speed = 5.0 sets the initial velocity: leave initial.velocity unset (0), "
     "not -1.0"),
])
def test_a_bad_impact_speed_is_a_one_line_error_naming_the_key(changes, words):
    with pytest.raises(ConfigError) as info:
        PAPER.override(changes)
    assert words in str(info.value) and "\n" not in str(info.value)


def test_the_curve_is_the_drop_runs_it_stands_for():
    """Each point of a curve over drop heights gives the first bounce of the rod dropped
    from that height (another path: the fall computed), one line per compared value."""
    table = restitution_curve(PAPER, heights=[1.0, 2.0, 4.0],
                              compare={"rod.mu": [10.0, 100.0]}, scheduler="inline")
    assert table.grid.keys == ("rod.mu", SPEED_KEY)
    assert np.allclose(table[SPEED_KEY], np.sqrt(2 * G * np.array([1.0, 2.0, 4.0] * 2)))
    assert np.allclose(table["w_impact"], -table[SPEED_KEY], rtol=1e-12)
    for i in range(len(table)):
        mu, v = float(table["rod.mu"][i]), float(table[SPEED_KEY][i])
        r = rodjit.simulate(PAPER.override({"rod.mu": mu, "initial.height": v * v / (2 * G)}))
        obs = observables(r)
        assert table["impact_status"][i] == obs["status"]
        assert table["restitution_first"][i] == pytest.approx(obs["restitution_first"],
                                                              rel=1e-7, abs=1e-12)
        assert table["contact_time_first"][i] == pytest.approx(obs["contact_time_first"],
                                                               rel=1e-6)
    # μ = 10 from 1 m stays on the floor: marked so, not a bounce of restitution 0
    assert table["impact_status"][0] == "no lift-off"
    text = curve_report(table)
    assert text.splitlines()[0].split() == ["rod.mu", "impact_speed", "drop_height",
                                            "restitution_first", "contact_time_first",
                                            "impact_status"]
    assert "no lift-off" in text.splitlines()[1] and " 1 " in text.splitlines()[1]


@pytest.mark.parametrize("kwargs, words", [
    ({}, "give the impact speeds or the drop heights"),
    ({"speeds": [1.0], "heights": [1.0]}, "give the impact speeds or the drop heights"),
    ({"speeds": [2.0, 0.0]}, "speeds: 0.0 is out of range (finite and > 0)"),
    ({"speeds": [2.0, math.nan]}, "speeds: nan is out of range"),
    ({"heights": []}, "heights: give at least one value"),
    ({"speeds": [2.0], "compare": {"initial.height": [1.0]}},
     "compare: initial.height is set by the curve itself"),
])
def test_bad_curve_arguments_are_one_line_errors(kwargs, words):
    with pytest.raises(ValueError, match=None) as info:
        curve_grid(PAPER, **kwargs)
    assert words in str(info.value)


def test_heights_need_a_fall():
    with pytest.raises(ValueError, match="heights need gravity.g < 0"):
        curve_grid(PAPER.override({"gravity.g": 0.0}), heights=[1.0])
    base, grid = curve_grid(PAPER.override({"gravity.g": 0.0}), speeds="linspace(1, 3, 3)")
    assert grid[SPEED_KEY] == [1.0, 2.0, 3.0] and base.initial.height == 0.01
    # a drop height below the start height lowers the start to it
    base, grid = curve_grid(PAPER, heights=[0.002, 1.0])
    assert base.initial.height == pytest.approx(0.002)


def test_the_csv_holds_the_table_at_full_precision(tmp_path):
    table = restitution_curve(PAPER, speeds=[3.0, 6.0], scheduler="inline")
    path = table.to_csv(tmp_path / "c.csv", [SPEED_KEY, "restitution_first", "impact_status",
                                             "contact_time_first"])
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == [SPEED_KEY, "restitution_first", "impact_status", "contact_time_first"]
    for i, row in enumerate(rows[1:]):
        assert float(row[0]) == table[SPEED_KEY][i]
        assert float(row[1]) == table["restitution_first"][i]     # bit for bit
        assert row[2] == table["impact_status"][i]
    with pytest.raises(ValueError, match="exists"):
        table.to_csv(path)
    with pytest.raises(ValueError, match="'nope' is not a column"):
        table.to_csv(tmp_path / "d.csv", ["nope"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.csv"]


def test_the_figure_marks_a_point_without_lift_off_and_breaks_its_line():
    pytest.importorskip("matplotlib")
    from rodjit.plotting.sweep import sweep_figure

    table = restitution_curve(PAPER, heights=[1.0, 2.0], compare={"rod.mu": [10.0, 100.0]},
                              scheduler="inline")
    fig = sweep_figure(table, x=SPEED_KEY)
    lines = {ln.get_label(): ln for ln in fig.axes[0].get_lines()}
    assert "no lift-off" in lines
    mu10 = [ln for label, ln in lines.items() if label.endswith("= 10")][0]
    y = np.asarray(mu10.get_ydata(), float)
    assert math.isnan(y[0]) and y[1] > 0         # the line starts at the bounce
    assert "impact speed" in fig.axes[0].get_xlabel()


def test_the_command_writes_the_sweep_the_csv_and_the_figure(tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    runner = CliRunner()
    monkeypatch.chdir(tmp_path)
    res = runner.invoke(main, ["restitution", "paper-mu100", "--heights", "1,2", "--compare",
                               "rod.mu=10,100", "--set", "time.t_end=1.5", "--csv", "c.csv",
                               "--plot", "c.png", "-j", "1", "--scheduler", "inline"])
    assert res.exit_code == 0, res.output
    assert "no lift-off" in res.output and "wrote c.csv" in res.output
    table = rodjit.load_sweep("paper-mu100_restitution.h5")
    assert len(table) == 4 and table.grid.keys == ("rod.mu", SPEED_KEY)
    assert "rodjit restitution paper-mu100 --heights 1,2" in table.attrs["command"]
    with open("c.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert rows[0]["impact_status"] == "no lift-off"
    assert float(rows[3]["restitution_first"]) == table["restitution_first"][3]
    with open("c.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    # again: the sweep file exists
    res = runner.invoke(main, ["restitution", "paper-mu100", "--heights", "1,2",
                               "--scheduler", "inline"])
    assert res.exit_code == 2 and "exists" in res.output


@pytest.mark.parametrize("args, words", [
    (["--speeds", "0,1"], "speeds: 0.0 is out of range (finite and > 0)"),
    (["--speeds", "1,x"], "speeds: '1,x' is not a list of numbers"),
    (["--heights", "linspace(0, 1, 0)"], "initial.height"),
    (["--speeds", "1", "--heights", "1"], "give the impact speeds or the drop heights"),
    ([], "give the impact speeds or the drop heights"),
    (["--speeds", "1,2", "--compare", "initial.height=1"], "compare: initial.height"),
    (["--speeds", "1,2", "--compare", "rod.mu"], "rod.mu"),
    (["--speeds", "1,2", "--csv", "x.h5", "--set", "rod.mu=-1"], "rod.mu"),
])
def test_bad_command_input_exits_2_in_one_line_and_writes_nothing(tmp_path, monkeypatch, args,
                                                                 words):
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, ["restitution", "paper-mu100", *args, "--scheduler",
                                    "inline"])
    assert res.exit_code == 2, res.output
    assert words in res.output
    assert len(res.output.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []
