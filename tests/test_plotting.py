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
