"""Pictures of an impact drawn from enough samples: the μ = 100 impact lasts about 12 ms
and the default snapshots are 5 ms apart.  The space-time map and the animation
re-simulate the contact from the snapshot before (true data of the same model, checked
against a run that wrote every millisecond), or warn naming the snapshot interval that
resolves it."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import rodjit
from rodjit import plotting
from rodjit.plotting import dense
from rodjit.plotting.animation import FRAMES_PER_CONTACT, movie_frames
from rodjit.plotting.source import RunSource

pytest.importorskip("matplotlib")

CFG = rodjit.load_preset("paper-mu100").override({"time.t_end": 0.6})


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("dense") / "mu100.h5"
    rodjit.run_to_file(CFG, path)
    return path


@pytest.fixture(scope="module")
def contact(run_file):
    bounces = rodjit.load_file(run_file).bounces
    a, b = float(bounces["t_impact"][0]), float(bounces["t_release"][0])
    assert (b - a) / CFG.output.snapshot_interval < 5     # the case: a sparse contact
    return a, b


def columns(ax) -> np.ndarray:
    """The times of a space-time map's columns (the centres of its cells)."""
    edges = np.asarray(ax.collections[0].get_coordinates())[0, :, 0]
    return (edges[:-1] + edges[1:]) / 2


