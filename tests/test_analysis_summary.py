"""The always-defined first-impact observables in sweep rows, run-file summaries, ``info``
and plots, and the figure of a convergence study."""
from __future__ import annotations

import math

import numpy as np
import pytest

import rodjit
from rodjit.analysis import first_impact, macroscopic_contacts, physics_of
from rodjit.output.summary import summarize
from rodjit.records.observables import IMPACT_COLUMNS
from rodjit.sweeps.point import SUMMARY_COLUMNS, PointTask, run_point

PAPER = rodjit.load_preset("paper-mu100")
TIMINGS = ("wall_time", "compile_time", "run_time", "run_file")


def _same(a, b) -> bool:
    return a == b or (isinstance(a, float) and math.isnan(a) and math.isnan(b))


def test_summary_columns_have_one_name_per_meaning():
    names = list(SUMMARY_COLUMNS)
    for name in ("restitution_first", "restitution_mean", "restitution_energy_mean",
                 "contact_time_first"):
        assert names.count(name) == 1
    for gone in ("restitution_impact", "contact_time_impact"):   # the first bounce's now
        assert gone not in names
    assert set(IMPACT_COLUMNS) <= set(names)


@pytest.mark.parametrize("mu", [10.0, 100.0])
def test_paper_point_has_a_defined_restitution_in_memory_and_saved(mu, tmp_path):
    cfg = PAPER.override({"rod.mu": mu, "time.t_end": 2.0})
    mem = run_point(PointTask(0, cfg, None, ())).values
    saved = run_point(PointTask(0, cfg, str(tmp_path / "p.h5"), ())).values
    for name in SUMMARY_COLUMNS:
        if name not in TIMINGS:
            assert _same(mem[name], saved[name]), (name, mem[name], saved[name])
    # the same numbers as the analysis layer on the Result
    res = rodjit.simulate(cfg)
    fi = first_impact(res.diagnostics, res.episodes, res.bounces, physics_of(res))
    assert mem["impact_status"] == fi.status
    assert mem["restitution_first"] == fi.restitution
    assert mem["contact_time_first"] == fi.contact_time
    assert mem["rebound_speed"] == fi.rebound_speed
    assert mem["min_u0_impact"] == fi.min_u0
    if mu == 10.0:
        # the first contact never ends: the restitution is 0, the bounce open and ambiguous
        assert mem["impact_status"] == "no lift-off"
        assert mem["restitution_first"] == 0.0 and mem["restitution_apex"] == 0.0
        assert mem["contact_time_first"] == math.inf
        assert math.isnan(mem["restitution_mean"])
        assert "never leaves the floor" in mem["impact_reason"]
        assert 0.1 < mem["rebound_speed"] / -mem["w_impact"] < 0.25
    else:
        assert mem["impact_status"] == "lift-off" and mem["impact_reason"] == ""
        assert 0.05 < mem["restitution_first"] < 0.3
        assert 0 < mem["contact_time_first"] < 0.1
        assert mem["restitution_first"] == pytest.approx(res.bounces["restitution"][0],
                                                         rel=1e-12)


def test_stiff_floor_row_has_no_restitution_above_the_energy_bound():
    cfg = rodjit.Config().override({"floor.kappa_b": 1e5, "floor.beta": 1e-3, "rod.N": 5,
                                    "time.t_end": 10.0, "rod.mu": 0.0,
                                    "output.snapshot_interval": 0.0})
    row = run_point(PointTask(0, cfg, None, ())).values
    res = rodjit.simulate(cfg)
    c = macroscopic_contacts(res.diagnostics, res.episodes, res.bounces, physics_of(res))
    w_i, g = c["w_impact"][0], cfg.gravity.g
    bound = math.sqrt(1 + 2 * (c["ev_impact"][0] + g * (c["z_release"][0] - c["z_impact"][0]))
                      / w_i ** 2)
    assert row["impact_status"] == "lift-off"
    assert row["restitution_first"] == pytest.approx(c["restitution"][0], rel=1e-14)
    assert row["restitution_first"] <= bound * (1 + 1e-9)
    # dropped at rest: no vibration is brought into the first impact, and μ = 0 keeps
    # (almost) all the energy
    assert row["vibration_ratio"] < 1e-12
    assert 0.5 < row["restitution_first"] <= 1 + 1e-6
    # the mean over the bounces not marked ambiguous (the apex bookkeeping read above 2)
    b = res.bounces
    assert row["restitution_mean"] == pytest.approx(b["restitution"][~b["ambiguous"]].mean())
    assert row["restitution_mean"] < 1.5 and 0 < row["restitution_energy_mean"] < 1


