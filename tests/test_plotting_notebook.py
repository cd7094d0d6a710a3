"""rodjit.plot and the pictures of the impact: every kind renders to a non-blank image with
labelled axes, from a Result or a file; the space-time map shows the compression wave;
animations have the frames asked for; figures render inline under pyplot."""
from __future__ import annotations

import io
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from click.testing import CliRunner

import rodjit
from conftest import module_runs
from rodjit import plotting
from rodjit.cli import main
from rodjit.plotting import sweep as sweep_plots

pytest.importorskip("matplotlib")
PIL = pytest.importorskip("PIL.Image")


CFG = rodjit.Config().override({"time.t_end": 1.0, "rod.N": 60})

result, run_file = module_runs(CFG)


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("plots") / "sweep.h5"
    rodjit.sweep(rodjit.Config().override({"time.t_end": 0.8}),
                 {"rod.mu": [0.0, 10.0], "floor.beta": [0.02, 0.05]}, output=path,
                 scheduler="inline")
    return path


def pixels(fig) -> np.ndarray:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=60)
    buf.seek(0)
    return np.asarray(PIL.open(buf).convert("L"), float)


def assert_drawn(fig):
    """Not a blank picture, and every axes with data carries labels with units."""
    assert pixels(fig).std() > 10
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>":
            continue
        assert ax.get_ylabel(), ax
    assert any("[s]" in ax.get_xlabel() or ax.get_xlabel() == "bounce" for ax in fig.axes)
    for ax in fig.axes:
        assert ".h5" not in ax.get_title()


@pytest.mark.parametrize("kind", plotting.KINDS)
def test_every_run_kind_draws_from_a_result_and_from_a_file(result, run_file, kind):
    for source in (result, run_file, str(run_file)):
        fig = rodjit.plot(source, kind)
        assert_drawn(fig)


@pytest.mark.parametrize("kind", sweep_plots.KINDS)
def test_every_sweep_kind_draws_from_a_table_and_from_a_file(sweep_file, kind):
    for source in (sweep_file, rodjit.load_sweep(sweep_file)):
        fig = rodjit.plot(source, kind)
        assert pixels(fig).std() > 10
        ax = fig.axes[0]
        assert ax.get_xlabel() and ax.get_ylabel() and ".h5" not in fig._suptitle.get_text()


def test_restitution_lines_differ_in_marker_and_colour(sweep_file):
    ax = rodjit.plot(sweep_file, "restitution").axes[0]
    lines = [ln for ln in ax.get_lines()
             if not ln.get_label().startswith(("_", "no value"))]
    assert len(lines) == 2
    assert lines[0].get_marker() != lines[1].get_marker()
    assert tuple(lines[0].get_color()) != tuple(lines[1].get_color())


def test_plot_draws_into_a_given_axes(result):
    import matplotlib.figure

    fig = matplotlib.figure.Figure()
    ax = fig.add_subplot(1, 2, 2)
    assert rodjit.plot(result, "heights", ax=ax) is fig
    assert ax.get_lines() and ax.get_xlabel() == "time t [s]"
    assert len(fig.axes) == 1


def test_energy_has_the_drift_on_a_log_scale(result):
    fig = rodjit.plot(result, "energy")
    top, bottom = fig.axes
    assert bottom.get_yscale() == "log" and bottom.get_ylabel() == "relative energy drift"
    assert top.get_ylabel() == "energy [J]"
    viscous = rodjit.simulate(CFG.override({"rod.mu": 5.0, "rod.N": 10}))
    assert rodjit.plot(viscous, "energy").axes[1].get_ylabel() == "energy balance error"


def test_contact_shows_the_bending_limit(result):
    top, bottom = rodjit.plot(result, "contact").axes
    beta = CFG.floor.beta
    limits = [ln for ln in top.get_lines() if "−β" in ln.get_label()]
    assert limits and np.all(np.asarray(limits[0].get_ydata()) == -beta)
    force = bottom.get_lines()[0]
    np.testing.assert_array_equal(force.get_ydata(), result.diagnostics["floor_force"])
    assert bottom.get_ylabel() == "σ_b [N]"


