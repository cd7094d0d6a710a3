"""The Strang kick–drift–kick splitting both explicit-force schemes share.

One step:  V(dt/2) ∘ K(dt/2) ∘ D(dt) ∘ K(dt/2) ∘ V(dt/2),  K a kick with the explicit
acceleration, D the drift of the linear part, V a viscous sub-step.  ``implicit_linear``
selects the scheme (a compile-time constant once inlined):

* False, ``verlet``: bending is in the kick, D is the plain drift, V is Crank–Nicolson;
  the stability bound includes bending and CN's viscous limit.
* True, ``semi-implicit``: bending is in D (the implicit midpoint rule on u' = v,
  M v' = −γBu, see ``beam``), V is the L-stable SDIRK2; the bound has stretch and floor only.
"""
from ..kernels.forces import OK, accel, kick
from . import workspace as W
from .beam import beam_midpoint
from .stability import explicit_dt
from .viscous import viscous_cn, viscous_sdirk2
from .._jit import kernel, step_kernel


@kernel
def initial_split(scheme, system, rod, floor, u, v, a, work, implicit_linear):
    """Acceleration of the initial state; ``(status, value, min_strain, floor_force,
    dt_suggest)``."""
    status, val, emin, fl, om2 = accel(u, a, work[W.S], work[W.K], system, rod, floor,
                                       not implicit_linear)
    return status, val, emin, fl, explicit_dt(system, floor, om2, u[0], v[0], scheme.cfl,
                                              not implicit_linear)


@step_kernel
def _viscous(vin, vout, tau, system, work, implicit_linear):
    if implicit_linear:
        return viscous_sdirk2(vin, vout, tau, system, work)
    return viscous_cn(vin, vout, tau, system, work)


@step_kernel
def step_split(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt, implicit_linear):
    """Trial step from (u, v, a) into (u2, v2, a2); the inputs are never modified.

    Returns ``(status, value, min_strain, floor_force, dt_suggest, w, dissipated)``;
    ``dt_suggest`` is cfl × the stability limit at the new state.
    """
    n = system.n
    h = system.h
    hdt = 0.5 * dt
    diss = 0.0
    if system.mu > 0.0:
        diss += _viscous(v, v2, hdt, system, work, implicit_linear)
        for i in range(n + 1):
            v2[i] += hdt * a[i]
    else:
        for i in range(n + 1):
            v2[i] = v[i] + hdt * a[i]
    if implicit_linear and system.gamma > 0.0:
        beam_midpoint(system, u, v2, u2, dt, work)
    else:
        for i in range(n + 1):
            u2[i] = u[i] + dt * v2[i]
    status, val, emin, fl, om2 = accel(u2, a2, work[W.S], work[W.K], system, rod, floor,
                                       not implicit_linear)
    if status != OK:
        return status, val, emin, fl, 0.0, 0.0, diss
    w = kick(v2, a2, hdt, h)
    if system.mu > 0.0:   # both viscous sub-steps conserve momentum: w is unchanged
        diss += _viscous(v2, v2, hdt, system, work, implicit_linear)
    return OK, 0.0, emin, fl, explicit_dt(system, floor, om2, u2[0], v2[0], scheme.cfl,
                                           not implicit_linear), w, diss
