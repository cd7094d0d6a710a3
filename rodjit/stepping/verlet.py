"""Velocity Verlet (kick–drift–kick), with viscosity by Strang splitting.

One step:  V(dt/2) ∘ K(dt/2) ∘ D(dt) ∘ K(dt/2) ∘ V(dt/2)  where K kicks with the explicit
force (stretch, bending, floor, gravity), D drifts, and V is a Crank–Nicolson viscous
sub-step.  Symmetric and second order; symplectic for μ = 0.  Stable for dt·ω ≤ 2 with
ω² bounded in ``accel``; the viscous limit μ·dt·4/h² ≤ 4·cfl keeps CN from ringing.
"""

from ..kernels.forces import OK, accel, kick
from . import workspace as W
from .stability import explicit_dt
from .viscous import viscous_cn
from .._jit import kernel, step_kernel


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    """Acceleration of the initial state; ``(status, value, min_strain, floor_force,
    dt_suggest)``."""
    status, val, emin, fl, om2 = accel(u, a, work[W.S], work[W.K], system, rod, floor, True)
    return status, val, emin, fl, explicit_dt(system, floor, om2, u[0], v[0], scheme.cfl, True)


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
        diss += viscous_cn(v, v2, hdt, system, work)
        for i in range(n + 1):
            v2[i] += hdt * a[i]
            u2[i] = u[i] + dt * v2[i]
    else:
        for i in range(n + 1):
            vh = v[i] + hdt * a[i]
            v2[i] = vh
            u2[i] = u[i] + dt * vh
    status, val, emin, fl, om2 = accel(u2, a2, work[W.S], work[W.K], system, rod, floor, True)
    if status != OK:
        return status, val, emin, fl, 0.0, 0.0, diss
    w = kick(v2, a2, hdt, h)
    if system.mu > 0.0:
        diss += viscous_cn(v2, v2, hdt, system, work)  # conserves momentum: w unchanged
    return OK, 0.0, emin, fl, explicit_dt(system, floor, om2, u2[0], v2[0], scheme.cfl,
                                           True), w, diss