def test_spacetime_shows_the_compression_wave_running_up_and_back(result):
    """During the first contact the strain minimum (the compression front) starts at the
    bottom, climbs past the middle of the rod and comes back down."""
    b = result.bounces
    t0, t1 = float(b["t_impact"][0]), float(b["t_release"][0])
    fig = rodjit.plot(result, "spacetime", t_range=(t0 - 0.02, t1 + 0.02))
    ax = fig.axes[0]
    mesh = ax.collections[0]
    N = CFG.rod.N
    z = np.asarray(mesh.get_array()).reshape(N, -1)     # rows: segments, columns: times
    rows = result.t[(result.t >= t0 - 0.02) & (result.t <= t1 + 0.02)]
    assert z.shape[1] == rows.size
    contact = (rows > t0) & (rows < t1)
    x_min = (np.argmin(z[:, contact], axis=0) + 0.5) / N   # where the strain is smallest
    top = int(np.argmax(x_min))
    assert x_min[:3].max() < 0.3                      # starts at the bottom
    assert x_min.max() > 0.6                          # runs up the rod
    assert x_min[top:].min() < x_min.max() - 0.3      # and back down before release
    assert any(p.get_label().startswith("contact") for p in ax.patches)
    assert ax.get_ylabel() == "natural coordinate x (0: bottom) [m]"


@pytest.mark.parametrize("quantity", ["u", "v"])
def test_spacetime_of_heights_and_velocities(result, quantity):
    fig = rodjit.plot(result, "spacetime", quantity=quantity)
    z = np.asarray(fig.axes[0].collections[0].get_array())
    np.testing.assert_array_equal(z.reshape(CFG.rod.N + 1, -1),
                                  getattr(result, quantity).T)


def test_figures_go_through_pyplot_when_it_is_in_use(tmp_path):
    """Under Jupyter's inline backend a figure is a pyplot figure whose canvas draws."""
    pytest.importorskip("matplotlib_inline")
    script = tmp_path / "inline.py"
    script.write_text(textwrap.dedent("""\
        import matplotlib
        matplotlib.use("module://matplotlib_inline.backend_inline")
        import matplotlib.pyplot as plt
        import rodjit
        r = rodjit.simulate(rodjit.Config().override({"time.t_end": 0.2}))
        fig = rodjit.plot(r, "heights")
        assert fig in [plt.figure(n) for n in plt.get_fignums()]
        fig.canvas.draw()
        print(type(fig.canvas).__name__, fig.canvas.get_width_height())
        """))
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split()[0] == "FigureCanvasAgg"


def test_animation_gif_has_the_frames_asked_for(run_file, tmp_path):
    out = rodjit.animate(run_file, tmp_path / "rod.gif", fps=8, duration=1.5)
    with PIL.open(out) as im:
        assert im.n_frames == 12
        im.seek(6)
        assert np.asarray(im.convert("L"), float).std() > 10


def test_an_animation_under_pyplot_leaves_no_figure_to_redraw(run_file, tmp_path):
    """In a notebook the inline backend draws every open pyplot figure after the cell; the
    animation's figure reads its frames from a file that is closed by then, so pyplot must
    not keep it."""
    plt = pytest.importorskip("matplotlib.pyplot")
    plt.close("all")
    rodjit.animate(run_file, tmp_path / "rod.gif", fps=4, duration=0.5)
    assert plt.get_fignums() == []


def test_animation_reads_one_snapshot_at_a_time(run_file, tmp_path, monkeypatch):
    import h5py

    sizes = []
    original = h5py.Dataset.__getitem__

    def counting(self, key):
        out = original(self, key)
        if self.name == "/snapshots/u":
            sizes.append(np.asarray(out).size)
        return out

    monkeypatch.setattr(h5py.Dataset, "__getitem__", counting)
    rodjit.animate(run_file, tmp_path / "rod.gif", fps=5, duration=1)
    assert sizes and max(sizes) == CFG.rod.N + 1


