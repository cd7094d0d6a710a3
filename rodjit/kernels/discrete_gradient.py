"""Stable difference quotients of a stress law's primitive (the discrete gradient of MODEL.md §2).

For a law with stress s and primitive P (``value``/``primitive`` of ``rodjit.model.laws``)

    q(a, b) = (P(b) − P(a)) / (b − a) = ∫₀¹ s(a + t(b − a)) dt,
    ∂q/∂b   = (s(b) − q) / (b − a)    = ∫₀¹ t s'(a + t(b − a)) dt,

so q(a, b)·(b − a) = P(b) − P(a) exactly (the energy identity of the discrete-gradient step)
and q → s(a) as b → a.  Two evaluations, chosen per call:

* **quadrature** (Gauss–Legendre on ``value`` and ``deriv``) when the interval is short
  compared with its distance to the singularity, |b − a| ≤ TAU·d with d = min(a, b) −
  lower(p), and with its distance to 0, |b − a| ≤ TAU·min(|a|, |b|) (so it neither
  contains nor touches 0).  No cancellation.  The number of points
  grows with r = |b − a|/d: 2 up to TAU2, 3 up to TAU3, 4 up to TAU.  For a pole of order 3
  the truncation at each switch is ≤ 2.5e-17 of the pole term (it scales as r⁴, r⁶, r⁸);
  for both Aiki–Kosugi laws it stays below half an ulp of q (measured with mpmath in the
  tests), i.e. below the rounding of the float nodes and weights.
  The distance to 0 matters because the stress vanishes there (s(0) = 0: the rod's
  natural length, the floor's switch): just below the floor's kink q is tiny against the
  pole's scale, and a rule's truncation, small against the pole term, is not small
  against q (2 points on (0, −9.67e-8) were 5e-14 off, 230 ulps of q).  The exact quotient
  is accurate there: P(0) = 0, and with |b − a| > TAU·min(|a|, |b|) its cancellation
  (|P(a)| + |P(b)|)/|P(b) − P(a)| ≲ 1 + 2/TAU.
* **exact quotient** otherwise.  Its rounding error is ≈ ε_mach (|P(a)| + |P(b)|)/|b − a|;
  since P(0) = 0 and |s| is monotone away from 0 on each side, |P(x)| ≤ |x| max|s|, which
  with |b − a| > TAU·d (or 0 inside (a, b), where |a| + |b| = |b − a|) bounds it by
  ≈ (2/TAU + 2) ε_mach max(|s(a)|, |s(b)|), i.e. ≲ 100 ulps of the stress scale.

Both bounds come on top of the conditioning of s itself: its arguments (the nodes, or a and
b) are floating-point numbers, so next to a pole of order p at distance d the stress is only
defined to a relative p·ε_mach·|x|/d; no evaluation can do better.

A law that gives ``difference`` (closed forms of q, ∂q/∂b and s(b), ``rodjit.model.laws.Law``)
has it used instead by ``difference`` below: one division and no branch per call, which is
most of the energy step's cost on a short rod.  The tests hold the closed forms of the
Aiki–Kosugi laws to the same bounds as the evaluation here.

A law may be non-smooth at 0 only (the floor's contact switch: σ_b ≡ 0 above 0 and its
derivative jumps there); an interval with 0 inside always takes the exact quotient, which is
accurate there (see above), so the quadrature never integrates across the kink.
"""

import numpy as np

from ..model.laws import deriv, law_of, lower, primitive, value
from ..model.laws import law_for_numba_type
from .._jit import overload, step_kernel

TAU = 0.02      # 4 points up to here, the exact quotient beyond
TAU3 = 1e-3     # 3 points up to here
TAU2 = 1e-4     # 2 points up to here

# Gauss–Legendre on [−1, 1]: nodes ±X with weights W (and 0 with weight W30 for 3 points)
X1 = 0.33998104358485626
X2 = 0.8611363115940526
W1 = 0.6521451548625461
W2 = 0.34785484513745385
X31 = 0.7745966692414834
W30 = 0.8888888888888888
W31 = 0.5555555555555556
X21 = 0.5773502691896258


