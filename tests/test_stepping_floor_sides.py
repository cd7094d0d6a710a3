"""The embedded pairs hold the floor law to one side of the contact switch per trial step
(``laws.Sided``) and end a step where u_0 leaves that side (``events.hermite_exit``).

Checked: the sided law's values (free side zero, contact side the law continued smoothly
past 0), compiled against Python; the exit of a step found on its quintic Hermite
interpolant, an excursion inside the step included; that every accepted step of a
bouncing run ends on its side or on the crossing; that the first contact is as accurate as
with the law itself and against a tight reference, in fewer trial steps; bit-for-bit
resume through the crossings.
"""
from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np
import pytest

import rodjit
from rodjit.driver.run import Run
from rodjit.model.laws import aiki_kosugi as ak
from rodjit.model.laws.base import (BOTH, CONTACT, FREE, Law, Sided, deriv, lower,
                                    primitive, register, value)
from rodjit.records.result import MemorySink
from rodjit.stepping import events
from rodjit.stepping import layout as L
from rodjit.stepping.loop import _holds_sides
from rodjit._jit import kernel, python_function

from conftest import assert_resume_is_bit_identical

FLOOR = ak.AikiKosugiFloor(1000.0, 0.05)


# ---- the sided law --------------------------------------------------------------------
@kernel
def _sided_values(h, floor, side):
    p = Sided(floor, side)
    return value(h, p), deriv(h, p)


@pytest.mark.parametrize("h", [-0.04, -1e-3, -1e-9, 0.0, 1e-9, 1e-3, 0.2])
def test_sided_law_values_compiled_and_python(h):
    """FREE is σ_b ≡ 0; BOTH is the law; CONTACT is the law at h ≤ 0 and its contact
    branch continued above 0; the compiled overloads and Python give the same numbers."""
    law_v, law_d = ak.floor_value.py_func(h, FLOOR), ak.floor_deriv.py_func(h, FLOOR)
    for side in (FREE, CONTACT, BOTH):
        v, d = _sided_values(h, FLOOR, side)
        # the compiled kernels fuse multiply-adds: equal to rounding
        assert (v, d) == pytest.approx((value(h, Sided(FLOOR, side)),
                                        deriv(h, Sided(FLOOR, side))), rel=1e-14, abs=0.0)
        if side == FREE:
            assert v == 0.0 and d == 0.0
        elif side == BOTH or h <= 0.0:
            assert v == pytest.approx(law_v, rel=1e-14, abs=0.0)
            assert d == pytest.approx(law_d, rel=1e-14, abs=0.0)
        else:
            assert v < 0.0 and d < 0.0     # the contact branch pulls down above the floor


@kernel
def _sided_bounds(h, floor, side):
    p = Sided(floor, side)
    return lower(p), primitive(h, p)


def test_sided_law_lower_and_primitive_compiled_and_python():
    """``lower`` and ``primitive`` of a sided law are the law's own, compiled and from
    Python (which the kernels run as under NUMBA_DISABLE_JIT: a sweep there failed with a
    KeyError on ``Sided``)."""
    for side in (FREE, CONTACT, BOTH):
        p = Sided(FLOOR, side)
        assert lower(p) == lower(FLOOR) == -0.05
        assert primitive(-0.01, p) == primitive(-0.01, FLOOR)
        assert _sided_bounds(-0.01, FLOOR, side) == pytest.approx(
            (lower(FLOOR), primitive(-0.01, FLOOR)), rel=1e-14)


def test_contact_extension_is_smooth_through_the_switch():
    """The extension and its derivative are continuous at 0 and the derivative is the
    extension's slope (so a CONTACT trial sees a smooth force)."""
    ext, dext = ak.floor_contact.py_func, ak.floor_contact_deriv.py_func
    assert ext(0.0, FLOOR) == 0.0
    for h in (-1e-3, 0.0, 1e-3, 0.02):
        eps = 1e-7
        slope = (ext(h + eps, FLOOR) - ext(h - eps, FLOOR)) / (2 * eps)
        assert dext(h, FLOOR) == pytest.approx(slope, rel=1e-6)
    assert dext(-1e-12, FLOOR) == pytest.approx(ak.floor_deriv.py_func(-1e-12, FLOOR),
                                                rel=1e-12)


# ---- the exit of a step -----------------------------------------------------------------
def _exit(poly, dt, free):
    """``hermite_exit`` for u_0(t) = poly(t) on [0, dt]."""
    p = np.polynomial.Polynomial(poly)
    dp, ddp = p.deriv(), p.deriv(2)
    return python_function(events.hermite_exit)(p(0), dp(0), ddp(0), p(dt), dp(dt),
                                                ddp(dt), dt, free), p


def test_exit_of_a_quintic_is_exact():
    """u_0 a quintic: the interpolant is u_0 itself, so the exit is its first root."""
    dt = 2e-3
    poly = [1e-3, -4.0, -9.8, 30.0, 1e3, -2e5]
    s, p = _exit(poly, dt, True)
    roots = [r.real for r in p.roots() if abs(r.imag) < 1e-12 and 0 < r.real < dt]
    assert s * dt == pytest.approx(min(roots), rel=1e-10)
    # from the contact side: a release
    s, p = _exit([-1e-3, 4.0, 9.8], dt, False)
    assert s * dt == pytest.approx(min(r for r in p.roots() if r > 0), rel=1e-10)


