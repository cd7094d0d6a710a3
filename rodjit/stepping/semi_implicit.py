"""Semi-implicit step: stiff linear parts implicit, singular stresses explicit.

One step:  V(dt/2) ∘ K(dt/2) ∘ B(dt) ∘ K(dt/2) ∘ V(dt/2)  where K kicks with stretch,
floor and gravity only, B is the implicit midpoint rule on the linear beam system
(u' = v, M v' = −γ B u; a pentadiagonal solve; exact on its quadratic energy; a plain drift
when γ = 0) and V is an L-stable SDIRK2 viscous sub-step (a tridiagonal solve).  Second
order; stable for dt·ω ≤ 2 with ω from stretch and floor alone, whatever γ and μ.
"""

from ..kernels.banded import penta_factor, penta_solve
from ..kernels.forces import OK, accel, kick, add_beam_term
from . import workspace as W
from .stability import explicit_dt
from .viscous import viscous_sdirk2
from .._jit import kernel, step_kernel


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    """Acceleration of the initial state; ``(status, value, min_strain, floor_force,
    dt_suggest)``."""
    status, val, emin, fl, om2 = accel(u, a, work[W.S], work[W.K], system, rod, floor, False)
    return status, val, emin, fl, explicit_dt(system, floor, om2, u[0], v[0], scheme.cfl, False)


@kernel
def _beam_matrix(a0, a1, a2, c, h, n):
    """Diagonals of M + c·B with B = h CᵀC, C the curvature rows (1, −2, 1)/h² of nodes
    1..N−1 (so γ/2 uᵀBu is the bending energy)."""
    for j in range(n + 1):
        a0[j] = h if 0 < j < n else 0.5 * h
        a1[j] = 0.0
        a2[j] = 0.0
    w = c / (h * h * h)
    for i in range(1, n):
        a0[i - 1] += w
        a0[i] += 4.0 * w
        a0[i + 1] += w
        a1[i - 1] -= 2.0 * w
        a1[i] -= 2.0 * w
        a2[i - 1] += w


@kernel
def _beam_midpoint(system, u, v, u2, dt, work):
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
        rhs[i] = (h if 0 < i < n else 0.5 * h) * v[i]
    # (M + dt²γ/4 B) v⁺ = M v − dt γ B (u + dt/4 v)
    add_beam_term(y, rhs, work[W.K], h, -dt * gam, False)
    _beam_matrix(work[W.BA0], work[W.BA1], work[W.BA2], 0.25 * dt * dt * gam, h, n)
    penta_factor(work[W.BA0], work[W.BA1], work[W.BA2], work[W.BL1], work[W.BL2], work[W.BDINV])
    penta_solve(work[W.BL1], work[W.BL2], work[W.BDINV], rhs, v)
    for i in range(n + 1):
        u2[i] = u[i] + 0.5 * dt * (vk[i] + v[i])


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    """Trial step from (u, v, a) into (u2, v2, a2); the inputs are never modified.

    Returns ``(status, value, min_strain, floor_force, dt_suggest, w, dissipated)``;
    ``dt_suggest`` is cfl × the stability limit at the new state.
    """
    n = system.n
    h = system.h
    hdt = 0.5 * dt
    diss = 0.0
    if system.mu > 0.0:
        diss += viscous_sdirk2(v, v2, hdt, system, work)
        for i in range(n + 1):
            v2[i] += hdt * a[i]
    else:
        for i in range(n + 1):
            v2[i] = v[i] + hdt * a[i]
    if system.gamma > 0.0:
        _beam_midpoint(system, u, v2, u2, dt, work)
    else:
        for i in range(n + 1):
            u2[i] = u[i] + dt * v2[i]
    status, val, emin, fl, om2 = accel(u2, a2, work[W.S], work[W.K], system, rod, floor, False)
    if status != OK:
        return status, val, emin, fl, 0.0, 0.0, diss
    w = kick(v2, a2, hdt, h)
    if system.mu > 0.0:
        diss += viscous_sdirk2(v2, v2, hdt, system, work)
    return OK, 0.0, emin, fl, explicit_dt(system, floor, om2, u2[0], v2[0], scheme.cfl,
                                           False), w, diss
