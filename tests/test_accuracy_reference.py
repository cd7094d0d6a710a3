"""Accuracy against independent references (tests/reference/).

(a) The reference solvers themselves: analytic free fall, the energy balance, agreement of
    the semi-discrete (MODEL.md §2) and the P2 finite-element (§1) solvers at order 2 in h
    away from contact, analytic Jacobians.
(b) rodjit's integrators at their defaults against the stored first-bounce reference
    values (tests/reference/reference_values.json, made by
    tests/reference/make_reference.py): restitution, contact time and deepest penetration
    within 1e-4 relative of the semi-discrete reference at the same N, for every
    integrator allowed at that μ.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import rodjit
from rodjit.config import VERLET_MU_MAX, VERLET_WARNING
from reference.fd_semidiscrete import FDSystem
from reference.laws import Params
from reference.p2fe import P2System
from reference.trajectory import integrate_to

REF = json.loads((Path(__file__).parent / "reference" / "reference_values.json").read_text())
RTOL_OBS = 1e-4
COMPARED = ("restitution", "contact_time", "min_u0")


# ----------------------------------------------------------------------------- (a) ----
def _fd_jac_check(system, y):
    J = system.jac(0.0, y)
    J = J.toarray() if hasattr(J, "toarray") else J
    Jn = np.empty_like(J)
    e = 1e-7
    for k in range(system.size):
        d = np.zeros(system.size)
        d[k] = e
        Jn[:, k] = (system.rhs(0.0, y + d) - system.rhs(0.0, y - d)) / (2 * e)
    return np.abs(J - Jn).max() / np.abs(J).max()


def test_reference_jacobians_match_finite_differences():
    rng = np.random.default_rng(7)
    fd = FDSystem(6, Params(gamma=0.01, mu=3.0))
    y = fd.initial(-0.01) + 1e-2 * rng.standard_normal(fd.size)   # in contact
    assert _fd_jac_check(fd, y) < 1e-9
    p2 = P2System(4, Params(mu=3.0))
    y = p2.initial(-0.01) + 1e-2 * rng.standard_normal(p2.size)
    assert _fd_jac_check(p2, y) < 1e-9


def test_reference_free_fall_is_exact():
    """No contact: z = z0 + g t²/2, w = g t for the semi-discrete system (MODEL.md §4),
    whatever the internal motion (a strained rod thrown at v0 = 1 from height 5)."""
    p = Params(mu=2.0)
    s = FDSystem(8, p)
    y0 = s.initial(height=5.0, velocity=1.0, strain=0.02)
    t = np.array([0.1, 0.4, 0.7])
    ys = integrate_to(s.rhs, s.jac, y0, t, rtol=1e-10, atol=1e-12)
    n1 = s.n + 1
    z0 = s.m @ y0[:n1]
    z = ys[:, :n1] @ s.m
    w = ys[:, n1:2 * n1] @ s.m
    assert np.all(ys[:, 0] > 0)
    np.testing.assert_allclose(w, 1.0 + p.g * t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(z, z0 + t + 0.5 * p.g * t**2, rtol=0, atol=1e-9)


@pytest.mark.parametrize("mu", [0.0, 100.0])
def test_reference_energy_balance_through_the_first_bounce(mu):
    """E_h + dissipated = E_h(0) (MODEL.md §2) through the impact, to the tolerance."""
    s = FDSystem(5, Params(mu=mu))
    y0 = s.initial(1.0)
    t = np.linspace(0.3, 0.6, 61)                   # before, in and after the contact
    ys = integrate_to(s.rhs, s.jac, y0, t, rtol=1e-10, atol=1e-12)
    E0, _ = s.energy(y0)
    bal = np.array([sum(s.energy(y)) for y in ys])
    assert np.any(ys[:, 0] < 0) and ys[0, 0] > 0    # the rod reaches the floor
    np.testing.assert_allclose(bal, E0, rtol=1e-7)
    if mu > 0:
        assert ys[-1, -1] > 1e-2 * abs(E0)          # something was dissipated


def test_p2_energy_balance_through_the_first_bounce():
    s = P2System(5, Params(mu=100.0))
    y0 = s.initial(1.0)
    ys = integrate_to(s.rhs, s.jac, y0, np.array([0.46, 0.55]), rtol=1e-10, atol=1e-12)
    E0, _ = s.energy(y0)
    np.testing.assert_allclose([sum(s.energy(y)) for y in ys], E0, rtol=1e-7)


def test_semi_discrete_converges_to_p2_at_order_two_away_from_contact():
    """No floor contact (g = 0, a strained, moving rod high up): the lumped-mass finite
    differences of MODEL.md §2 converge to the P2 continuum solution at order 2 in h.
    Non-stiff here (small μ), so an explicit high-order SciPy method steps both."""
    from scipy.integrate import DOP853

    p = Params(mu=0.05, g=0.0)
    t = np.array([0.25])
    probe = np.array([0.0, 0.5, 1.0])

    def at_probes(system, x):
        y = system.initial(height=2.0)
        n1 = len(x)
        y[:n1] = 2.0 + x + 0.03 * np.sin(np.pi * x)          # non-uniform strain
        y[n1:2 * n1] = 0.2 * np.cos(np.pi * x)
        y = integrate_to(system.rhs, None, y, t, rtol=1e-11, atol=1e-13, method=DOP853)[0]
        return np.interp(probe, x, y[:n1])

    fine, coarse = P2System(32, p), P2System(16, p)
    ref = at_probes(fine, fine.x)
    p2_err = np.abs(at_probes(coarse, coarse.x) - ref).max()
    errs = []
    for n in (32, 64, 128):
        s = FDSystem(n, p)
        errs.append(np.abs(at_probes(s, np.arange(n + 1) * s.h) - ref).max())
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.3), (errs, orders)
    assert p2_err < 0.5 * errs[-1]          # the continuum reference is far more accurate


def test_reference_values_are_converged_in_the_tolerance():
    """The stored semi-discrete values carry a tolerance-ladder error estimate far below
    the 1e-4 the integrators are held to."""
    for key, entry in REF["semi_discrete"].items():
        assert entry["closed"], key
        for name in COMPARED:
            est = entry["error_estimate"][name] / abs(entry["values"][name])
            assert est < 1e-6, (key, name, est)


def test_semi_discrete_references_approach_the_continuum():
    """The N = 200 semi-discrete first bounce is close to the P2 continuum one (μ > 0: no
    shocks, MODEL.md §4), closer than N = 5."""
    for mu in (1, 100, 1000):
        cont = REF["continuum"][f"mu={mu}"]["values"]
        for name in COMPARED:
            d5 = abs(REF["semi_discrete"][f"N=5,mu={mu}"]["values"][name] - cont[name])
            d200 = abs(REF["semi_discrete"][f"N=200,mu={mu}"]["values"][name] - cont[name])
            assert d200 < d5 or d200 < 1e-3 * abs(cont[name]), (mu, name, d5, d200)


# ----------------------------------------------------------------------------- (b) ----
def _rodjit_first_bounce(integrator, mu, n):
    cfg = rodjit.load_preset("paper-mu100").override({
        "rod.mu": mu, "rod.N": n, "time.integrator": integrator, "time.t_end": 1.2,
        "output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0})
    b = rodjit.simulate(cfg).bounces
    assert b["t_impact"].size >= 1 and not b["open"][0]
    return {"restitution": b["restitution"][0],
            "contact_time": b["t_release"][0] - b["t_impact"][0],
            "min_u0": b["min_u0"][0]}


# Every integrator at its defaults (time.control = "tolerance"), at every μ where it is
# allowed: verlet splits its viscous sub-step off the kicks and is not allowed above
# rodjit.config.VERLET_MU_MAX (the configuration warns; measured 2.8e-4 at μ = 100, N = 5,
# and steps ∝ μN²; see tests/reference/notes/README.md and docs/integrators.md).
# The explicit pairs where their viscous cap admits the run (``registry.VISCOUS_STEPS_MAX``:
# dp54 and dop853 at μ = 100 and 1000 with N = 200 are refused), and "auto", the default.
_CASES = [(i, mu, n) for i in ("verlet", "semi-implicit", "energy", "dp54", "dop853",
                               "radau5", "auto")
          for mu in (1, 100, 1000) for n in (5, 200)
          if not (i == "verlet" and mu > VERLET_MU_MAX)
          and not (i in ("dp54", "dop853") and mu * n * n > 1e6)]


def _case(i, mu, n):
    # the pairs' N = 200 run at μ = 1 takes about 50 000 steps: a few seconds
    slow = i in ("dp54", "dop853") and n == 200
    return pytest.param(i, mu, n, id=f"{i}-mu{mu}-N{n}",
                        marks=[pytest.mark.slow] if slow else [])


def test_verlet_warns_where_it_is_not_allowed():
    """Where verlet is left out above, its configuration says so."""
    cfg = rodjit.Config().override({"time.integrator": "verlet", "rod.mu": 100.0})
    assert VERLET_WARNING in cfg.warnings()
    assert VERLET_WARNING not in cfg.override({"rod.mu": VERLET_MU_MAX}).warnings()


@pytest.mark.parametrize("integrator,mu,n", [_case(*c) for c in _CASES])
def test_first_bounce_matches_the_semi_discrete_reference(integrator, mu, n):
    ref = REF["semi_discrete"][f"N={n},mu={mu}"]["values"]
    got = _rodjit_first_bounce(integrator, mu, n)
    rel = {k: abs(got[k] - ref[k]) / abs(ref[k]) for k in COMPARED}
    assert max(rel.values()) < RTOL_OBS, rel
