"""The run summary read back from a file agrees with the in-memory Result."""
import math

import numpy as np
import pytest

import rodjit
from rodjit.output.summary import summarize


@pytest.mark.parametrize("overrides", [{}, {"rod.mu": 100.0, "time.integrator": "semi-implicit"}])
def test_summary_matches_the_result(tmp_path, overrides):
    cfg = rodjit.Config().override({"time.t_end": 2.0, **overrides})
    mem = rodjit.simulate(cfg)
    s = rodjit.run_to_file(cfg, tmp_path / "r.h5")
    again = summarize(tmp_path / "r.h5")
    assert again.report() == s.report() and again.path == s.path
    assert s.status == "completed" and s.t == s.t_end == 2.0
    assert s.energy_error == pytest.approx(mem.energy_error(), rel=1e-12)
    assert s.min_strain == min(mem.diagnostics["min_strain"].min(), mem.bounces["min_strain"].min())
    assert s.min_u0 == min(mem.diagnostics["u_bottom"].min(), mem.bounces["min_u0"].min()) < 0
    assert s.steps == mem.stats["steps"] and s.rejected_steps == mem.stats["rejected_steps"]
    assert s.counts == {"snapshots": mem.t.size, "diagnostics": mem.diagnostics["t"].size,
                        "episodes": mem.episodes["t_start"].size, "bounces": mem.n_bounces}
    assert s.node_steps_per_second > 0 and s.run_time > 0
    label = "energy drift" if cfg.rod.mu == 0 else "energy balance error"
    assert f"{label:<22}{s.energy_error:.3g}" in s.report()


def test_report_lists_open_bounces_and_shortens_long_tables(tmp_path):
    s = rodjit.run_to_file(rodjit.Config().override({"time.t_end": 3.0}), tmp_path / "r.h5")
    n = s.n_bounces
    assert n >= 3
    s.bounces["open"][-1] = True
    s.bounces["restitution"][-1] = math.nan
    s.bounces["t_release"][-1] = math.nan
    s.bounces["ambiguous"][-1] = True
    s.bounces["restitution_energy"][-1] = math.nan

    def rows(text):
        return [ln for ln in text.splitlines() if len(ln.split()) >= 8 and ln.split()[0].isdigit()]

    full = rows(s.report())
    assert len(full) == n and full[-1].split()[-3:] == ["open", "-", "?"] and " - " in full[-1]
    assert all(len(r.split()) == 8 for r in full[:-1] if not r.endswith("?"))
    assert "?: ambiguous" in s.report()
    short = s.report(max_bounces=2)
    assert "    ..." in short.splitlines() and rows(short) == [full[0], full[-1]]
    assert np.all(np.isfinite(s.bounces["restitution"][:-1]))


def assert_same_summary(a, b):
    """Every field equal, floats exactly (NaN equal to NaN), bounce columns bit for bit."""
    for name in a.__dataclass_fields__:
        x, y = getattr(a, name), getattr(b, name)
        if name == "bounces":
            assert sorted(x) == sorted(y)
            for col in y:
                assert x[col].dtype == y[col].dtype, col
                assert np.array_equal(x[col], y[col], equal_nan=x[col].dtype.kind == "f"), col
        elif name == "attrs":
            assert sorted(x) == sorted(y)
            for key in y:
                assert np.array_equal(x[key], y[key]), key
        elif isinstance(x, float) and math.isnan(x):
            assert math.isnan(y), name
        else:
            assert x == y, name


def _interrupt_when_in_contact():
    import os
    import signal
    from rodjit.stepping import layout as L
    state = {"sent": False}

    def progress(run):
        if not state["sent"] and run.arrays.ev[L.IN_CONTACT]:
            state["sent"] = True
            os.kill(os.getpid(), signal.SIGTERM)
    return progress


def test_closed_summary_equals_the_file_read_back(tmp_path, monkeypatch):
    """What run_to_file / resume_file return (built from what the writer kept) is what
    summarize reads back, for completed, interrupted (open bounce), resumed, extended and
    failed runs, with diagnostics spread over many blocks and chunks."""
    import rodjit.driver.run as run_module

    monkeypatch.setattr(run_module, "NODE_STEPS_PER_CALL", 600)
    cfg = rodjit.Config().override({"time.t_end": 1.5, "rod.mu": 2.0,
                                    "output.diagnostics_interval": 1e-4})
    path = tmp_path / "r.h5"
    with pytest.raises(rodjit.RunInterrupted) as info:
        rodjit.run_to_file(cfg, path, progress=_interrupt_when_in_contact())
    s = info.value.summary
    assert s.status == "interrupted" and s.bounces["open"][-1]
    assert_same_summary(s, summarize(path))
    s = rodjit.resume_file(path)                     # diagnostics from both sessions
    assert s.status == "completed" and s.counts["diagnostics"] == 15001 > 8192
    assert_same_summary(s, summarize(path))
    assert_same_summary(rodjit.resume_file(path, t_end=2.0), summarize(path))
    with pytest.raises(rodjit.SimulationError) as failed:
        rodjit.run_to_file(rodjit.Config().override({"time.dt": 1e-3, "time.integrator": "verlet",
                                                     "initial.velocity": -100.0}),
                           tmp_path / "f.h5")
    assert failed.value.summary.status == "failed"
    assert_same_summary(failed.value.summary, summarize(tmp_path / "f.h5"))


def test_extremes_give_the_energy_error_exactly(rng):
    """max |x - e0| from the running max and min of x (in blocks of any size) equals the
    direct computation bit for bit."""
    from rodjit.records.extremes import Extremes

    for _ in range(200):
        n = int(rng.integers(1, 500))
        scale = 10.0 ** rng.uniform(-8, 8)
        total = rng.normal(size=n) * scale
        diss = rng.uniform(0, 1, n) * scale
        e0 = float(rng.normal() * scale + rng.choice([0.0, 1e-3 * scale]))
        ext = Extremes()
        cuts = np.sort(rng.integers(0, n + 1, 3))
        for a, b in zip(np.r_[0, cuts], np.r_[cuts, n]):
            ext.update(total[a:b], diss[a:b], np.abs(total[a:b]), diss[a:b], total[a:b],
                       diss[a:b])
        assert ext.energy_deviation(e0) == float(np.max(np.abs(total + diss - e0)))
        assert ext.kinetic_max == float(np.max(np.abs(total)))
        assert ext.samples == n and ext.force_max == float(np.max(diss))
    assert Extremes().energy_deviation(1.0) == 0.0 and np.isnan(Extremes().energy_error(1.0))