def test_the_zoom_on_an_impact_has_many_columns_inside_the_contact(run_file, contact):
    a, b = contact
    window = (a - 0.02, b + 0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("error", dense.SparseSnapshots)
        fig = plotting.figure(run_file, "spacetime", t_range=window)
    ax = fig.axes[0]
    t = columns(ax)
    inside = np.unique(t[(t >= a) & (t <= b)])
    assert inside.size >= dense.MIN_SAMPLES
    assert np.all(np.diff(t) > 0)
    assert ax.get_xlim()[0] <= window[0] + 1e-3 and ax.get_xlim()[1] >= window[1] - 1e-3
    assert ax.get_xlabel() == "time t [s]"
    assert ax.get_ylabel() == "natural coordinate x (0: bottom) [m]"
    labels = [h.get_text() for h in ax.get_legend().get_texts()]
    assert any(text.startswith("re-simulated every") for text in labels)
    # the colour scale fitted to the strains drawn, symmetric about 0
    z = np.asarray(ax.collections[0].get_array())
    assert ax.collections[0].get_clim() == pytest.approx((-np.abs(z).max(), np.abs(z).max()))


def test_the_whole_run_resolves_its_contacts_too(run_file, contact):
    a, b = contact
    for source in (run_file, rodjit.simulate(CFG)):      # a file, a Result in memory
        t = columns(plotting.figure(source, "spacetime", quantity="v").axes[0])
        assert np.unique(t[(t >= a) & (t <= b)]).size >= dense.MIN_SAMPLES


def test_nothing_is_re_simulated_beyond_the_run(run_file):
    """A window past the end draws the run up to its last snapshot, no invented future."""
    end = CFG.time.t_end
    ax = plotting.figure(run_file, "spacetime", t_range=(end - 0.02, end + 0.5)).axes[0]
    t = columns(ax)
    assert t.size >= dense.MIN_SAMPLES and t.max() <= end + 1e-9


def test_without_re_simulation_a_warning_names_the_interval_that_resolves_it(
        run_file, contact, tmp_path):
    a, b = contact
    with pytest.warns(dense.SparseSnapshots) as caught:
        fig = plotting.figure(run_file, "spacetime", t_range=(a - 0.02, b + 0.02),
                              dense=False)
    assert len(caught) == 1
    text = str(caught[0].message)
    assert "output.snapshot_interval = 0.005 s" in text
    advised = float(text.split("a run with output.snapshot_interval = ")[1].split(" s")[0])
    assert (b - a) / dense.MIN_SAMPLES / 2.5 <= advised <= (b - a) / dense.MIN_SAMPLES
    t = columns(fig.axes[0])
    assert np.unique(t[(t >= a) & (t <= b)]).size < 5          # the snapshots as they are
    # the advice works: a run with that interval draws the contact from its own snapshots
    fine = tmp_path / "fine.h5"
    rodjit.run_to_file(CFG.override({"output.snapshot_interval": advised}), fine)
    with warnings.catch_warnings():
        warnings.simplefilter("error", dense.SparseSnapshots)
        fig = plotting.figure(fine, "spacetime", t_range=(a - 0.02, b + 0.02), dense=False)
    t = columns(fig.axes[0])
    assert np.unique(t[(t >= a) & (t <= b)]).size >= dense.MIN_SAMPLES


def test_a_failed_re_simulation_draws_the_snapshots_and_warns(run_file, contact, monkeypatch):
    def fails(*args, **kwargs):
        raise ValueError("floor.law 'mine' cannot be imported")

    monkeypatch.setattr(dense, "resimulate", fails)
    a, b = contact
    with pytest.warns(dense.SparseSnapshots, match="re-simulating from a snapshot failed: "
                      "ValueError: floor.law 'mine'"):
        plotting.figure(run_file, "spacetime", t_range=(a - 0.02, b + 0.02))


def test_re_simulated_states_are_those_of_a_run_that_wrote_them(run_file, contact, tmp_path):
    """The continuation from a snapshot against a run with every millisecond written from
    the start (its own steps throughout): the same solution to the integrator's tolerance,
    small against the contact's compression."""
    a, b = contact
    fine = tmp_path / "every_ms.h5"
    rodjit.run_to_file(CFG.override({"output.snapshot_interval": 0.001}), fine)
    reference = rodjit.load_file(fine)
    with RunSource(run_file) as src:
        t, u, v = dense.resimulate(src, a - 0.003, b + 0.003, 0.001)
        start = src.snapshot_times()[np.searchsorted(src.snapshot_times(), a - 0.003) - 1]
    assert t[0] >= a - 0.003 and t[-1] <= b + 0.003 + 1e-12 and t.size >= 15
    rows = np.searchsorted(reference.t, t - 1e-9)
    np.testing.assert_allclose(reference.t[rows], t, atol=1e-9)
    strain = np.diff(u, axis=1) * CFG.rod.N - 1
    reference_strain = np.diff(reference.u[rows], axis=1) * CFG.rod.N - 1
    assert np.abs(strain - reference_strain).max() < 1e-5 * np.abs(reference_strain).max()
    assert np.abs(v - reference.v[rows]).max() < 1e-5 * np.abs(reference.v[rows]).max()
    assert start < a - 0.003                     # continued from the snapshot before


def test_the_movie_does_not_skip_the_impact(run_file, contact):
    a, b = contact
    with warnings.catch_warnings():
        warnings.simplefilter("error", dense.SparseSnapshots)
        with RunSource(run_file) as src:
            s, frames = movie_frames(src, 60)
    t = s.t[frames]
    assert 54 <= frames.size <= 60 and np.all(np.diff(t) > 0)   # two may share a state
    inside = t[(t >= a - 1e-9) & (t <= b + 1e-9)]
    assert inside.size >= FRAMES_PER_CONTACT - 1
    assert np.diff(inside).max() <= 1.5 * (b - a) / (FRAMES_PER_CONTACT - 1)


def test_a_movie_too_short_for_its_contacts_says_the_duration_that_shows_them(run_file):
    """Contacts take at most half the frames: 12 frames over each of the run's contacts
    need twice 12 per contact, at 20 frames a second."""
    with RunSource(run_file) as src:
        n = len(dense.contacts(src, 0.0, CFG.time.t_end))
        seconds = 2 * FRAMES_PER_CONTACT * n / 20
        with pytest.warns(dense.SparseSnapshots, match=rf"duration = {seconds:g} s or more "
                          r"at fps = 20 shows them"):
            s, frames = movie_frames(src, 10, fps=20)
    assert frames.size == 10


def test_a_movie_of_sparse_snapshots_without_re_simulation_warns(run_file, contact):
    with RunSource(run_file) as src:
        with pytest.warns(dense.SparseSnapshots,
                          match=r"^animate: .*output.snapshot_interval = 0.001 s or less"):
            s, frames = movie_frames(src, 60, dense=False)
    a, b = contact
    t = s.t[frames]
    assert ((t >= a) & (t <= b)).sum() < 5


@pytest.mark.slow
def test_the_command_line_says_a_failed_re_simulation_as_one_warning_line(
        run_file, contact, tmp_path, monkeypatch):
    """``rodjit plot`` and ``rodjit animate`` draw the snapshots they have when the run
    cannot be continued here (a law whose module is not imported) and say why in one
    ``warning:`` line naming the setting and the value that resolves it."""
    from click.testing import CliRunner

    from rodjit.cli import main

    def fails(*args, **kwargs):
        raise ImportError("No module named 'my_law'")

    monkeypatch.setattr(dense, "resimulate", fails)
    a, b = contact

    def advised(samples):       # 1, 2 or 5 times a power of ten at most (b - a) / samples
        need = (b - a) / samples
        power = 10.0 ** np.floor(np.log10(need))
        return f"{max(m * power for m in (1, 2, 5) if m * power <= need):.3g}"

    runner = CliRunner()
    plot = ["plot", str(run_file), "--kind", "spacetime", "-o", str(tmp_path / "st.png"),
            "--dpi", "40"]
    movie = ["animate", str(run_file), "-o", str(tmp_path / "rod.gif"), "--fps", "20",
             "--duration", "5", "--dpi", "30"]
    for samples, args in ((dense.MIN_SAMPLES, plot), (FRAMES_PER_CONTACT, movie)):
        r = runner.invoke(main, args)
        assert r.exit_code == 0, r.output
        lines = [ln for ln in r.output.splitlines() if ln.startswith("warning:")]
        assert len(lines) == 1, r.output
        assert "ImportError: No module named 'my_law'" in lines[0]
        assert f"output.snapshot_interval = {advised(samples)} s or less" in lines[0]
        assert r.output.splitlines()[-1].startswith("wrote ")


def test_a_fixed_step_run_is_re_simulated_to_rounding(contact):
    """Under a fixed ``time.dt`` the continuation takes the run's own steps: where it meets
    the run's snapshots it agrees to rounding, not only to a tolerance."""
    cfg = CFG.override({"time.dt": 1e-5, "time.t_end": 0.5})
    res = rodjit.simulate(cfg)
    a, b = contact
    with RunSource(res) as src:
        t, u, v = dense.resimulate(src, a - 0.005, b + 0.005, 0.0005)
    shared = [(i, np.flatnonzero(np.abs(t - ts) < 1e-9)) for i, ts in enumerate(res.t)]
    shared = [(i, j[0]) for i, j in shared if j.size]
    assert len(shared) >= 3                     # the snapshots across the contact
    for i, j in shared:
        assert np.abs(u[j] - res.u[i]).max() < 1e-12
        assert np.abs(v[j] - res.v[i]).max() < 1e-10 * np.abs(res.v).max()


def test_a_movie_of_many_bounces_shares_half_its_frames_among_the_contacts():
    """At μ = 0 (paper-mu0) six contacts of about 130 ms in 5 s: 12 frames each do not fit
    in half of the default 100 frames, but 8 each do; the contacts get those rather than
    the 2 or 3 evenly spread frames that step over them."""
    from rodjit.plotting.animation import MIN_FRAMES_PER_CONTACT, frame_times

    times = np.linspace(0.0, 5.0, 1001)
    spans = [(0.5 + 0.75 * k, 0.63 + 0.75 * k) for k in range(6)]
    t, short, skipped = frame_times(times, spans, 100)
    assert skipped == 0 and short == spans
    assert t.size == 100 and np.all(np.diff(t) >= 0)
    per = 50 // len(spans)
    for a, b in spans:
        inside = t[(t >= a) & (t <= b)]
        assert inside.size >= per
        assert np.diff(inside).max() <= 1.01 * (b - a) / (per - 1)
    # too many contacts for even MIN_FRAMES_PER_CONTACT each: the evenly spread frames,
    # and the number of frames that shows every contact with its full share
    many = [(0.1 + 0.2 * k, 0.2 + 0.2 * k) for k in range(20)]
    assert 50 // len(many) < MIN_FRAMES_PER_CONTACT
    t, short, skipped = frame_times(times, many, 100)
    assert skipped == 2 * FRAMES_PER_CONTACT * len(many) and t.size == 100
