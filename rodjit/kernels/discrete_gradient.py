"""Stable difference quotients of a stress law's primitive (the discrete gradient of MODEL.md §2).

For a law with stress s and primitive P (``value``/``primitive`` of ``rodjit.model.laws``)

    q(a, b) = (P(b) − P(a)) / (b − a) = ∫₀¹ s(a + t(b − a)) dt,
    ∂q/∂b   = (s(b) − q) / (b − a)    = ∫₀¹ t s'(a + t(b − a)) dt,

so q(a, b)·(b − a) = P(b) − P(a) exactly (the energy identity of the discrete-gradient step)
and q → s(a) as b → a.  Two evaluations, chosen per call:

* **quadrature** (4-point Gauss–Legendre on ``value`` and ``deriv``) when the interval is
  short compared with its distance to the singularity, |b − a| ≤ TAU·d with
  d = min(a, b) − lower(p), and does not contain 0 in its interior.  No cancellation; the
  truncation error for a pole of order 3 (both Aiki–Kosugi laws) is ≤ 2.5e-17 relative at
  |b − a| = TAU·d (it scales as (TAU/2)⁸; checked with mpmath in the tests).
* **exact quotient** otherwise.  Its rounding error is ≈ ε_mach (|P(a)| + |P(b)|)/|b − a|;
  since P(0) = 0 and |s| is monotone away from 0 on each side, |P(x)| ≤ |x| max|s|, which
  with |b − a| > TAU·d (or 0 inside (a, b), where |a| + |b| = |b − a|) bounds it by
  ≈ (2/TAU + 2) ε_mach max(|s(a)|, |s(b)|), i.e. ≲ 100 ulps of the stress scale.

Both bounds come on top of the conditioning of s itself: its arguments (the nodes, or a and
b) are floating-point numbers, so next to a pole of order p at distance d the stress is only
defined to a relative p·ε_mach·|x|/d; no evaluation can do better.

A law may be non-smooth at 0 only (the floor's contact switch: σ_b ≡ 0 above 0 and its
derivative jumps there); an interval with 0 inside always takes the exact quotient, which is
accurate there (see above), so the quadrature never integrates across the kink.
"""
import numba

from ..model.laws import deriv, lower, primitive, value

TAU = 0.02

# 4-point Gauss–Legendre on [−1, 1]: nodes ±X1, ±X2 with weights W1, W2
X1 = 0.33998104358485626
X2 = 0.8611363115940526
W1 = 0.6521451548625461
W2 = 0.34785484513745385


@numba.njit(cache=True)
def uses_quadrature(a, b, p):
    """True if ``quotient`` evaluates q(a, b) by quadrature (short interval, no 0 inside)."""
    if a * b < 0.0:
        return False
    return abs(b - a) <= TAU * (min(a, b) - lower(p))


@numba.njit(cache=True)
def quotient(a, pa, b, p):
    """``(q, ∂q/∂b)`` for q(a, b) = (P(b) − P(a))/(b − a) of the law ``p``; ``pa`` = P(a)
    (cached by the caller: a is fixed during a step).  Both a and b must be admissible."""
    if uses_quadrature(a, b, p):
        c = 0.5 * (a + b)
        hw = 0.5 * (b - a)
        fm1 = value(c - X1 * hw, p)
        fp1 = value(c + X1 * hw, p)
        fm2 = value(c - X2 * hw, p)
        fp2 = value(c + X2 * hw, p)
        q = 0.5 * (W1 * (fm1 + fp1) + W2 * (fm2 + fp2))
        # weights t = (1 ± x)/2 of ∫ t s'(a + tΔ) dt at the nodes
        dm1 = deriv(c - X1 * hw, p)
        dp1 = deriv(c + X1 * hw, p)
        dm2 = deriv(c - X2 * hw, p)
        dp2 = deriv(c + X2 * hw, p)
        qp = 0.25 * (W1 * ((1.0 - X1) * dm1 + (1.0 + X1) * dp1)
                     + W2 * ((1.0 - X2) * dm2 + (1.0 + X2) * dp2))
        return q, qp
    delta = b - a
    q = (primitive(b, p) - pa) / delta
    qp = (value(b, p) - q) / delta
    return q, qp
