"""The steps whose extremes are taken without a search (``stepping.extremes``): a step that
runs one way has its extremes at its ends, and a step whose Bernstein hull cannot beat an
open bounce's running minima leaves them unchanged.  Checked against the search itself on
random steps of the cubic Hermite (the energy, semi-implicit and verlet integrators)."""
from __future__ import annotations

import numpy as np
import pytest

from rodjit.driver.run import parameters
from rodjit.model.laws import value
from rodjit.presets import load_preset
from rodjit.stepping.extremes import (cannot_beat, monotone, search_extremes, state_at,
                                     step_extremes)


@pytest.fixture(scope="module", params=["energy", "semi-implicit"])
def model(request):
    cfg = load_preset("paper-mu100").override({"time.integrator": request.param})
    scheme, _, system, _, floor = parameters(cfg)
    return scheme, system, floor, cfg.rod.N + 1


def _step(rng, n1, h, linear: bool):
    """A step (rows u, v, a at its two ends) of a rod near the floor; ``linear``: each node
    moves at nearly constant velocity, so the step runs one way."""
    dt = 10.0 ** rng.uniform(-5, -3)
    old = np.zeros((3, n1))
    new = np.zeros((3, n1))
    strain = rng.uniform(-0.07, 0.02, n1 - 1)
    old[0] = rng.uniform(-0.01, 0.02) + np.concatenate(([0.0], np.cumsum(h * (1 + strain))))
    new[0] = old[0] + dt * rng.normal(0.0, 2.0, n1)
    if linear:
        v = (new[0] - old[0]) / dt
        old[1] = v * (1 + 1e-3 * rng.uniform(-1, 1, n1))
        new[1] = v * (1 + 1e-3 * rng.uniform(-1, 1, n1))
    else:
        old[1] = rng.normal(0.0, 2.0, n1)
        new[1] = rng.normal(0.0, 2.0, n1)
    return old, new, dt


def _strain_min(u, h):
    return float(np.min(np.diff(u) / h - 1.0))


def test_a_monotone_step_has_its_extremes_at_its_ends(model):
    scheme, system, floor, n1 = model
    h = system.h
    rng = np.random.default_rng(7)
    work, interp = np.zeros((8, n1)), np.zeros((2, n1))
    seen = 0
    for _ in range(400):
        old, new, dt = _step(rng, n1, h, linear=True)
        if not monotone(scheme, old, new, dt):
            continue
        seen += 1
        ff_end = value(new[0][0], floor)
        e_end = _strain_min(new[0], h)
        fast = step_extremes(scheme, old, new, work, interp, system, floor, dt, ff_end, e_end)
        slow = search_extremes(scheme, old, new, work, interp, system, floor, dt, ff_end,
                               e_end)
        # the extremes over the closed step, by sampling it finely
        fine_u, fine_e = np.inf, np.inf
        for theta in np.linspace(0.0, 1.0, 1001):
            state_at(scheme, old, new, work, interp, dt, theta)
            fine_u = min(fine_u, interp[0][0])
            fine_e = min(fine_e, _strain_min(interp[0], h))
        assert fast[0] == min(old[0][0], new[0][0])
        assert abs(fast[0] - fine_u) <= 1e-14 and abs(fast[2] - fine_e) <= 1e-14
        assert fast[1] == max(ff_end, value(fast[0], floor))
        # the search is never more extreme than the step (up to rounding)
        assert slow[0] >= fast[0] - 1e-15 and slow[2] >= fast[2] - 1e-15
    assert seen > 100


def test_a_step_that_cannot_beat_the_running_minima_leaves_them(model):
    scheme, system, floor, n1 = model
    h = system.h
    rng = np.random.default_rng(11)
    work, interp = np.zeros((8, n1)), np.zeros((2, n1))
    skipped = searched = 0
    for _ in range(600):
        old, new, dt = _step(rng, n1, h, linear=False)
        ff_end = value(new[0][0], floor)
        e_end = _strain_min(new[0], h)
        u_min, ff_max, e_min = search_extremes(scheme, old, new, work, interp, system, floor,
                                               dt, ff_end, e_end)
        # running minima a little below or above the step's own
        cur_u = u_min - rng.uniform(-1e-3, 1e-3)
        cur_e = e_min - rng.uniform(-1e-3, 1e-3)
        if cannot_beat(scheme, old, new, dt, h, cur_u, cur_e):
            skipped += 1
            assert u_min > cur_u and e_min > cur_e
            # σ_b grows with the penetration: the largest force stays that of cur_u
            assert ff_max <= value(cur_u, floor)
        else:
            searched += 1
        # a running minimum at or above the step's start can always be beaten
        assert not cannot_beat(scheme, old, new, dt, h, old[0][0], cur_e)
        assert not cannot_beat(scheme, old, new, dt, h, cur_u, _strain_min(old[0], h))
    assert skipped > 50 and searched > 50


def test_dense_output_steps_are_always_searched():
    cfg = load_preset("paper-mu100").override({"time.integrator": "dp54"})
    scheme, _, system, _, floor = parameters(cfg)
    n1 = cfg.rod.N + 1
    old, new, dt = _step(np.random.default_rng(3), n1, system.h, linear=True)
    assert not monotone(scheme, old, new, dt)
    assert not cannot_beat(scheme, old, new, dt, system.h, -1.0, -1.0)
