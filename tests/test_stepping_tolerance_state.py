"""One meaning of a tolerance: under tolerance control every integrator keeps the state,
heights and velocities both, near a tight reference.

Each scheme estimates its local error in the one error norm (``control.height_scale``,
``velocity_scale``) over heights and velocities; at rtol 1e-6, atol 1e-9 on ``paper-mu0``
over the first second (one impact, its contact and the rebound) every one of them keeps
the snapshot heights (m) and the velocities over the impact speed √(2g·height) within
1e-3 of dop853 at rtol 1e-12, atol 1e-15.  An estimate of the heights alone (the
kick–drift–kick schemes' before they estimated the velocities) leaves the bottom node's
velocity in contact 1e-2 off.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import rodjit
from rodjit.stepping import registry

BOUND = 1e-3

# paper-mu0 (μ = γ = 0) warns that its first bounce has no continuum limit in N: the
# comparison here is of the semi-discrete system at one N
pytestmark = pytest.mark.filterwarnings("ignore::rodjit.config.ModelWarning")


def _run(integrator, rtol, atol):
    cfg = rodjit.load_preset("paper-mu0").override({
        "time.t_end": 1.0, "time.integrator": integrator, "time.control": "tolerance",
        "time.rtol": rtol, "time.atol": atol, "output.diagnostics_interval": 0.0})
    return cfg, rodjit.simulate(cfg)


@pytest.fixture(scope="module")
def reference():
    return _run("dop853", 1e-12, 1e-15)


@pytest.mark.parametrize("integrator", [s.name for s in registry.SCHEMES
                                        if s.module.startswith("rodjit.")])
def test_a_tolerance_bounds_heights_and_velocities(integrator, reference):
    cfg, ref = reference
    res = _run(integrator, 1e-6, 1e-9)[1]
    np.testing.assert_array_equal(res.t, ref.t)
    assert res.episodes["t_start"].size > 0           # the first second has an impact
    impact_speed = math.sqrt(2.0 * abs(cfg.gravity.g) * cfg.initial.height)
    du = np.abs(res.u - ref.u).max()
    dv = np.abs(res.v - ref.v).max() / impact_speed
    assert du < BOUND and dv < BOUND, (integrator, du, dv)
