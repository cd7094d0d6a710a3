"""The implicit sub-steps: viscous (Crank–Nicolson, SDIRK2) and the beam midpoint rule."""
import numpy as np
import pytest
from scipy.linalg import expm

from rodjit.model.system import RodSystem, masses
from rodjit.stepping import workspace as W
from rodjit.stepping.beam import beam_midpoint
from rodjit.stepping.viscous import viscous_cn, viscous_sdirk2


def viscous_matrix(n, mu):
    """μK with R(v) = μ/2 vᵀKv = μ/2 Σ h ((v_{i+1} − v_i)/h)² (MODEL.md §2)."""
    h = 1.0 / n
    D = (np.eye(n + 1, k=1) - np.eye(n + 1))[:-1] / h
    return mu * h * D.T @ D


def bending_matrix(n, gamma):
    h = 1.0 / n
    C = np.zeros((max(n - 1, 0), n + 1))
    for i in range(1, n):
        C[i - 1, i - 1:i + 2] = [1.0, -2.0, 1.0]
    return gamma * h * C.T @ (C / h**4)


@pytest.mark.parametrize("n", [1, 2, 9])
def test_crank_nicolson_solves_its_equation_and_reports_the_dissipation(rng, n):
    mu, tau = 3.0, 0.01
    system = RodSystem(n, 1.0 / n, 0.0, mu, 0.0)
    M, K = np.diag(masses(n)), viscous_matrix(n, mu)
    v0 = rng.normal(size=n + 1)
    v1 = np.zeros(n + 1)
    work = np.zeros((W.WORK_ROWS, n + 1))
    diss = viscous_cn(v0, v1, tau, system, work)
    vbar = 0.5 * (v0 + v1)
    assert np.allclose(M @ (v1 - v0), -tau * K @ vbar, rtol=0, atol=1e-13)
    # the energy it removes is exactly τ·2R(v̄), and momentum is untouched
    assert diss == pytest.approx(tau * vbar @ K @ vbar, rel=1e-12)
    assert np.sum(masses(n) * v1) == pytest.approx(np.sum(masses(n) * v0), rel=1e-13)
    viscous_cn(v0, v0, tau, system, work)        # in place gives the same
    assert np.array_equal(v0, v1)


def test_sdirk2_is_second_order_and_L_stable(rng):
    n, mu = 12, 2.0
    system = RodSystem(n, 1.0 / n, 0.0, mu, 0.0)
    M, K = np.diag(masses(n)), viscous_matrix(n, mu)
    A = -np.linalg.solve(M, K)
    v0 = rng.normal(size=n + 1)
    work = np.zeros((W.WORK_ROWS, n + 1))
    errs = []
    for tau in (1e-4, 5e-5, 2.5e-5):
        v1 = np.zeros(n + 1)
        viscous_sdirk2(v0, v1, tau, system, work)
        errs.append(np.abs(v1 - expm(tau * A) @ v0).max())
    # local error O(τ³) (second order globally)
    assert 7.0 < errs[0] / errs[1] < 9.0 and 7.0 < errs[1] / errs[2] < 9.0
    # L-stable: a huge viscous step leaves essentially only the momentum (constant) mode
    v1 = np.zeros(n + 1)
    diss = viscous_sdirk2(v0, v1, 1e6, system, work)
    w = np.sum(masses(n) * v0)
    assert np.abs(v1 - w).max() < 1e-6 * np.abs(v0).max()
    ke = lambda v: 0.5 * np.sum(masses(n) * v * v)
    assert diss == pytest.approx(ke(v0) - ke(v1), rel=1e-12) and diss > 0


def test_beam_midpoint_conserves_its_quadratic_energy_and_momentum(rng):
    n, gamma, dt = 10, 0.3, 0.02
    system = RodSystem(n, 1.0 / n, gamma, 0.0, 0.0)
    M, B = np.diag(masses(n)), bending_matrix(n, 1.0)
    u = 1 + np.linspace(0, 1, n + 1) + 0.01 * rng.normal(size=n + 1)
    v = rng.normal(size=n + 1)
    work = np.zeros((W.WORK_ROWS, n + 1))
    energy = lambda u, v: 0.5 * v @ M @ v + 0.5 * gamma * u @ B @ u
    e0, p0 = energy(u, v), masses(n) @ v
    v1, u1 = v.copy(), np.zeros(n + 1)
    beam_midpoint(system, u, v1, u1, dt, work)
    assert energy(u1, v1) == pytest.approx(e0, rel=1e-13)
    assert masses(n) @ v1 == pytest.approx(p0, rel=1e-13, abs=1e-14)
    # it is the implicit midpoint rule: M(v1 − v0) = −dt γ B (u0 + u1)/2
    assert np.allclose(M @ (v1 - v), -dt * gamma * B @ (0.5 * (u + u1)), rtol=0, atol=1e-11)
