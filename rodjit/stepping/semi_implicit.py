"""Semi-implicit step: stiff linear parts implicit, singular stresses explicit.

One step:  V(dt/2) ∘ K(dt/2) ∘ B(dt) ∘ K(dt/2) ∘ V(dt/2)  where K kicks with stretch,
floor and gravity only, B is the implicit midpoint rule on the linear beam system
(u' = v, M v' = −γ B u; a pentadiagonal solve; exact on its quadratic energy; a plain drift
when γ = 0) and V is an L-stable SDIRK2 viscous sub-step (a tridiagonal solve); see
``splitting``.  Second order; stable for dt·ω ≤ 2 with ω from stretch and floor alone,
whatever γ and μ.
"""
from .splitting import initial_split, step_split
from .._jit import kernel, step_kernel


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    return initial_split(scheme, system, rod, floor, u, v, a, work, True)


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    return step_split(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt, True)
