"""An integrator of one's own: ``time.integrator = "position-verlet"``, registered from
this module (which a sweep's worker processes import by its name, ``Scheme.module``).

Position Verlet, drift–kick–drift:

    u½ = uⁿ + dt/2 vⁿ,    vⁿ⁺¹ = vⁿ + dt a(u½, vⁿ),    uⁿ⁺¹ = u½ + dt/2 vⁿ⁺¹,

with ``a`` the full acceleration of MODEL.md §2 (``kernels.rates.full_accel``: stretch,
bending, floor, viscosity, gravity).  At μ = 0 the force depends on u alone and the step is
the symmetric, symplectic, second-order adjoint of velocity Verlet (``verlet``); the
viscous force is taken with the velocity at the step's start, so with μ > 0 the step is
first order in that term.  The step size is ``time.cfl`` × the stability limit 2/ω of
the explicit force, with the viscous limit (``stepping.stability.explicit_dt``), as
``verlet`` chooses it under ``time.control = "cfl"``; the step has no error estimate, so
it runs under that control.  It evaluates the force twice a step (at u½ for the kick, at
uⁿ⁺¹ for the state the loop keeps), where ``verlet`` needs once.

The loop calls ``initial`` once and ``step`` for each trial step (``stepping.schemes``):
a step writes the new state into ``u2, v2, a2`` and returns a ``StepResult``; a status
other than OK makes the loop retry a shorter step.  docs/extending.md walks through it.
"""
from typing import NamedTuple

from rodjit._jit import kernel
from rodjit.kernels.forces import OK, momentum
from rodjit.kernels.rates import dissipation_rate, full_accel
from rodjit.stepping import registry
from rodjit.stepping import workspace as W
from rodjit.stepping.stability import explicit_dt
from rodjit.stepping.step_result import StepResult


class PositionVerlet(NamedTuple):
    cfl: float


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    status, val, emin, fl, om2 = full_accel(system, rod, floor, u, v, a, work[W.S],
                                            work[W.K], True)
    return StepResult(status, val, emin, fl,
                      explicit_dt(system, floor, om2, u[0], v[0], scheme.cfl, True), 0.0, 0.0)


@kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    half = 0.5 * dt
    for i in range(u.size):               # drift to the middle of the step
        u2[i] = u[i] + half * v[i]
    status, val, emin, fl, om2 = full_accel(system, rod, floor, u2, v, a2, work[W.S],
                                            work[W.K], False)
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
    vm = work[W.V0]                       # a scratch row: the step's mean velocity
    for i in range(u.size):
        v2[i] = v[i] + dt * a2[i]         # kick with the middle's force
        vm[i] = 0.5 * (v[i] + v2[i])
        u2[i] += half * v2[i]             # drift to the end
    status, val, emin, fl, om2 = full_accel(system, rod, floor, u2, v2, a2, work[W.S],
                                            work[W.K], True)
    return StepResult(status, val, emin, fl,
                      explicit_dt(system, floor, om2, u2[0], v2[0], scheme.cfl, True),
                      momentum(v2, system.h), dt * dissipation_rate(system, vm))


SCHEME = registry.register(registry.Scheme(
    "position-verlet", __name__, "PositionVerlet", lambda tc, P: P(float(tc.cfl)),
    W.WORK_ROWS, cfl_control=True, order=2, cap_keys=("time.cfl",)))
