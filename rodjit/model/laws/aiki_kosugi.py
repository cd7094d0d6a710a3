"""The stresses of Aiki & Kosugi (MODEL.md §1): rod stress f and floor stress σ_b.

The formulas are MODEL.md's, rearranged algebraically so that no two O(1) terms cancel near
x = 0 (the literal forms lose all relative accuracy there; the NumPy reference in
``rodjit.model.reference`` keeps the literal forms, and the tests check that both agree).
"""
from __future__ import annotations

from typing import NamedTuple


from .base import Law, register
from ..._jit import step_kernel


class AikiKosugiRod(NamedTuple):
    """Parameters of f(ε) = κ/2 (ε + 1/2 − 1/(2(1+ε)³)), ε > −1."""

    kappa: float


class AikiKosugiFloor(NamedTuple):
    """Parameters of σ_b(h) = κ_b (β³/(h+β)³ − 1) for h ≤ 0, 0 above; h > −β."""

    kappa_b: float
    beta: float


@step_kernel
def rod_value(e, p):
    # κ/2 (ε + 1/2 − 1/(2q³)) with q = 1+ε, written as κ ε (2q³ + q² + q + 1) / (4q³)
    q = 1.0 + e
    q2 = q * q
    q3 = q2 * q
    return p.kappa * e * (2.0 * q3 + q2 + q + 1.0) / (4.0 * q3)


@step_kernel
def rod_deriv(e, p):
    q = 1.0 + e
    q2 = q * q
    return 0.5 * p.kappa * (1.0 + 1.5 / (q2 * q2))


@step_kernel
def rod_deriv_max(lo, hi, p):
    # f' = κ/2 (1 + 3/(2q⁴)) decreases in ε, so its largest value on [lo, hi] is at lo.
    # This holds for the floating-point evaluation too (each operation in rod_deriv is
    # monotone in its argument), so it equals the largest rod_deriv over any strains in
    # [lo, hi] bit for bit.
    return rod_deriv(lo, p)


@step_kernel
def rod_primitive(e, p):
    # κ/2 (ε²/2 + ε/2 + 1/(4q²) − 1/4) = κ ε² (2q² + 2q + 1) / (8q²)  (≥ 0, exact near 0)
    q = 1.0 + e
    q2 = q * q
    return p.kappa * e * e * (2.0 * q2 + 2.0 * q + 1.0) / (8.0 * q2)


@step_kernel
def rod_lower(p):
    return -1.0


@step_kernel
def floor_value(h, p):
    # κ_b (r³ − 1), r = β/(h+β); r³ − 1 = (r − 1)(r² + r + 1) and r − 1 = −h/(h+β)
    if h > 0.0:
        return 0.0
    inv = 1.0 / (h + p.beta)     # one division (the floor is evaluated several times a step)
    r = p.beta * inv
    return -p.kappa_b * (h * inv) * (r * r + r + 1.0)


@step_kernel
def floor_deriv(h, p):
    if h > 0.0:
        return 0.0
    # −3κ_b r⁴/β = −3κ_b β³/(h+β)⁴: one division
    s = h + p.beta
    s2 = s * s
    b = p.beta
    return -3.0 * p.kappa_b * (b * b * b) / (s2 * s2)


@step_kernel
def floor_primitive(h, p):
    # κ_b (−β³/(2(h+β)²) − h + β/2) = −κ_b h² (2h + 3β) / (2(h+β)²)   (≤ 0)
    if h > 0.0:
        return 0.0
    s = h + p.beta
    return -p.kappa_b * h * h * (2.0 * h + 3.0 * p.beta) / (2.0 * s * s)


@step_kernel
def floor_lower(p):
    return -p.beta


ROD = register(
    Law(
        name="aiki-kosugi",
        kind="rod",
        params=AikiKosugiRod,
        from_config=lambda rod: AikiKosugiRod(float(rod.kappa)),
        value=rod_value,
        deriv=rod_deriv,
        primitive=rod_primitive,
        lower=rod_lower,
        deriv_max=rod_deriv_max,
        description="f(ε) = κ/2 (ε + 1/2 − 1/(2(1+ε)³)), singular as ε ↓ −1",
    )
)

FLOOR = register(
    Law(
        name="aiki-kosugi",
        kind="floor",
        params=AikiKosugiFloor,
        from_config=lambda floor: AikiKosugiFloor(float(floor.kappa_b), float(floor.beta)),
        value=floor_value,
        deriv=floor_deriv,
        primitive=floor_primitive,
        lower=floor_lower,
        description="σ_b(h) = κ_b (β³/(h+β)³ − 1) for h ≤ 0, singular as h ↓ −β",
    )
)
