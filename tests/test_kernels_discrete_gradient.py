"""The stable difference quotients of the discrete gradient against 50-digit arithmetic.

q(a, b) = (P(b) − P(a))/(b − a) and ∂q/∂b for both Aiki–Kosugi laws, with arguments drawn
where the evaluation is delicate: nearly coinciding (|b − a| down to 1e-300 relative),
near the singularity, straddling the floor's kink at 0, and at the quadrature/exact-quotient
switch.  The bounds are the ones derived in ``rodjit.kernels.discrete_gradient``.  Both ways
of evaluating are held to them: by evaluations of the law (``quotient``, what a law without
a closed form gets) and the laws' closed forms (``difference``, what the energy step uses).
"""
import math

import mpmath as mp
import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from rodjit.kernels.discrete_gradient import (TAU, TAU2, TAU3, difference, points, quotient,
                                              quotient_slope, uses_quadrature)
from rodjit.model.laws import AikiKosugiFloor, AikiKosugiRod, primitive, value

EPS = np.finfo(float).eps
ROD = AikiKosugiRod(100.0)
FLOOR = AikiKosugiFloor(1e5, 1e-3)
mp.mp.dps = 50


# ---- MODEL.md §1, literally, in 50 digits --------------------------------------------------
def rod_f(e):
    return ROD.kappa / mp.mpf(2) * (e + mp.mpf(1) / 2 - 1 / (2 * (1 + e) ** 3))


def rod_fp(e):
    return ROD.kappa / mp.mpf(2) * (1 + mp.mpf(3) / (2 * (1 + e) ** 4))


def rod_P(e):
    return ROD.kappa / mp.mpf(2) * (e**2 / 2 + e / 2 + 1 / (4 * (1 + e) ** 2) - mp.mpf(1) / 4)


def floor_f(x):
    kb, b = mp.mpf(FLOOR.kappa_b), mp.mpf(FLOOR.beta)
    return kb * (b**3 / (x + b) ** 3 - 1) if x <= 0 else mp.mpf(0)


def floor_fp(x):
    kb, b = mp.mpf(FLOOR.kappa_b), mp.mpf(FLOOR.beta)
    return -3 * kb * b**3 / (x + b) ** 4 if x <= 0 else mp.mpf(0)


def floor_P(x):
    kb, b = mp.mpf(FLOOR.kappa_b), mp.mpf(FLOOR.beta)
    return kb * (-(b**3) / (2 * (x + b) ** 2) - x + b / 2) if x <= 0 else mp.mpf(0)


LAWS = {"rod": (ROD, rod_f, rod_fp, rod_P), "floor": (FLOOR, floor_f, floor_fp, floor_P)}


def _digits(*xs):
    """Decimal digits the literal formulas cancel for arguments of these magnitudes."""
    return max([0.0] + [-math.log10(abs(x)) for x in xs if x != 0])


def exact(law, a, b):
    """q(a, b), ∂q/∂b (the limits s(a), s'(a)/2 when b == a) and the scales max(|s(a)|,
    |s(b)|), max(|s'(a)|, |s'(b)|), to ~40 significant digits.

    The literal formulas cancel O(1) terms down to O(x) or O(x²) near 0, and the quotients
    divide a difference by b − a: the working precision grows with both.
    """
    _, f, fp, P = LAWS[law]
    dps = int(40 + 2 * _digits(a, b) + 2 * _digits(b - a if a != b else 0.0))
    with mp.workdps(dps):
        A, B = mp.mpf(a), mp.mpf(b)
        s_scale = max(abs(f(A)), abs(f(B)))
        d_scale = max(abs(fp(A)), abs(fp(B)))
        if A == B:
            return +f(A), +fp(A) / 2, +s_scale, +d_scale
        q = (P(B) - P(A)) / (B - A)
        return +q, +((f(B) - q) / (B - A)), +s_scale, +d_scale


