"""The implicit midpoint rule on the linear beam system u' = v, M v' = −γ B u.

Exact on its quadratic energy ½vᵀMv + γ/2 uᵀBu; one pentadiagonal solve per step.
"""
from ..kernels.banded import add_bending, penta_factor, penta_solve
from ..kernels.forces import add_beam_term
from ..kernels.mass import node_mass
from . import workspace as W
from .._jit import kernel


@kernel
def beam_matrix(a0, a1, a2, c, h, n):
    """Diagonals of M + c·B with B = h CᵀC, C the curvature rows (1, −2, 1)/h² of nodes
    1..N−1 (so γ/2 uᵀBu is the bending energy)."""
    for j in range(n + 1):
        a0[j] = node_mass(j, n, h)
        a1[j] = 0.0
        a2[j] = 0.0
    add_bending(a0, a1, a2, c / (h * h * h), n)


@kernel
def beam_midpoint(system, u, v, u2, dt, work):
    """Implicit midpoint on u' = v, M v' = −γ B u over dt: v (in place) and u2."""
    n = system.n
    h = system.h
    gam = system.gamma
    y = work[W.BY]
    vk = work[W.BVK]
    rhs = work[W.VRHS]
    for i in range(n + 1):
        vk[i] = v[i]
        y[i] = u[i] + 0.25 * dt * v[i]
        rhs[i] = node_mass(i, n, h) * v[i]
    # (M + dt²γ/4 B) v⁺ = M v − dt γ B (u + dt/4 v)
    add_beam_term(y, rhs, work[W.K], h, -dt * gam, bool(False))
    beam_matrix(work[W.BA0], work[W.BA1], work[W.BA2], 0.25 * dt * dt * gam, h, n)
    penta_factor(work[W.BA0], work[W.BA1], work[W.BA2], work[W.BL1], work[W.BL2], work[W.BDINV])
    penta_solve(work[W.BL1], work[W.BL2], work[W.BDINV], rhs, v)
    for i in range(n + 1):
        u2[i] = u[i] + 0.5 * dt * (vk[i] + v[i])
