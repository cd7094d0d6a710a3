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
    """Parameters of f(ε) = κ/2 (ε + 1/2 − 1/(2(1+ε)³)), ε > −1.

    Attributes
    ----------
    kappa : float
        Elastic modulus κ of the rod [N] (``rod.kappa``).
    """

    kappa: float


class AikiKosugiFloor(NamedTuple):
    """Parameters of σ_b(h) = κ_b (β³/(h+β)³ − 1) for h ≤ 0, 0 above; h > −β.

    Attributes
    ----------
    kappa_b : float
        Stiffness κ_b of the floor [N] (``floor.kappa_b``).
    beta : float
        Bending limit β of the floor [m] (``floor.beta``).
    """

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
def rod_difference(a, b, p):
    # (P(b) − P(a))/(b − a) with 1/q_b² − 1/q_a² = −(b − a)(q_a + q_b)/(q_a q_b)²:
    # q = κ/8 (2σ + X/(q_a q_b)²), σ = a + b, X = 2(q_a q_b)² − q_a − q_b written as
    # q_a(b(2+b) + a q_b²) + q_b(a(2+a) + b q_a²): for strains of one sign every term has
    # that sign (no cancellation near 0 or near the pole; at a = b it is rod_value's form).
    # ∂q/∂b = κ/8 (2 + (2q_a + q_b)/(q_a² q_b³)), a sum of positive terms; f(b) as in
    # rod_value with 1/q_b³ = q_a²·(1/(q_a² q_b³)).  One division for the three.
    qa = 1.0 + a
    qb = 1.0 + b
    qb2 = qb * qb
    inv = 1.0 / (qa * qa * (qb2 * qb))
    x = qa * (b * (2.0 + b) + a * qb2) + qb * (a * (2.0 + a) + b * (qa * qa))
    c = 0.125 * p.kappa
    return (c * (2.0 * (a + b) + x * (qb * inv)),
            c * (2.0 + (2.0 * qa + qb) * inv),
            0.25 * p.kappa * b * (2.0 * (qb2 * qb) + qb2 + qb + 1.0) * ((qa * qa) * inv))


@step_kernel
def rod_lower(p):
    return -1.0


@step_kernel
def floor_contact(h, p):
    # the contact branch κ_b (r³ − 1), r = β/(h+β), for any h > −β (smooth through 0, where
    # it meets the free side): r³ − 1 = (r − 1)(r² + r + 1) and r − 1 = −h/(h+β)
    inv = 1.0 / (h + p.beta)     # one division (the floor is evaluated several times a step)
    r = p.beta * inv
    return -p.kappa_b * (h * inv) * (r * r + r + 1.0)


@step_kernel
def floor_contact_deriv(h, p):
    # −3κ_b r⁴/β = −3κ_b β³/(h+β)⁴: one division
    s = h + p.beta
    s2 = s * s
    b = p.beta
    return -3.0 * p.kappa_b * (b * b * b) / (s2 * s2)


@step_kernel
def floor_value(h, p):
    if h > 0.0:
        return 0.0
    return floor_contact(h, p)


@step_kernel
def floor_deriv(h, p):
    if h > 0.0:
        return 0.0
    return floor_contact_deriv(h, p)


@step_kernel
def floor_primitive(h, p):
    # κ_b (−β³/(2(h+β)²) − h + β/2) = −κ_b h² (2h + 3β) / (2(h+β)²)   (≤ 0)
    if h > 0.0:
        return 0.0
    s = h + p.beta
    return -p.kappa_b * h * h * (2.0 * h + 3.0 * p.beta) / (2.0 * s * s)


@step_kernel
def floor_difference(a, b, p):
    # Both at or below 0: with s = h + β, 1/s_b² − 1/s_a² = −(b − a)(s_a + s_b)/(s_a s_b)²
    # gives q = −κ_b M/(2(s_a s_b)²), M = β s_a b(2β + b) + a s_a s_b² + β s_b a(2β + a)
    # + b s_b s_a² (every term ≤ 0: no cancellation), and ∂q/∂b = −κ_b β³(2s_a + s_b)/
    # (2 s_a² s_b³); σ_b(b) as in floor_value with 1/s_b = s_a² s_b²·(1/(s_a² s_b³)).  One
    # division for the three.  Across the contact switch at 0 (σ_b, P ≡ 0 above) the
    # interval is at least as long as its part below 0, and the exact quotient is accurate.
    if a > 0.0 and b > 0.0:
        return 0.0, 0.0, 0.0
    if a > 0.0 or b > 0.0:
        pa = floor_primitive(a, p)
        q = (floor_primitive(b, p) - pa) / (b - a)
        vb = floor_value(b, p)
        return q, (vb - q) / (b - a), vb
    be = p.beta
    sa = a + be
    sb = b + be
    sa2 = sa * sa
    sb2 = sb * sb
    inv = 1.0 / (sa2 * (sb2 * sb))
    m = (be * sa * (b * (2.0 * be + b)) + a * sa * sb2
         + be * sb * (a * (2.0 * be + a)) + b * sb * sa2)
    c = -0.5 * p.kappa_b
    isb = (sa2 * sb2) * inv
    r = be * isb
    return (c * m * (sb * inv), c * (be * be * be) * (2.0 * sa + sb) * inv,
            -p.kappa_b * (b * isb) * (r * r + r + 1.0))


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
        difference=rod_difference,
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
        difference=floor_difference,
        extension=floor_contact,
        extension_deriv=floor_contact_deriv,
        description="σ_b(h) = κ_b (β³/(h+β)³ − 1) for h ≤ 0, singular as h ↓ −β",
    )
)