def check(law, a, b):
    p, f, fp, _ = LAWS[law]
    q = quotient(a, primitive(a, p), b, p)
    qp = quotient_slope(a, b, q, p)
    q_ex, qp_ex, s_scale, d_scale = exact(law, a, b)
    # error bounds of the module docstring: ≲ (2/TAU + 2) ulps of the stress scale, times
    # the conditioning 1 + 4|x|/dist of a pole of order ≤ 4 (s' of both laws) at distance
    # dist; the derivative's exact-quotient branch divides once more by |b − a| > TAU·dist
    dist = min(a, b) - (-1.0 if law == "rod" else -FLOOR.beta)
    cond = 1 + 4 * max(abs(a), abs(b)) / dist
    s_scale = max(s_scale, abs(q_ex))
    if not uses_quadrature(a, b, p):
        d_scale += s_scale / abs(mp.mpf(b) - mp.mpf(a))
    err_q = abs(mp.mpf(q) - q_ex)
    err_qp = abs(mp.mpf(qp) - qp_ex)
    assert err_q <= 4 * (2 / TAU + 2) * EPS * cond * s_scale + 1e-300, (law, a, b, q, q_ex)
    assert err_qp <= 4 * (2 / TAU + 2) * EPS * cond * d_scale + 1e-300, (law, a, b, qp, qp_ex)
    check_closed_form(law, a, b, q_ex, qp_ex, s_scale, d_scale, dist)


def check_closed_form(law, a, b, q_ex, qp_ex, s_scale, d_scale, dist):
    """The law's closed form: a few ulps of the stress scale, times the conditioning of its
    poles (q ∝ q_a⁻²q_b⁻², ∂q/∂b ∝ q_a⁻²q_b⁻³: order ≤ 5) — well inside the bound above.
    Across the floor's switch at 0 it is the exact quotient, with that bound's terms."""
    p, f = LAWS[law][:2]
    q, qp, sb = difference(a, b, p)
    cond = 1 + 5 * max(abs(a), abs(b)) / dist
    # s(b) by the law's own formula, its one division shared: a few ulps, times the
    # conditioning of the pole at b (the literal formula cancels down to O(b) near 0)
    with mp.workdps(int(40 + 2 * _digits(b))):
        sb_ex = f(mp.mpf(b))
    lo = -1.0 if law == "rod" else -FLOOR.beta
    assert abs(mp.mpf(sb) - sb_ex) <= 8 * EPS * (1 + 5 * abs(b) / (b - lo)) * abs(sb_ex), (
        law, a, b, sb, sb_ex)
    if law == "floor" and (a > 0.0) != (b > 0.0):
        d_scale = d_scale + s_scale / abs(mp.mpf(b) - mp.mpf(a))
        tol = 4 * (2 / TAU + 2)
    else:
        tol = 4
    assert abs(mp.mpf(q) - q_ex) <= tol * EPS * cond * s_scale + 1e-300, (law, a, b, q, q_ex)
    assert abs(mp.mpf(qp) - qp_ex) <= tol * EPS * cond * d_scale + 1e-300, (law, a, b, qp,
                                                                            qp_ex)


def _pair(lo, hi, lower):
    """(a, b): a in (lo, hi), b = a + a relative offset of 10^k of the distance to ``lower``.

    Nonzero arguments below 1e-150 in magnitude are left out: there f̂ ∝ x² underflows (a
    height or strain of 1e-150 has no physical meaning; 0 itself is exact)."""
    return st.tuples(
        st.floats(lo, hi, allow_nan=False, exclude_min=True, exclude_max=True),
        st.floats(-300.0, 0.5),
        st.sampled_from([-1.0, 1.0]),
    ).map(lambda t: (t[0], t[0] + t[2] * 10.0 ** t[1] * 0.9 * (t[0] - lower) / 1.0))


def _normal(x):
    return x == 0.0 or abs(x) > 1e-150


