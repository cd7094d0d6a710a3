"""The floor's boundary condition (MODEL.md §1): the semi-discrete equations of §2 at rest on
the floor tend to ``γu_xxx − f(ε) − μu_tx = +σ_b`` at x = 0 as h → 0, not to the paper's
``= −σ_b``.

At rest (γ = 0, v = 0) every node balances: node N carries half a segment's weight, each
segment the weight of everything above it, so f(ε_{i+½}) = g (1 − x_{i+½}) and, at node 0,
σ_b(u_0) = −g − f(ε_½) − m_0 g = −g exactly.  The continuum condition's residual
−f(ε(0)) − σ_b(u(0)) is then approximated by −f(ε_½) − σ_b(u_0) = g h/2 → 0 at first order,
while the paper's sign leaves 2g.
"""
from __future__ import annotations

import numpy as np
import pytest

import rodjit
from rodjit.model import reference
from rodjit.model.system import build_system


def _invert_stress(target: float, rod) -> float:
    """ε with f(ε) = target, by bisection (f increases on (−1, ∞))."""
    lo, hi = -1.0 + 1e-15, 10.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if reference.rod_stress(mid, rod) < target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def static_state(config) -> np.ndarray:
    """The semi-discrete rod at rest on the floor, built from the balance of each node."""
    system, rod, floor = build_system(config)
    n, h, g = system.n, system.h, system.g
    x_mid = (np.arange(n) + 0.5) * h
    eps = np.array([_invert_stress(g * (1.0 - x), rod) for x in x_mid])
    kb, beta = floor.kappa_b, floor.beta
    u0 = beta / (1.0 - g / kb) ** (1.0 / 3.0) - beta     # σ_b(u_0) = −g
    return np.concatenate([[u0], u0 + h * np.cumsum(1.0 + eps)])


@pytest.mark.parametrize("n", [5, 40, 320])
def test_static_state_is_an_equilibrium_of_the_semi_discrete_system(n):
    cfg = rodjit.Config().override({"rod.N": n})
    system, rod, floor = build_system(cfg)
    u = static_state(cfg)
    forces = reference.forces(u, np.zeros_like(u), system, rod, floor)
    assert np.max(np.abs(forces)) < 1e-11 * abs(system.g)
    assert u[0] < 0.0                      # pressed into the floor
    assert reference.floor_stress(u[0], floor) == pytest.approx(-system.g, rel=1e-12)


def test_discrete_bottom_balance_tends_to_the_floor_condition_with_plus_sigma_b():
    residual_plus, residual_paper = [], []
    for n in (10, 20, 40, 80, 160):
        cfg = rodjit.Config().override({"rod.N": n})
        system, rod, floor = build_system(cfg)
        u = static_state(cfg)
        f_bottom = float(reference.rod_stress((u[1] - u[0]) / system.h - 1.0, rod))
        sigma = reference.floor_stress(u[0], floor)
        # γ u_xxx − f − μ u_tx − (±σ_b) with γ = 0 and the rod at rest
        residual_plus.append(-f_bottom - sigma)
        residual_paper.append(-f_bottom + sigma)
    residual_plus = np.abs(residual_plus)
    assert np.allclose(residual_plus[:-1] / residual_plus[1:], 2.0, rtol=1e-6)   # first order
    assert residual_plus[-1] < 1e-2 * abs(cfg.gravity.g)
    # the paper's sign: the residual tends to 2|g| instead of 0
    assert residual_paper[-1] == pytest.approx(2.0 * abs(cfg.gravity.g), rel=3e-3)
    assert min(residual_paper) > abs(cfg.gravity.g)


def test_a_viscous_run_settles_on_the_static_state():
    """The dynamics agree: the paper's μ = 100 rod, left to settle, rests in that state."""
    cfg = rodjit.load_preset("paper-mu100").override({
        "time.integrator": "energy", "time.t_end": 30.0, "output.snapshot_interval": 0.0,
        "output.diagnostics_interval": 0.0})
    res = rodjit.simulate(cfg)
    assert np.max(np.abs(res.v_final)) < 1e-6
    assert np.allclose(res.u_final, static_state(cfg), atol=1e-6)