@step_kernel
def points(a, b, p):
    """Gauss–Legendre points ``quotient`` uses for q(a, b): 2, 3, 4, or 0 for the exact
    quotient (interval long for its distance to the pole or to 0, or with 0 inside)."""
    if a * b < 0.0:
        return 0
    r = abs(b - a)
    if r > TAU * min(abs(a), abs(b)):
        # next to 0, where the stress vanishes (module docstring): the exact quotient
        return 0
    d = min(a, b) - lower(p)
    if r <= TAU2 * d:
        return 2
    if r <= TAU3 * d:
        return 3
    if r <= TAU * d:
        return 4
    return 0


@step_kernel
def uses_quadrature(a, b, p):
    """True if ``quotient`` evaluates q(a, b) by quadrature."""
    return points(a, b, p) > 0


@step_kernel
def quotient(a, pa, b, p):
    """q(a, b) = (P(b) − P(a))/(b − a) of the law ``p``; ``pa`` = P(a), or NaN to have it
    evaluated here if the exact quotient needs it (the quadrature does not: P is then
    not evaluated at all).  Both a and b must be admissible."""
    m = points(a, b, p)
    if m == 0:
        if pa != pa:
            pa = primitive(a, p)
        return (primitive(b, p) - pa) / (b - a)
    c = 0.5 * (a + b)
    hw = 0.5 * (b - a)
    if m == 2:
        return 0.5 * (value(c - X21 * hw, p) + value(c + X21 * hw, p))
    if m == 3:
        return 0.5 * (W30 * value(c, p) + W31 * (value(c - X31 * hw, p) + value(c + X31 * hw, p)))
    return 0.5 * (W1 * (value(c - X1 * hw, p) + value(c + X1 * hw, p))
                  + W2 * (value(c - X2 * hw, p) + value(c + X2 * hw, p)))


@step_kernel
def quotient_slope(a, b, q, p):
    """∂q/∂b for q = ``quotient``(a, P(a), b, p), by the same rule: the exact derivative
    of the computed q (Newton's Jacobian)."""
    m = points(a, b, p)
    if m == 0:
        return (value(b, p) - q) / (b - a)
    # ∫₀¹ t s'(a + tΔ) dt: the nodes c ∓ x·hw sit at t = (1 ∓ x)/2
    c = 0.5 * (a + b)
    hw = 0.5 * (b - a)
    if m == 2:
        return 0.25 * ((1.0 - X21) * deriv(c - X21 * hw, p) + (1.0 + X21) * deriv(c + X21 * hw, p))
    if m == 3:
        return 0.25 * (W30 * deriv(c, p) + W31 * ((1.0 - X31) * deriv(c - X31 * hw, p)
                                                  + (1.0 + X31) * deriv(c + X31 * hw, p)))
    return 0.25 * (W1 * ((1.0 - X1) * deriv(c - X1 * hw, p)
                         + (1.0 + X1) * deriv(c + X1 * hw, p))
                   + W2 * ((1.0 - X2) * deriv(c - X2 * hw, p)
                           + (1.0 + X2) * deriv(c + X2 * hw, p)))


@step_kernel
def _by_evaluations(a, b, p):
    q = quotient(a, np.nan, b, p)
    return q, quotient_slope(a, b, q, p), value(b, p)


def difference(a, b, p):
    """(q(a, b), ∂q/∂b, s(b)): the law's closed form if it has one, else ``quotient``,
    ``quotient_slope`` and ``value``.  What a caller does not use is dead code once
    compiled."""
    law = law_of(p)
    if law.difference is not None:
        return law.difference(a, b, p)
    return _by_evaluations(a, b, p)


@overload(difference)
def _difference_ov(a, b, p):
    impl = law_for_numba_type(p).difference
    if impl is None:
        return lambda a, b, p: _by_evaluations(a, b, p)
    return lambda a, b, p: impl(a, b, p)