SETTINGS = settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@SETTINGS
@given(_pair(-0.999, 3.0, -1.0))
@example((0.0, 1e-300))
@example((-0.5, -0.5))
@example((0.3, 0.3 * (1 + 1e-15)))
@example((-0.99, -0.99 + TAU * 0.01 * (1 - 1e-9)))     # just inside the quadrature range
@example((-0.99, -0.99 + TAU * 0.01 * (1 + 1e-9)))     # just outside
@example((0.5, 0.5 + TAU2 * 1.5 * (1 + 1e-9)))         # 2 → 3 points
@example((0.5, 0.5 - TAU3 * 1.5 * (1 - 1e-9)))         # 3 → 4 points
def test_rod_quotient_matches_high_precision(ab):
    a, b = ab
    assume(b > -1.0 and math.isfinite(b) and _normal(a) and _normal(b))
    check("rod", a, b)


@SETTINGS
@given(_pair(-0.999e-3, 2e-3, -1e-3))
@example((-1e-4, 1e-4))        # straddles the kink at 0
@example((1e-12, -1e-12))
@example((0.0, -1e-300))
@example((-3e-4, -3e-4 * (1 + 1e-13)))
@example((5e-4, 7e-4))         # both above the floor: q ≡ 0
@example((0.0, -9.67e-8))      # from the kink just into contact: σ_b tiny against the pole
def test_floor_quotient_matches_high_precision(ab):
    a, b = ab
    assume(b > -1e-3 and math.isfinite(b) and _normal(a) and _normal(b))
    check("floor", a, b)


@pytest.mark.parametrize("law", ["rod", "floor"])
@pytest.mark.parametrize("m, tau", [(2, TAU2), (3, TAU3), (4, TAU)])
def test_quadrature_truncation_at_the_switches_is_below_rounding(law, m, tau):
    """At |b − a| = tau·d (the widest interval each rule gets) the m-point rule's truncation,
    in 50 digits with exact nodes and weights, is below half an ulp of q even next to the
    pole (the kernel's float nodes and weights add rounding, covered by the tests above)."""
    p, f, _, _ = LAWS[law]
    lo = -1.0 if law == "rod" else -FLOOR.beta
    r = mp.sqrt(mp.mpf(6) / 5)
    x, w = {2: ([-1 / mp.sqrt(3), 1 / mp.sqrt(3)], [1, 1]),
            3: ([-mp.sqrt(mp.mpf(3) / 5), 0, mp.sqrt(mp.mpf(3) / 5)],
                [mp.mpf(5) / 9, mp.mpf(8) / 9, mp.mpf(5) / 9]),
            4: ([s * mp.sqrt(mp.mpf(3) / 7 + c * mp.mpf(2) / 7 * r) for s in (-1, 1) for c in (-1, 1)],
                [(18 - c * mp.sqrt(30)) / 36 for s in (-1, 1) for c in (-1, 1)])}[m]
    worst = 0.0
    # where the pole is nearer than 0 (the distance to 0 takes over beyond about half way)
    for frac in (1e-6, 1e-3, 0.1, 0.3, 0.45):
        a = lo + frac * abs(lo)
        b = a + tau * (a - lo) * (1 - 1e-6)
        assert points(a, b, p) == m
        A, B = mp.mpf(a), mp.mpf(b)
        gl = sum(wk / 2 * f(A + (B - A) * (1 + xk) / 2) for xk, wk in zip(x, w))
        q_ex = exact(law, a, b)[0]
        worst = max(worst, float(abs(gl - q_ex) / abs(q_ex)))
    assert worst < EPS / 2


@pytest.mark.parametrize("law", ["rod", "floor"])
def test_exact_quotient_branch_reproduces_the_primitive_difference(law):
    """Away from coincidence q·(b − a) = P(b) − P(a) to rounding: the energy identity."""
    p = LAWS[law][0]
    rng = np.random.default_rng(5)
    lo = -1.0 if law == "rod" else -FLOOR.beta
    for _ in range(200):
        a, b = lo + abs(lo) * rng.uniform(0.05, 1.5, 2)
        if uses_quadrature(a, b, p):
            continue
        q = quotient(a, primitive(a, p), b, p)
        dp = primitive(b, p) - primitive(a, p)
        assert abs(q * (b - a) - dp) <= 4 * EPS * (abs(primitive(a, p)) + abs(primitive(b, p)))


