"""One error norm for every adaptive integrator (``control.height_scale``,
``velocity_scale``): the largest over the estimated components of |e| over its scale,
atol in metres for heights and atol·VELOCITY_SCALE for velocities."""
from __future__ import annotations

import numpy as np
import pytest

from rodjit.stepping import control, registry
from rodjit.stepping.integrators import radau


def _norm(eu, ev, u, v, u2, v2, rtol, atol):
    su = atol + rtol * np.maximum(np.abs(u), np.abs(u2))
    sv = atol * control.VELOCITY_SCALE + rtol * np.maximum(np.abs(v), np.abs(v2))
    return max(np.max(np.abs(eu) / su), np.max(np.abs(ev) / sv))


def test_radau_measures_its_estimate_in_the_one_norm():
    """An error concentrated on one node (the bottom in contact) counts in full: a root
    mean square over the 2(N+1) components would divide it by √(2N+2)."""
    rng = np.random.default_rng(3)
    n1 = 21
    u, v, u2, v2 = (rng.normal(size=n1) for _ in range(4))
    work = np.zeros((radau.WORK_ROWS, n1))
    work[radau.EU, 0] = 3e-7          # the bottom node only
    work[radau.EV, 5] = 1e-9
    scheme = radau.Radau5(1e-6, 1e-9)
    got = radau._error(scheme, u, v, u2, v2, work)
    want = _norm(work[radau.EU], work[radau.EV], u, v, u2, v2, 1e-6, 1e-9)
    assert got == pytest.approx(want, rel=1e-14)


@pytest.mark.parametrize("y, y2", [(0.3, -0.7), (0.0, 0.0), (-2.0, 1e-3)])
def test_scales(y, y2):
    s = radau.Radau5(1e-5, 1e-8)
    assert control.height_scale(s, y, y2) == 1e-8 + 1e-5 * max(abs(y), abs(y2))
    assert control.velocity_scale(s, y, y2) == (1e-8 * control.VELOCITY_SCALE
                                                + 1e-5 * max(abs(y), abs(y2)))


def test_every_builtin_integrator_states_the_one_norm():
    first = {s.error_norm.split(";")[0] for s in registry.SCHEMES
             if s.module.startswith("rodjit.")}
    assert len(first) == 1, first
    assert "VELOCITY_SCALE" in first.pop()
