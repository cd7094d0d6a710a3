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
    def rows(text):
        return [ln for ln in text.splitlines() if len(ln.split()) == 7 and ln.split()[0].isdigit()]

    full = rows(s.report())
    assert len(full) == n and full[-1].endswith("open") and " - " in full[-1]
    short = s.report(max_bounces=2)
    assert "    ..." in short.splitlines() and rows(short) == [full[0], full[-1]]
    assert np.all(np.isfinite(s.bounces["restitution"][:-1]))