def test_animation_leaves_no_pyplot_figure_to_redraw_from_the_closed_file(run_file, tmp_path):
    """Under pyplot (a notebook) an open figure would be drawn after the cell, running the
    animation's frame function on a file source already closed."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    before = plt.get_fignums()
    rodjit.animate(run_file, tmp_path / "rod.gif", fps=2, duration=1)
    assert plt.get_fignums() == before


def test_cli_plot_and_animate(run_file, sweep_file, tmp_path):
    runner = CliRunner()
    for suffix in ("png", "pdf", "svg"):
        out = tmp_path / f"st.{suffix}"
        r = runner.invoke(main, ["plot", str(run_file), "--kind", "spacetime", "-o", str(out),
                                 "--dpi", "50", "--figsize", "6,3"])
        assert r.exit_code == 0, r.output
        assert out.stat().st_size > 1000
    with PIL.open(tmp_path / "st.png") as im:
        assert im.size == (300, 150)
    r = runner.invoke(main, ["plot", str(run_file), "-o", str(tmp_path / "x.jpg")])
    assert r.exit_code == 2 and "suffix" in r.output
    r = runner.invoke(main, ["plot", str(run_file), "--figsize", "6"])
    assert r.exit_code == 2 and "--figsize" in r.output
    gif = tmp_path / "rod.gif"
    r = runner.invoke(main, ["animate", str(run_file), "-o", str(gif), "--fps", "4",
                             "--duration", "1"])
    assert r.exit_code == 0, r.output
    with PIL.open(gif) as im:
        assert im.n_frames == 4
    r = runner.invoke(main, ["animate", str(sweep_file)])
    assert r.exit_code == 2 and "sweep file" in r.output


def test_mp4_needs_ffmpeg(run_file, tmp_path, monkeypatch):
    from matplotlib import animation

    monkeypatch.setattr(animation.writers, "is_available", lambda name: False)
    r = CliRunner().invoke(main, ["animate", str(run_file), "-o", str(tmp_path / "rod.mp4")])
    assert r.exit_code == 1
    assert r.output.strip().split("\n")[-1] == (
        "Error: MP4 needs ffmpeg, which is not installed; write a .gif instead or install "
        "ffmpeg")
    assert not (tmp_path / "rod.mp4").exists()


def test_a_sweep_plot_of_only_nan_says_so_and_exits_1(tmp_path):
    path = tmp_path / "nan.h5"
    # too short for any bounce to finish: every restitution is NaN
    rodjit.sweep(rodjit.Config().override({"time.t_end": 0.1}), {"rod.mu": [0.0, 1.0]},
                 output=path, scheduler="inline")
    r = CliRunner().invoke(main, ["plot", str(path), "-o", str(tmp_path / "p.png")])
    assert r.exit_code == 1
    assert "in this figure is NaN" in r.output
    assert not (tmp_path / "p.png").exists()


def test_sweep_panels_one_per_value(sweep_file, tmp_path):
    table = rodjit.load_sweep(sweep_file)
    fig = rodjit.plot(table, "restitution", panels="floor.beta")
    axes = [ax for ax in fig.axes if ax.get_lines()]
    assert len(axes) == 2
    assert "β = 0.02" in axes[0].get_title() and "β = 0.05" in axes[1].get_title()
    for ax, beta in zip(axes, (0.02, 0.05)):
        line = [ln for ln in ax.get_lines()
                if not ln.get_label().startswith(("_", "no value"))] or \
            [ln for ln in ax.get_lines() if ln.get_marker() != "None"]
        mask = table["floor.beta"] == beta
        np.testing.assert_array_equal(line[0].get_ydata(),
                                      table["restitution_first"][mask])   # the default
    r = CliRunner().invoke(main, ["plot", str(sweep_file), "--panels", "floor.beta", "-o",
                                  str(tmp_path / "p.png")])
    assert r.exit_code == 0, r.output


def test_animation_colour_scale_fits_the_data_and_the_time_stamp_is_uncovered(
        run_file, tmp_path, monkeypatch):
    """The strain colour scale spans the frames' strains (a fixed ±0.5 made |ε| <= 0.07
    look white), and the time stamp lies clear of the legend."""
    from rodjit.plotting import animation

    kept = []
    monkeypatch.setattr(animation, "discard", kept.append)
    rodjit.animate(run_file, tmp_path / "rod.gif", fps=4, duration=1)
    fig = kept[0]
    ax = fig.axes[0]
    bar = ax.collections[-1]
    res = rodjit.load_file(run_file)
    rows = animation.frame_rows(res.t.size, 4)
    eps = np.diff(res.u[rows], axis=1) * CFG.rod.N - 1.0
    largest = np.abs(eps).max()
    assert bar.norm.vmax == pytest.approx(1.05 * largest, rel=1e-9)
    assert bar.norm.vmin == -bar.norm.vmax
    assert ax.get_title().startswith("t = ") and ax.get_title().endswith(" s")
    # (not drawn again here: the frames' file is closed) the stamp is the axes' title, the
    # legend the figure's, below the axes, where it cannot cover the stamp
    assert ax.get_legend() is None and len(fig.legends) == 1
    assert fig.axes[1].get_ylabel() == "strain ε [1]"