def test_run_report_and_info_show_the_first_impact(tmp_path):
    from rodjit.reports import info

    path = tmp_path / "r.h5"
    rodjit.run_to_file(PAPER.override({"rod.mu": 10.0, "time.t_end": 2.0}), path)
    s = summarize(path)
    assert s.impact["impact_status"] == "no lift-off"
    text = info(path)
    line = next(ln for ln in text.splitlines() if "first impact" in ln)
    ratio = s.impact["rebound_speed"] / -s.impact["w_impact"]
    assert "no lift-off" in line and f"{ratio:.3g} of impact" in line
    # one meaning of "no lift-off": the bounce table's open row says it too, not "open"
    row = [ln for ln in text.splitlines() if ln.split()[:2] == ["1", "0.4515"]][0]
    assert "no lift-off" in row and "open" not in row
    assert "(restitution no lift-off)" in str(rodjit.load_file(path))
    path2 = tmp_path / "l.h5"
    rodjit.run_to_file(PAPER.override({"time.t_end": 1.0}), path2)
    s2 = summarize(path2)
    line = next(ln for ln in s2.report().splitlines() if "first impact" in ln)
    assert f"e = {s2.impact['restitution_first']:.4g} (lift-off)" in line
    assert f"contact {s2.impact['contact_time_first']:.4g} s" in line
    # the apex ratio named as such, and never a bare "e = 0" beside the restitution
    assert s2.impact["restitution_apex"] == 0.0 and "apex e" not in line
    assert "centre-of-mass apex restitution 0 (the centre of mass rises no higher" in line
    # an open bounce that may still end reads "open"
    path3 = tmp_path / "o.h5"
    rodjit.run_to_file(PAPER.override({"time.t_end": 0.455}), path3)
    r3 = rodjit.load_file(path3)
    assert r3.bounces["open"][-1] and "(restitution open" in str(r3)


def test_sweep_plot_draws_a_no_lift_off_point(tmp_path):
    pytest.importorskip("matplotlib")
    from rodjit.plotting.sweep import sweep_figure

    path = tmp_path / "s.h5"
    rodjit.sweep(PAPER.override({"time.t_end": 2.0}), {"rod.mu": [1.0, 10.0, 100.0]},
                 output=path, scheduler="inline")
    table = rodjit.load_sweep(path)
    assert table["restitution_first"][1] == 0.0        # no lift-off: the bounce is open
    assert table.bounces(1)["open"][-1] and table.bounces(1)["ambiguous"][-1]
    ax = sweep_figure(path).axes[0]
    lines = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 3]   # not the e = 1 rule
    assert len(lines) == 1
    assert np.array_equal(lines[0].get_xdata(), [1.0, 10.0, 100.0])
    y = np.asarray(lines[0].get_ydata(), float)
    # drawn as a point of its own, "no lift-off" at its value 0, which breaks the line
    assert np.isnan(y[1]) and np.array_equal(y[[0, 2]], table["restitution_first"][[0, 2]])
    marks = [ln for ln in ax.get_lines() if ln.get_label() == "no lift-off"]
    assert len(marks) == 1
    assert list(marks[0].get_xdata()) == [10.0] and list(marks[0].get_ydata()) == [0.0]


def test_convergence_plot_renders_on_log_axes(tmp_path):
    pytest.importorskip("matplotlib")
    from click.testing import CliRunner

    from rodjit.cli import main
    from rodjit.plotting.convergence import convergence_figure

    conv = rodjit.converge(PAPER.override({"time.t_end": 0.8, "rod.mu": 1.0}),
                           {"rod.N": [5, 10, 20, 40]},
                           observables=["contact_time_first", "min_u0_first"],
                           scheduler="inline")
    path = tmp_path / "conv.h5"
    conv.save(path)
    ax = convergence_figure(path).axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    drawn = [ln for ln in ax.get_lines() if not ln.get_label().startswith("_")]
    assert len(drawn) == 2 and "p = " in drawn[0].get_label()
    assert np.array_equal(drawn[0].get_xdata(), [5, 10, 20, 40])
    png = tmp_path / "conv.png"
    out = CliRunner().invoke(main, ["plot", str(path), "-o", str(png)])
    assert out.exit_code == 0, out.output
    from matplotlib.image import imread

    img = imread(png)
    assert img.std() > 0.01                       # not blank
    bad = CliRunner().invoke(main, ["plot", str(path), "--kind", "heights"])
    assert bad.exit_code == 2
