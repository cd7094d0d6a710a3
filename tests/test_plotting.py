"""Figures of a run file: the curves drawn, the limits, the errors."""
import numpy as np
import pytest

import rodjit
from rodjit import plotting

pytest.importorskip("matplotlib")


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("plot") / "r.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 1.5}), path)
    return path


def test_heights_draws_every_node_of_a_small_rod(run_file):
    fig = plotting.figure(run_file, "heights")
    ax = fig.axes[0]
    res = rodjit.load_file(run_file)
    lines = [ln for ln in ax.get_lines() if ln.get_label().startswith("x = ")]
    assert len(lines) == 6
    for i, line in enumerate(lines):
        assert np.array_equal(line.get_xdata(), res.t)
        assert np.array_equal(line.get_ydata(), res.u[:, i])


def test_heights_of_a_long_rod_draws_evenly_spaced_nodes(tmp_path):
    path = tmp_path / "long.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.2, "rod.N": 40}), path)
    labels = [ln.get_label() for ln in plotting.figure(path).axes[0].get_lines()
              if ln.get_label().startswith("x = ")]
    assert len(labels) == plotting.MAX_CURVES
    assert labels[0] == "x = 0" and labels[-1] == "x = 1" and "x = 0.5" in labels


def test_energy_and_bounces(run_file):
    res = rodjit.load_file(run_file)
    labels = [ln.get_label() for ln in plotting.figure(run_file, "energy").axes[0].get_lines()]
    assert {"kinetic", "stretch", "floor", "gravity", "total E"} <= set(labels)
    assert "bending" not in labels                     # gamma = 0
    ax = plotting.figure(run_file, "bounces").axes[0]
    points = [ln for ln in ax.get_lines() if ln.get_label() == "restitution"][0]
    closed = ~res.bounces["open"]
    assert np.array_equal(points.get_ydata(), res.bounces["restitution"][closed])


def test_errors(tmp_path):
    path = tmp_path / "nosnap.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.1,
                                                 "output.snapshot_interval": 0}), path)
    with pytest.raises(ValueError, match="no snapshots"):
        plotting.figure(path, "heights")
    with pytest.raises(ValueError, match="kind = 'pie' is not allowed"):
        plotting.figure(path, "pie")


def test_a_contact_window_ranges_over_the_contact(run_file):
    """A time window of the contact plot shows the heights and forces of that window: the
    penetration below the floor is a visible part of the axis, not a sliver of 0-1 m."""
    res = rodjit.load_file(run_file)
    t, u0 = res.diagnostics["t"], res.diagnostics["u_bottom"]
    t_hit = float(t[np.argmin(u0)])
    window = (t_hit - 0.02, t_hit + 0.02)
    shown = (t >= window[0]) & (t <= window[1])
    top, bottom = plotting.figure(run_file, "contact", t_range=window).axes[:2]
    lo, hi = top.get_ylim()
    beta = res.config.floor.beta
    assert lo < min(u0.min(), -beta) and hi >= u0[shown].max()
    assert hi - lo < 1.2 * (max(u0[shown].max(), 0.0) - min(u0.min(), -beta))
    assert top.get_xlim() == pytest.approx(window)
    f = res.diagnostics["floor_force"][shown]
    assert bottom.get_ylim()[1] == pytest.approx(f.max() + 0.05 * f.max(), rel=1e-6)
    assert top.get_ylabel().endswith("[m]") and bottom.get_ylabel().endswith("[N]")


def test_the_default_heights_figure_shows_the_first_impact_beside_the_run(run_file):
    """The whole run hides a 12 ms impact: the default figure adds a panel over the first
    impact (half its duration either side), its contact drawn from enough samples."""
    from rodjit.plotting.dense import MIN_SAMPLES

    res = rodjit.load_file(run_file)
    fig = plotting.figure(run_file, "heights")
    whole, impact = fig.axes[:2]
    a, r = float(res.bounces["t_impact"][0]), float(res.bounces["t_release"][0])
    assert whole.get_xlim() == pytest.approx((res.t[0], res.t[-1]))
    assert impact.get_xlim() == pytest.approx((a - (r - a) / 2, r + (r - a) / 2))
    bottom = [ln for ln in impact.get_lines() if ln.get_label() == "x = 0"][0]
    t = bottom.get_xdata()
    assert np.sum((t >= a) & (t <= r)) >= MIN_SAMPLES
    assert bottom.get_ydata().min() < 0.0                 # the penetration is drawn
    assert impact.get_legend() is not None and whole.get_legend() is None
    # the same window by name, and one panel where the caller gives the axes or a window
    fig2 = plotting.figure(run_file, "heights", t_range="impact")
    assert len(fig2.axes) == 1 and fig2.axes[0].get_xlim() == impact.get_xlim()
    from rodjit.plotting.run import impact_window
    from rodjit.plotting.source import RunSource

    with RunSource(run_file) as src:
        assert impact_window(src) == pytest.approx(impact.get_xlim())
    import matplotlib.pyplot as plt

    _, ax = plt.subplots()
    assert len(plotting.figure(run_file, "heights", ax=ax).axes) == 1
    plt.close("all")


def test_a_run_that_never_reaches_the_floor_has_no_impact_window(tmp_path):
    path = tmp_path / "fall.h5"
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.2}), path)
    assert len(plotting.figure(path, "heights").axes) == 1
    with pytest.raises(plotting.NothingToDraw, match="never reached the floor"):
        plotting.figure(path, "contact", t_range="impact")


@pytest.mark.parametrize("bad", [(0.5, 0.4), (0.1, float("nan")), (0.0, float("inf")),
                                 (1.0,), "first", (0.1, "x")])
def test_a_bad_time_window_is_refused_by_name(run_file, bad):
    with pytest.raises(ValueError, match=r"^t_range = .* (is out of range|is not allowed)"):
        plotting.figure(run_file, "heights", t_range=bad)


def test_the_command_line_takes_a_time_window(run_file, tmp_path):
    from click.testing import CliRunner

    from rodjit.cli import main

    def plot(*args):
        return CliRunner().invoke(main, ["plot", str(run_file), *args])

    r = plot("--kind", "contact", "--t-range", "impact", "-o", str(tmp_path / "a.png"))
    assert r.exit_code == 0 and (tmp_path / "a.png").stat().st_size > 0, r.output
    r = plot("--t-range", "0.5,0.6", "-o", str(tmp_path / "b.png"))
    assert r.exit_code == 0, r.output
    for bad in ("0.6,0.5", "0.5", "a,b", "0.5,inf"):
        r = plot("--t-range", bad, "-o", str(tmp_path / "c.png"))
        assert r.exit_code == 2 and not (tmp_path / "c.png").exists(), r.output
        lines = r.output.strip().splitlines()
        assert len(lines) == 1 and "--t-range" in lines[0] and "T0 < T1" in lines[0]
