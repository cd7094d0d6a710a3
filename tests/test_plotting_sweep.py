"""Figures of a sweep file: the lines and cells drawn are the table's values."""
import numpy as np
import pytest

import rodjit
from rodjit.plotting.sweep import sweep_figure

pytest.importorskip("matplotlib")

GRID = {"rod.mu": [0.0, 1.0, 10.0], "floor.kappa_b": [1e3, 1e4], "floor.beta": [0.01, 0.05]}


@pytest.fixture(scope="module")
def sweep_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("plot") / "s.h5"
    rodjit.sweep(rodjit.Config().override({"time.t_end": 1.0}), GRID, output=path,
                 scheduler="inline")
    return path


def test_restitution_against_mu_one_line_per_floor(sweep_path):
    table = rodjit.load_sweep(sweep_path)
    ax = sweep_figure(sweep_path).axes[0]
    lines = [ln for ln in ax.get_lines()
             if not ln.get_label().startswith(("_", "no value", "no lift-off"))]
    assert [ln.get_label() for ln in lines] == [
        "κ_b = 1000, β = 0.01", "κ_b = 1000, β = 0.05", "κ_b = 10000, β = 0.01",
        "κ_b = 10000, β = 0.05"]
    for ln, (kb, beta) in zip(lines, [(1e3, 0.01), (1e3, 0.05), (1e4, 0.01), (1e4, 0.05)]):
        mask = (table["floor.kappa_b"] == kb) & (table["floor.beta"] == beta)
        assert np.array_equal(ln.get_xdata(), table["rod.mu"][mask])
        # a point without lift-off breaks the line (it is marked on its own)
        stays = table["impact_status"][mask] == "no lift-off"
        expected = np.where(stays, np.nan, table["restitution_first"][mask])
        assert np.array_equal(ln.get_ydata(), expected, equal_nan=True)
    assert ax.get_xscale() == "linear"          # 0, 1, 10: less than two decades


def test_heatmap_cells_are_the_table_at_the_chosen_mu(sweep_path):
    table = rodjit.load_sweep(sweep_path)
    fig = sweep_figure(sweep_path, "heatmap", quantity="contact_time_first",
                       at={"rod.mu": "1"})
    ax = fig.axes[0]
    z = ax.collections[0].get_array().reshape(2, 2)     # rows: β, columns: κ_b
    for r, beta in enumerate([0.01, 0.05]):
        for c, kb in enumerate([1e3, 1e4]):
            i = np.flatnonzero((table["rod.mu"] == 1.0) & (table["floor.kappa_b"] == kb)
                               & (table["floor.beta"] == beta))[0]
            assert z[r, c] == table["contact_time_first"][i]
    assert "at μ = 1" in ax.get_title()
    assert [t.get_text() for t in ax.get_xticklabels()] == ["1000", "10000"]


def test_a_log_axis_for_values_over_decades(tmp_path):
    path = tmp_path / "log.h5"
    rodjit.sweep(rodjit.Config().override({"time.t_end": 0.5}),
                 {"floor.kappa_b": [1e3, 1e4, 1e5]}, output=path, scheduler="inline")
    ax = sweep_figure(path, x="floor.kappa_b", quantity="min_u0").axes[0]
    assert ax.get_xscale() == "log"
    with pytest.raises(ValueError, match="kind = 'pie' is not allowed"):
        sweep_figure(path, "pie")


def _inside_the_figure(fig, artist) -> bool:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    box = artist.get_window_extent(canvas.get_renderer())
    width, height = canvas.get_width_height()
    return box.x0 >= 0 and box.x1 <= width and box.y1 <= height


@pytest.mark.parametrize("kind, options", [("restitution", {}), ("heatmap", {}),
                                           ("restitution", {"panels": "floor.beta"})])
def test_titles_fit_and_every_axis_has_its_unit(sweep_path, kind, options):
    """The title (the quantity's long description) is wrapped inside the figure, not cut
    at both sides; each axis names its unit: the key's, or the column's from the file."""
    fig = sweep_figure(sweep_path, kind, at={"rod.mu": "1"} if kind == "heatmap" else None,
                       **options)
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>":
            assert ax.get_ylabel() == "restitution_first [1]"
            continue
        assert _inside_the_figure(fig, ax.title), ax.get_title()
        labels = {ax.get_xlabel(), ax.get_ylabel()} - {""}
        assert labels, kind
        for label in labels:
            assert label.endswith("]"), label
    ax = fig.axes[0]
    if kind == "heatmap":
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("κ_b (floor.kappa_b) [N]",
                                                      "β (floor.beta) [m]")
    else:
        assert ax.get_xlabel() == "μ (rod.mu) [N s]"
        assert ax.get_ylabel() == "restitution_first [1]"


def test_a_point_without_a_value_is_marked_not_dropped(tmp_path):
    """The rod dropped from 3 m has not reached the floor by t_end: its restitution is NaN,
    drawn as a marker at the foot of the axes with a legend entry saying so."""
    path = tmp_path / "nan.h5"
    rodjit.sweep(rodjit.Config().override({"time.t_end": 0.6}),
                 {"initial.height": [0.2, 0.5, 3.0]}, output=path, scheduler="inline")
    table = rodjit.load_sweep(path)
    assert np.isnan(table["restitution_first"]).sum() == 1
    ax = sweep_figure(path).axes[0]
    marks = [ln for ln in ax.get_lines() if ln.get_label().startswith("no value")]
    assert len(marks) == 1
    assert list(marks[0].get_xdata()) == [3.0]
    assert ax.get_legend() is not None
    assert "no value" in [t.get_text() for t in ax.get_legend().get_texts()][0]


def test_a_heatmap_of_one_value_says_so(sweep_path):
    """At μ = 10 the rod never lifts off: restitution_first is 0 wherever it has a value. The title
    says so and the colour scale is not a ±0.1 band around a single value."""
    table = rodjit.load_sweep(sweep_path)
    at = table["rod.mu"] == 10.0
    e = table["restitution_first"][at]
    assert np.all(e[np.isfinite(e)] == 0.0)
    ax = sweep_figure(sweep_path, "heatmap", at={"rod.mu": "10"}).axes[0]
    assert "(every value 0)" in ax.get_title()
    assert ax.collections[0].get_clim() == (-1.0, 1.0)
    ax = sweep_figure(sweep_path, "heatmap", at={"rod.mu": "1"}).axes[0]
    assert "every value" not in ax.get_title()