def test_exit_finds_an_excursion_inside_the_step():
    """Both ends above the floor, a dip below it inside (a grazing contact): the exit is
    the dip's first root, not 'no exit'; a trajectory that stays above gives 2."""
    dt = 1e-2
    # (t − 0.003)(t − 0.006) + tiny: below 0 between 3 and 6 ms, above at both ends
    poly = np.polynomial.Polynomial.fromroots([3e-3, 6e-3]).coef * 100.0
    s, _ = _exit(poly, dt, True)
    assert s * dt == pytest.approx(3e-3, rel=1e-9)
    s, _ = _exit([1e-3, -0.1, 5.0], dt, True)                    # stays above: min 5e-4
    assert s == 2.0
    # the trial's side is the start's; a start at 0 moving up stays on the free side
    s, _ = _exit([0.0, 1.0, -9.8], dt, True)
    assert s == 2.0


# ---- the loop ---------------------------------------------------------------------------
def _paper(integrator, **over):
    cfg = rodjit.load_preset("paper-mu0")
    return cfg.override({"time.integrator": integrator, "time.t_end": 0.6,
                         "output.snapshot_interval": 0.005,
                         "output.diagnostics_interval": 0.005, **over})


class PlainFloor(NamedTuple):
    """The Aiki–Kosugi floor registered without its extension: the pairs step with the
    law itself (the comparison the sided steps are measured against)."""

    kappa_b: float
    beta: float


register(Law(name="aiki-kosugi-plain-test", kind="floor", params=PlainFloor,
             from_config=lambda f: PlainFloor(float(f.kappa_b), float(f.beta)),
             value=ak.floor_value, deriv=ak.floor_deriv, primitive=ak.floor_primitive,
             lower=ak.floor_lower))


def test_which_runs_hold_sides():
    from rodjit.stepping.integrators.erk import DOP853, DP54
    from rodjit.stepping.integrators.radau import Radau5
    assert _holds_sides(DP54, ak.AikiKosugiFloor) and _holds_sides(DOP853, ak.AikiKosugiFloor)
    assert not _holds_sides(DP54, PlainFloor)
    assert not _holds_sides(Radau5, ak.AikiKosugiFloor)


@pytest.mark.parametrize("integrator", ["dp54", "dop853"])
def test_every_step_ends_on_its_side_or_on_the_crossing(integrator):
    """Step by step through the first bounces: an accepted step that changes the side of
    u_0 ends within a sliver of 0 (the crossing), never deep on the other side."""
    run = Run(_paper(integrator, **{"time.rtol": 1e-8, "time.atol": 1e-8}))
    run.start(MemorySink())
    crossings = 0
    while run.t < 0.6 - 1e-12:
        u0 = run.u[0]
        run.advance(MemorySink(), max_steps=1)
        if (u0 < 0.0) != (run.u[0] < 0.0):
            crossings += 1
            assert min(abs(u0), abs(run.u[0])) < 1e-7, (run.t, u0, run.u[0])
    assert crossings >= 4


def _first_contact(integrator, tol, floor_law="aiki-kosugi"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = rodjit.simulate(_paper(integrator, **{
            "time.t_end": 0.5, "time.rtol": tol, "time.atol": tol, "floor.law": floor_law}))
    return np.vstack([res.u, res.v]), res


@pytest.mark.slow
@pytest.mark.parametrize("integrator", ["dp54", "dop853"])
def test_first_contact_as_accurate_as_the_law_itself_in_fewer_trials(integrator):
    """The fall, the first contact and the chatter after it (0.5 s): against dop853 at
    1e-13 with the law itself, the sided steps are as accurate at 1e-8 and 1e-10 (within
    3× of the law itself, and following the tolerance), with fewer trial steps."""
    ref, _ = _first_contact("dop853", 1e-13, "aiki-kosugi-plain-test")
    sided_ref, _ = _first_contact("dop853", 1e-13)
    assert np.abs(sided_ref - ref).max() < 1e-10          # the same solution
    for tol in (1e-8, 1e-10):
        y, res = _first_contact(integrator, tol)
        yp, rp = _first_contact(integrator, tol, "aiki-kosugi-plain-test")
        err, err_plain = np.abs(y - ref).max(), np.abs(yp - ref).max()
        assert err < max(3 * err_plain, 100 * tol), (tol, err, err_plain)
        trials = res.stats["steps"] + res.stats["rejected_steps"]
        trials_plain = rp.stats["steps"] + rp.stats["rejected_steps"]
        assert trials < trials_plain, (tol, trials, trials_plain)
        assert res.stats["rejected_steps"] < 0.6 * rp.stats["rejected_steps"]


@pytest.mark.parametrize("integrator", ["dp54", "dop853"])
def test_resume_through_crossings_is_bit_identical(integrator):
    cfg = _paper(integrator, **{"time.rtol": 1e-7, "time.atol": 1e-7})
    for max_steps in (37, 101):
        assert_resume_is_bit_identical(cfg, max_steps=max_steps)
