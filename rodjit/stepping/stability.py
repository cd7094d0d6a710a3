"""Step-size suggestion of the explicit schemes: cfl × the stability limit 2/ω."""

from ..model.laws import deriv
from .._jit import step_kernel


@step_kernel
def explicit_dt(system, floor, omega2, u0, v0, cfl, viscous_limit):
    """cfl · 2/ω at the new state, with two refinements:

    * ``viscous_limit``: also μ·dt·4/h² ≤ 2·cfl (Crank–Nicolson viscous sub-steps);
    * contact anticipation: above the floor σ_b' = 0, so ω does not see the floor.  If
      the bottom could reach it within the step, the step beyond the time of arrival is
      limited by the stiffness at touchdown, 2|σ_b'(0)|/h added to ω².  (The loop ends a
      step on the crossing itself.)
    """
    dt = cfl * 2.0 / omega2 ** 0.5
    if viscous_limit and system.mu > 0.0:
        dt = min(dt, cfl * system.h * system.h / (2.0 * system.mu))
    if u0 > 0.0 and v0 < 0.0 and u0 + v0 * dt < 0.0:
        om2c = omega2 + 2.0 * abs(deriv(0.0, floor)) / system.h
        dt = min(dt, max(cfl * 2.0 / om2c ** 0.5, u0 / -v0))
    return dt
