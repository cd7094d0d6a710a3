"""A new stress law is one module (tests/custom_law.py); the kernels take it unchanged."""
import numpy as np
import pytest

import custom_law  # noqa: F401  (registers "log-test")
import rodjit


@pytest.mark.slow
def test_custom_law_runs_conserves_energy_and_sets_the_wave_speed():
    # small free vibration: ω_1 = π √f'(0) = π √κ for this law (f'(0) = κ, not 5κ/4)
    n, kappa = 40, 64.0
    x = np.linspace(0, 1, n + 1)
    cfg = rodjit.Config().override({"rod.law": "log-test", "rod.N": n, "rod.kappa": kappa,
                                    "gravity.g": 0.0, "time.t_end": 1.0,
                                    "output.snapshot_interval": 1e-3})
    res = rodjit.simulate(cfg, u0=1.0 + x + 1e-6 * np.cos(np.pi * x))
    q = (res.u - 1.0 - x) @ np.cos(np.pi * x)
    i = np.flatnonzero(np.sign(q[:-1]) != np.sign(q[1:]))
    tz = res.t[i] - q[i] * (res.t[i + 1] - res.t[i]) / (q[i + 1] - q[i])
    omega = np.pi / np.polyfit(np.arange(tz.size), tz, 1)[0]
    assert omega == pytest.approx(np.pi * np.sqrt(kappa), rel=2e-3)   # O(h²) = 5e-4 here
    # a drop with bounces: energy conserved at the schemes' accuracy
    res = rodjit.simulate(rodjit.Config().override({"rod.law": "log-test", "time.t_end": 3.0}))
    assert res.n_bounces >= 2 and res.energy_error() < 2e-3
    assert res.diagnostics["min_strain"].min() > -1
