"""A floor law of one's own: ``floor.law = "square-floor"``, registered from this module.

    σ_b(h) = κ_b (β²/(h + β)² − 1) for h ≤ 0, 0 above,        h > −β,

the Aiki–Kosugi floor with the exponent 2 in place of 3: the same stiffness at the surface
per unit β (σ_b'(0) = −2κ_b/β against −3κ_b/β) and a milder barrier, whose stored energy
−σ̂_b grows as β²/(h + β) rather than as its square near the bending limit.  Its primitive
(zero at h = 0) is σ̂_b(h) = κ_b (β − β²/(h + β) − h).  It reads ``floor.kappa_b`` and
``floor.beta``, as the built-in law does.

From Python, import this module before naming the law; from the command line,
``rodjit --import square_floor run --set floor.law=square-floor`` with this folder as the
working directory (or on ``PYTHONPATH``).  A sweep's worker processes import it themselves
(``rodjit.sweeps.point.user_modules``).  docs/extending.md walks through it.
"""
from typing import NamedTuple

from rodjit.laws import Law, law_kernel, register


class SquareFloor(NamedTuple):
    kappa_b: float
    beta: float


@law_kernel
def value(h, p):
    if h > 0.0:
        return 0.0
    r = p.beta / (h + p.beta)
    return p.kappa_b * (r * r - 1.0)


@law_kernel
def deriv(h, p):
    if h > 0.0:
        return 0.0
    r = p.beta / (h + p.beta)
    return -2.0 * p.kappa_b * r * r / (h + p.beta)


@law_kernel
def primitive(h, p):
    if h > 0.0:
        return 0.0
    # κ_b (β − β²/(h + β) − h) = κ_b (β h/(h + β) − h): no cancellation of O(β) terms
    return p.kappa_b * (p.beta * h / (h + p.beta) - h)


@law_kernel
def lower(p):
    return -p.beta


LAW = register(Law(name="square-floor", kind="floor", params=SquareFloor,
                   from_config=lambda floor: SquareFloor(float(floor.kappa_b),
                                                         float(floor.beta)),
                   value=value, deriv=deriv, primitive=primitive, lower=lower,
                   description="kappa_b (beta^2/(h+beta)^2 - 1) for h <= 0, 0 above"))