def test_limits_at_coinciding_arguments():
    """b == a gives the stress and half its derivative (no 0/0), both ways."""
    from rodjit.model.laws import deriv
    for p, x in ((ROD, 0.37), (ROD, -0.8), (ROD, 0.0), (FLOOR, -4e-4), (FLOOR, 3e-4),
                 (FLOOR, 0.0)):
        q = quotient(x, primitive(x, p), x, p)
        qp = quotient_slope(x, x, q, p)
        assert q == pytest.approx(value(x, p), rel=1e-15, abs=1e-300)
        assert qp == pytest.approx(0.5 * deriv(x, p), rel=1e-15, abs=1e-300)
        qc, qpc, sc = difference(x, x, p)
        assert sc == pytest.approx(value(x, p), rel=4 * EPS, abs=1e-300)
        assert qc == pytest.approx(value(x, p), rel=4 * EPS, abs=1e-300)
        assert qpc == pytest.approx(0.5 * deriv(x, p), rel=4 * EPS, abs=1e-300)


@pytest.mark.parametrize("law", ["rod", "floor"])
def test_closed_form_reproduces_the_primitive_difference(law):
    """q·(b − a) = P(b) − P(a) to the rounding of the primitives: the energy identity the
    energy step relies on, for the quotients it actually uses."""
    p = LAWS[law][0]
    rng = np.random.default_rng(7)
    lo = -1.0 if law == "rod" else -FLOOR.beta
    for _ in range(400):
        a = lo + abs(lo) * rng.uniform(1e-3, 1.5)
        b = a + abs(lo) * rng.choice([1e-9, 1e-5, 1e-2, 0.5]) * rng.normal()
        if not b > lo:
            continue
        q = difference(a, b, p)[0]
        dp = primitive(b, p) - primitive(a, p)
        mag = abs(primitive(a, p)) + abs(primitive(b, p))
        assert abs(q * (b - a) - dp) <= 8 * EPS * mag + 1e-300, (a, b)


def test_a_law_without_a_closed_form_gets_the_evaluations():
    """``difference`` of a law that gives none (tests/custom_law.py) is ``quotient``,
    ``quotient_slope`` and ``value``, bit for bit, compiled as in the step."""
    import numba

    import custom_law

    p = custom_law.LogRod(3.0)

    @numba.njit
    def both(a, b, p):
        return difference(a, b, p)

    for a, b in ((0.2, 0.2 + 1e-9), (-0.5, 0.4), (0.1, 0.1 + 1e-3)):
        q = quotient(a, np.nan, b, p)
        assert both(a, b, p) == (q, quotient_slope(a, b, q, p), value(b, p))


@pytest.mark.parametrize("law", ["rod", "floor"])
def test_primitive_left_to_the_quotient_gives_the_same_bits(law):
    """``pa = NaN`` makes ``quotient`` evaluate P(a) itself, and only on the exact branch:
    both paths give exactly the quotient with P(a) passed in (the compiled step relies on
    it)."""
    p = LAWS[law][0]
    rng = np.random.default_rng(11)
    lo = -1.0 if law == "rod" else -FLOOR.beta
    branches = set()
    for _ in range(400):
        a = lo + abs(lo) * rng.uniform(0.05, 1.5)
        b = a + abs(lo) * rng.choice([1e-7, 1e-4, 1e-2, 0.5]) * rng.normal()
        if not b > lo:
            continue
        branches.add(points(a, b, p))
        assert quotient(a, np.nan, b, p) == quotient(a, primitive(a, p), b, p)
    assert branches == {0, 2, 3, 4}
