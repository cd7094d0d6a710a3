"""A scheme added the way a contributor would: this module plus one registry line.

Symplectic Euler with the explicit force of ``verlet`` (no viscosity), a fixed suggestion
of cfl × 2/ω; tests/test_stepping_registry.py adds its line to the registry.
"""
from typing import NamedTuple

from rodjit.kernels.forces import accel, momentum
from rodjit.stepping import workspace as W
from rodjit.stepping.step_result import StepResult
from rodjit._jit import kernel


class Toy(NamedTuple):
    cfl: float


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    status, val, emin, fl, om2 = accel(u, a, work[W.S], work[W.K], system, rod, floor, True)
    return StepResult(status, val, emin, fl, scheme.cfl * 2.0 / om2 ** 0.5, 0.0, 0.0)


@kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    for i in range(u.size):
        v2[i] = v[i] + dt * a[i]
        u2[i] = u[i] + dt * v2[i]
    status, val, emin, fl, om2 = accel(u2, a2, work[W.S], work[W.K], system, rod, floor, True)
    sstats[0] += 1
    return StepResult(status, val, emin, fl, scheme.cfl * 2.0 / om2 ** 0.5,
                      momentum(v2, system.h), 0.0)
