"""The steps whose extremes are taken without a search (``stepping.extremes``): a step that
runs one way has the extremes of u_0 and of the strain at its ends, checked against the
search itself on random steps of the cubic Hermite (the energy, semi-implicit and verlet
integrators); its floor force is sampled as the search samples it, whatever the law."""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pytest

from rodjit.driver.run import parameters
from rodjit.laws import Law, law_kernel, register
from rodjit.model.laws import value
from rodjit.presets import load_preset
from rodjit.stepping.extremes import monotone, search_extremes, state_at, step_extremes


@pytest.fixture(scope="module", params=["energy", "semi-implicit"])
def model(request):
    cfg = load_preset("paper-mu100").override({"time.integrator": request.param})
    scheme, _, system, _, floor, _ = parameters(cfg)
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


def test_dense_output_steps_are_always_searched():
    cfg = load_preset("paper-mu100").override({"time.integrator": "dp54"})
    scheme, _, system, _, _, _ = parameters(cfg)
    n1 = cfg.rod.N + 1
    old, new, dt = _step(np.random.default_rng(3), n1, system.h, linear=True)
    assert not monotone(scheme, old, new, dt)


class PeakFloor(NamedTuple):
    """A floor stress that peaks at u_0 = ``c`` (a Lorentzian of height ``a``, width ``w``):
    not the largest at the deepest point."""

    a: float
    c: float
    w: float


@law_kernel
def _peak_value(h, p):
    x = (h - p.c) / p.w
    return p.a / (1.0 + x * x)


@law_kernel
def _peak_deriv(h, p):
    x = (h - p.c) / p.w
    q = 1.0 + x * x
    return -2.0 * p.a * x / (p.w * q * q)


@law_kernel
def _peak_primitive(h, p):
    return p.a * p.w * (math.atan((h - p.c) / p.w) - math.atan(-p.c / p.w))


@law_kernel
def _peak_lower(p):
    return -1.0


register(Law(name="peak-floor-test", kind="floor", params=PeakFloor,
             from_config=lambda f: PeakFloor(1.0, 0.005, 0.001), value=_peak_value,
             deriv=_peak_deriv, primitive=_peak_primitive, lower=_peak_lower))


def test_a_monotone_steps_floor_force_is_sampled_whatever_the_law(model):
    """A step running one way in u_0 across the peak of a floor law that does not grow
    with the penetration: the largest force over the step is the peak's (the sample at
    its middle), not the force at its deepest end."""
    scheme, system, _, n1 = model
    floor = PeakFloor(1.0, 0.005, 0.001)
    dt = 1e-3
    old, new = np.zeros((3, n1)), np.zeros((3, n1))
    old[0] = np.arange(n1) * system.h                 # unstrained, bottom at u_0 = 0
    old[1] = new[1] = 10.0                            # rising at 10 m/s: u_0 to 0.01
    new[0] = old[0] + dt * old[1]
    assert monotone(scheme, old, new, dt)
    ff_end = value(new[0][0], floor)
    ends = max(value(old[0][0], floor), ff_end)
    work, interp = np.zeros((8, n1)), np.zeros((2, n1))
    u0, ff, _ = step_extremes(scheme, old, new, work, interp, system, floor, dt, ff_end,
                              0.0)
    assert u0 == 0.0 and ends < 0.04
    assert ff == pytest.approx(1.0, rel=1e-12)        # the peak, at θ = 1/2
    searched = search_extremes(scheme, old, new, work, interp, system, floor, dt, ff_end,
                               0.0)
    assert ff >= searched[1]
