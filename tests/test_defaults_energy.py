"""A default run over 200 s at μ = 0 keeps its energy to 1e-6 relative (docs/integrators.md)."""
import warnings

import numpy as np
import pytest

import rodjit


def test_default_run_keeps_energy_over_200_s_at_mu_0():
    cfg = rodjit.Config().override({"time.t_end": 200.0, "output.snapshot_interval": 0.0,
                                    "output.diagnostics_interval": 0.05})
    # "auto" chooses dop853 with its tolerances divided by the run's length
    assert cfg.rod.mu == 0.0 and cfg.time.integrator == "auto"
    assert cfg.resolve().time.integrator == "dop853"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rodjit.config.ModelWarning)
        res = rodjit.simulate(cfg)
    assert res.config.time.rtol == cfg.time.rtol / 200.0
    e = np.asarray(res.diagnostics["energy_total"])
    assert res.t_final == pytest.approx(200.0)
    assert res.n_bounces > 100
    assert np.abs(e - e[0]).max() <= 1e-6 * abs(e[0])


def test_default_run_warns_that_its_first_bounce_has_no_continuum_limit():
    cfg = rodjit.Config().override({"time.t_end": 0.01})
    with pytest.warns(rodjit.config.ModelWarning, match="no continuum limit"):
        rodjit.simulate(cfg)
    assert not rodjit.Config().override({"rod.gamma": 1e-3}).warnings()
