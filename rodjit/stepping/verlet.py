"""Velocity Verlet (kick–drift–kick), with viscosity by Strang splitting.

One step:  V(dt/2) ∘ K(dt/2) ∘ D(dt) ∘ K(dt/2) ∘ V(dt/2)  where K kicks with the explicit
force (stretch, bending, floor, gravity), D drifts, and V is a Crank–Nicolson viscous
sub-step (``splitting``).  Symmetric and second order; symplectic for μ = 0.  Stable for
dt·ω ≤ 2 with ω² bounded in ``accel``; the viscous limit μ·dt·4/h² ≤ 4·cfl keeps CN from
ringing.
"""
from .splitting import initial_split, step_split
from .._jit import kernel, step_kernel


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    return initial_split(scheme, system, rod, floor, u, v, a, work, False)


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    return step_split(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt, False)
