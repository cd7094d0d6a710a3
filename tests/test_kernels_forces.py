"""Compiled forces and energies against the plain-NumPy reference (MODEL.md §2–3)."""
import numpy as np
import pytest

from rodjit.kernels.forces import BAD_FLOOR, BAD_STRAIN, NON_FINITE, OK, accel, energies
from rodjit.model import reference
from rodjit.model.laws import AikiKosugiFloor, AikiKosugiRod
from rodjit.model.system import RodSystem, masses

ROD = AikiKosugiRod(100.0)
FLOOR = AikiKosugiFloor(1000.0, 0.05)


def random_state(rng, n, bottom):
    """An admissible but strongly deformed state: strains in (−0.6, 0.6)."""
    h = 1.0 / n
    eps = rng.uniform(-0.6, 0.6, n)
    u = bottom + np.concatenate([[0.0], np.cumsum((1 + eps) * h)])
    v = rng.normal(0, 2.0, n + 1)
    return u, v


def rel_err(a, b):
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


@pytest.mark.parametrize("n", [1, 2, 3, 7, 40])
@pytest.mark.parametrize("gamma", [0.0, 0.37])
@pytest.mark.parametrize("bottom", [0.3, -0.02])   # in flight / in contact
def test_accel_matches_reference(rng, n, gamma, bottom):
    system = RodSystem(n, 1.0 / n, gamma, 0.0, -9.81)
    u, v = random_state(rng, n, bottom)
    a = np.zeros(n + 1)
    s = np.zeros(n + 1)
    k = np.zeros(n + 1)
    status, _, emin, ff, om2 = accel(u, a, s, k, system, ROD, FLOOR, True)
    assert status == OK
    ref = reference.acceleration(u, np.zeros(n + 1), system, ROD, FLOOR)
    assert rel_err(a, ref) < 1e-12
    assert emin == pytest.approx(np.min(np.diff(u) * n - 1), rel=1e-14)
    assert ff == pytest.approx(reference.floor_stress(u[0], FLOOR), rel=1e-13, abs=0)
    # without the beam term (semi-implicit's explicit part)
    status, *_ = accel(u, a, s, k, system, ROD, FLOOR, False)
    nobeam = reference.acceleration(u, np.zeros(n + 1), system._replace(gamma=0.0), ROD, FLOOR)
    assert rel_err(a, nobeam) < 1e-12


def test_stiffness_bound_covers_the_largest_frequency(rng):
    """ω² from accel bounds the largest eigenvalue of M⁻¹K (K = Jacobian of −force)."""
    from scipy.linalg import eigh
    n = 12
    system = RodSystem(n, 1.0 / n, 0.01, 0.0, 0.0)
    u, _ = random_state(rng, n, -0.02)
    work = np.zeros((3, n + 1))
    _, _, _, _, om2 = accel(u, np.zeros(n + 1), work[0], work[1], system, ROD, FLOOR, True)
    J = np.zeros((n + 1, n + 1))
    d = 1e-7
    for j in range(n + 1):
        up, um = u.copy(), u.copy()
        up[j] += d
        um[j] -= d
        J[:, j] = -(reference.forces(up, 0 * u, system, ROD, FLOOR)
                    - reference.forces(um, 0 * u, system, ROD, FLOOR)) / (2 * d)
    lam = eigh(0.5 * (J + J.T), np.diag(masses(n)), eigvals_only=True)
    assert lam.max() <= om2 <= 4 * lam.max()


@pytest.mark.parametrize("gamma", [0.0, 0.2])
def test_energies_match_reference(rng, gamma):
    n = 9
    system = RodSystem(n, 1.0 / n, gamma, 0.0, -9.81)
    for bottom in (0.4, -0.03):
        u, v = random_state(rng, n, bottom)
        ke, st, be, fe, ge, emin, z, w = energies(u, v, np.zeros(n + 1), system, ROD, FLOOR)
        ref = reference.energies(u, v, system, ROD, FLOOR)
        for got, name in [(ke, "energy_kinetic"), (st, "energy_stretch"), (be, "energy_bend"),
                          (fe, "energy_floor"), (ge, "energy_gravity"), (z, "cm_height"),
                          (w, "cm_velocity"), (emin, "min_strain")]:
            assert got == pytest.approx(ref[name], rel=1e-12, abs=1e-14), name


def test_forces_are_minus_the_gradient_of_the_potential(rng):
    """The reference forces are −∂V/∂u of the reference energies (MODEL.md §2)."""
    n = 6
    system = RodSystem(n, 1.0 / n, 0.3, 0.0, -9.81)
    u, _ = random_state(rng, n, -0.01)
    V = lambda x: sum(reference.energies(x, 0 * x, system, ROD, FLOOR)[k] for k in
                      ("energy_stretch", "energy_bend", "energy_floor", "energy_gravity"))
    F = reference.forces(u, 0 * u, system, ROD, FLOOR)
    d = 1e-6
    for j in range(n + 1):
        e = np.zeros(n + 1)
        e[j] = d
        assert F[j] == pytest.approx(-(V(u + e) - V(u - e)) / (2 * d), rel=1e-6, abs=1e-6)


def test_inadmissible_and_non_finite_states_are_flagged():
    n = 4
    system = RodSystem(n, 0.25, 0.0, 0.0, -9.81)
    work = np.zeros((3, n + 1))
    ok = 0.5 + np.linspace(0, 1, n + 1)
    crushed = ok.copy()
    crushed[2] = crushed[1]                    # ε = −1 on segment 1
    below = ok - 0.6                           # u0 = −0.1 < −β
    nan = ok.copy()
    nan[3] = np.nan
    for u, want in [(ok, OK), (crushed, BAD_STRAIN), (below, BAD_FLOOR), (nan, NON_FINITE)]:
        assert accel(u, work[2], work[0], work[1], system, ROD, FLOOR, True)[0] == want
