"""Kick–drift–kick schemes: ``verlet`` and ``semi-implicit`` as rows of one stage table.

A step is the Strang composition

    V(dt/2) ∘ K(dt/2) ∘ D(dt) ∘ K(dt/2) ∘ V(dt/2),

K a kick with the explicit acceleration, D the drift of the linear part, V a viscous
sub-step.  A row of ``STAGES`` chooses each operator:

============== ============================== ===================================== ==========
scheme         K kicks with                   D                                     V
============== ============================== ===================================== ==========
verlet         stretch, bending, floor, g     u += dt v                             CN
semi-implicit  stretch, floor, g              implicit midpoint on u' = v,          SDIRK2
                                              M v' = −γBu (``beam``; u += dt v
                                              when γ = 0)
============== ============================== ===================================== ==========

``verlet`` is symmetric, second order, symplectic for μ = 0, and stable for dt·ω ≤ 2 with
ω² bounded in ``accel`` (bending included), and CN's viscous limit μ·dt·4/h² ≤ 4·cfl keeps
Crank–Nicolson from ringing.  ``semi-implicit`` keeps the stiff linear parts implicit (the
midpoint rule is exact on the beam's quadratic energy; SDIRK2 is L-stable), so its bound
has stretch and floor alone, whatever γ and μ.  Second order both.

The row is a compile-time constant of the scheme's parameter type (``stages``): each
scheme compiles to its own straight-line step.  A new kick–drift–kick variant is one more
parameter class and one more row (plus its line in ``registry``).
"""
from typing import NamedTuple

from numba.extending import overload

from ..kernels.forces import OK, accel, kick
from . import workspace as W
from .beam import beam_midpoint
from .stability import explicit_dt
from .step_result import StepResult
from .viscous import viscous_cn, viscous_sdirk2
from .._jit import STEP_JIT_OPTIONS, kernel, step_kernel

__all__ = ["Verlet", "SemiImplicit", "Stages", "STAGES", "stages", "initial", "step"]


class Verlet(NamedTuple):
    cfl: float


class SemiImplicit(NamedTuple):
    cfl: float


# the drift D and the viscous sub-step V
DRIFT = 0            # u += dt v
BEAM_MIDPOINT = 1    # implicit midpoint on u' = v, M v' = −γBu (a plain drift when γ = 0)
CRANK_NICOLSON = 0
SDIRK2 = 1


class Stages(NamedTuple):
    """One row of the stage table."""

    kick_bending: bool    # K includes the bending force (and ω² its stiffness)
    drift: int            # DRIFT or BEAM_MIDPOINT
    viscous: int          # CRANK_NICOLSON or SDIRK2
    viscous_limit: bool   # the step bound includes the viscous sub-step's limit


STAGES = {
    Verlet: Stages(kick_bending=True, drift=DRIFT, viscous=CRANK_NICOLSON,
                   viscous_limit=True),
    SemiImplicit: Stages(kick_bending=False, drift=BEAM_MIDPOINT, viscous=SDIRK2,
                         viscous_limit=False),
}


def stages(scheme) -> Stages:
    """The stage-table row of a scheme (compiled: a constant of its parameter type)."""
    return STAGES[type(scheme)]


@overload(stages, jit_options=STEP_JIT_OPTIONS)
def _stages_ov(scheme):
    row = STAGES[scheme.instance_class]
    return lambda scheme: row


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    """Acceleration of the initial state and the first step's bound."""
    st = stages(scheme)
    status, val, emin, fl, om2 = accel(u, a, work[W.S], work[W.K], system, rod, floor,
                                       st.kick_bending)
    return StepResult(status, val, emin, fl,
                      explicit_dt(system, floor, om2, u[0], v[0], scheme.cfl,
                                  st.viscous_limit), 0.0, 0.0)


@step_kernel
def _viscous(st, vin, vout, tau, system, work):
    if st.viscous == SDIRK2:
        return viscous_sdirk2(vin, vout, tau, system, work)
    return viscous_cn(vin, vout, tau, system, work)


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    """Trial step from (u, v, a) into (u2, v2, a2); the inputs are never modified.

    ``dt_suggest`` is cfl × the stability limit at the new state.
    """
    st = stages(scheme)
    n = system.n
    h = system.h
    hdt = 0.5 * dt
    diss = 0.0
    if system.mu > 0.0:
        diss += _viscous(st, v, v2, hdt, system, work)
        for i in range(n + 1):
            v2[i] += hdt * a[i]
    else:
        for i in range(n + 1):
            v2[i] = v[i] + hdt * a[i]
    if st.drift == BEAM_MIDPOINT and system.gamma > 0.0:
        beam_midpoint(system, u, v2, u2, dt, work)
    else:
        for i in range(n + 1):
            u2[i] = u[i] + dt * v2[i]
    status, val, emin, fl, om2 = accel(u2, a2, work[W.S], work[W.K], system, rod, floor,
                                       st.kick_bending)
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, diss)
    w = kick(v2, a2, hdt, h)
    if system.mu > 0.0:   # both viscous sub-steps conserve momentum: w is unchanged
        diss += _viscous(st, v2, v2, hdt, system, work)
    return StepResult(OK, 0.0, emin, fl,
                      explicit_dt(system, floor, om2, u2[0], v2[0], scheme.cfl,
                                  st.viscous_limit), w, diss)
