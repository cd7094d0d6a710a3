"""Stress laws against MODEL.md §1: values, derivatives, primitives, domains, signs."""
import mpmath as mp
import numpy as np
import pytest

from rodjit.model import reference
from rodjit.model.laws import AikiKosugiFloor, AikiKosugiRod, deriv, lower, primitive, value

ROD = AikiKosugiRod(kappa=100.0)
FLOOR = AikiKosugiFloor(kappa_b=1000.0, beta=0.05)


def mp_f(e, k):
    e = mp.mpf(e)
    return k / 2 * (e + mp.mpf(1) / 2 - 1 / (2 * (1 + e) ** 3))


def mp_fhat(e, k):
    e = mp.mpf(e)
    return k / 2 * (e**2 / 2 + e / 2 + 1 / (4 * (1 + e) ** 2) - mp.mpf(1) / 4)


def mp_sb(h, kb, b):
    h = mp.mpf(h)
    return kb * (b**3 / (h + b) ** 3 - 1) if h <= 0 else mp.mpf(0)


def mp_sbhat(h, kb, b):
    h = mp.mpf(h)
    return kb * (-(b**3) / (2 * (h + b) ** 2) - h + b / 2) if h <= 0 else mp.mpf(0)


EPS = [-0.999, -0.9, -0.5, -0.1, -1e-3, -1e-9, 0.0, 1e-12, 1e-6, 0.01, 0.3, 2.0, 50.0]
HS = [-0.0499, -0.04, -0.025, -0.01, -1e-4, -1e-10, 0.0, 1e-9, 0.2]


@pytest.mark.parametrize("e", EPS)
def test_rod_law_matches_model_md_to_rounding(e):
    mp.mp.dps = 40
    for got, want in [(value(e, ROD), mp_f(e, 100)), (primitive(e, ROD), mp_fhat(e, 100)),
                      (deriv(e, ROD), mp.diff(lambda x: mp_f(x, 100), e))]:
        assert abs(got - float(want)) <= 4e-16 * max(abs(float(want)), 1e-300) + 1e-300


@pytest.mark.parametrize("h", HS)
def test_floor_law_matches_model_md_to_rounding(h):
    mp.mp.dps = 40
    for got, want in [(value(h, FLOOR), mp_sb(h, 1000, mp.mpf(FLOOR.beta))),
                      (primitive(h, FLOOR), mp_sbhat(h, 1000, mp.mpf(FLOOR.beta)))]:
        assert abs(got - float(want)) <= 1e-15 * abs(float(want)) + 1e-30
    if h < 0:
        want = mp.diff(lambda x: mp_sb(x, 1000, mp.mpf(FLOOR.beta)), h)
        assert deriv(h, FLOOR) == pytest.approx(float(want), rel=1e-14)


def test_literal_forms_lose_accuracy_near_zero_but_ours_do_not():
    # the NumPy reference keeps MODEL.md's literal form; near ε = 0 it cancels
    e = 1e-9
    exact = float(mp_fhat(e, 100))
    assert primitive(e, ROD) == pytest.approx(exact, rel=1e-15)
    assert abs(float(reference.rod_energy_density(e, ROD)) - exact) > 1e-3 * exact


def test_key_properties():
    assert deriv(0.0, ROD) == pytest.approx(1.25 * ROD.kappa, rel=1e-15)   # f'(0) = 5κ/4
    assert value(0.0, ROD) == 0.0 and primitive(0.0, ROD) == 0.0
    assert lower(ROD) == -1.0 and lower(FLOOR) == -0.05
    # the floor pushes up, only below the surface, without bound at the bending limit
    assert value(0.1, FLOOR) == 0.0 and value(0.0, FLOOR) == 0.0
    assert value(-0.01, FLOOR) > 0.0 and value(-0.05 + 1e-9, FLOOR) > 1e20
    assert -primitive(-0.05 + 1e-9, FLOOR) > 1e10      # floor energy barrier
    assert value(-1 + 1e-4, ROD) < -1e10               # total compression barrier
    assert deriv(0.0, FLOOR) == pytest.approx(-3 * 1000 / 0.05)


def test_primitive_is_the_integral_of_value():
    from scipy.integrate import quad
    for e in [-0.7, -0.2, 0.4]:
        assert primitive(e, ROD) == pytest.approx(quad(lambda x: value(x, ROD), 0, e, epsabs=0, epsrel=1e-13)[0], rel=1e-11)
    for h in [-0.04, -0.001]:
        assert primitive(h, FLOOR) == pytest.approx(quad(lambda x: value(x, FLOOR), 0, h, epsabs=0, epsrel=1e-13)[0], rel=1e-11)


def test_generic_dispatch_inside_compiled_code():
    import numba

    @numba.njit
    def f(e, p):
        return value(e, p), deriv(e, p), primitive(e, p), lower(p)

    assert f(-0.3, ROD) == (value(-0.3, ROD), deriv(-0.3, ROD), primitive(-0.3, ROD), -1.0)
    assert f(-0.01, FLOOR)[0] == value(-0.01, FLOOR)


def test_the_lower_end_from_python_is_the_compiled_one():
    """``lower`` called from Python evaluates the law's own Python function (no compiled
    dispatch); compiled code calls the kernel. Both give the same number, for every law
    registered with a configuration of the default run."""
    import numba

    import rodjit
    from rodjit.model.laws import get_law, law_names

    @numba.njit
    def compiled(p):
        return lower(p)

    cfg = rodjit.Config().override({"floor.beta": 1e-3})
    for kind, section in (("rod", cfg.rod), ("floor", cfg.floor)):
        for name in law_names(kind):
            try:
                p = get_law(kind, name).from_config(section)
            except (TypeError, ValueError, AttributeError):
                continue            # a law whose parameters the default section lacks
            assert isinstance(lower(p), float)
            assert lower(p) == compiled(p), (kind, name)
    assert lower(FLOOR) == -0.05 and lower(ROD) == -1.0
