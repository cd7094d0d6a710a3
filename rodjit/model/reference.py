"""Plain-NumPy reference of the semi-discrete system (MODEL.md §2–3): the readable spec.

Deliberately independent of the compiled kernels: the Aiki–Kosugi laws are written here in
MODEL.md's literal form (other laws fall back to their scalar functions), the forces as
``−∂V/∂u − ∂R/∂v`` assembled with array slicing.  Slow; used by tests and by benchmarks
that hand the same right-hand side to SciPy.
"""
from __future__ import annotations

import numpy as np

from .laws import AikiKosugiFloor, AikiKosugiRod, primitive, value
from .system import masses

__all__ = ["rod_stress", "rod_energy_density", "floor_stress", "floor_energy",
           "forces", "acceleration", "energies", "rhs", "discrete_gradient",
           "discrete_gradient_residual", "damping_factor"]


def rod_stress(eps, rod):
    eps = np.asarray(eps, dtype=float)
    if isinstance(rod, AikiKosugiRod):
        return rod.kappa / 2 * (eps + 0.5 - 1.0 / (2 * (1 + eps) ** 3))
    return np.vectorize(lambda e: value(float(e), rod))(eps)


def rod_energy_density(eps, rod):
    eps = np.asarray(eps, dtype=float)
    if isinstance(rod, AikiKosugiRod):
        return rod.kappa / 2 * (eps**2 / 2 + eps / 2 + 1.0 / (4 * (1 + eps) ** 2) - 0.25)
    return np.vectorize(lambda e: primitive(float(e), rod))(eps)


def floor_stress(h, floor):
    if isinstance(floor, AikiKosugiFloor):
        kb, b = floor.kappa_b, floor.beta
        return kb * (b**3 / (h + b) ** 3 - 1.0) if h <= 0 else 0.0
    return value(float(h), floor)


def floor_energy(h, floor):
    """σ̂_b(h); the floor's potential energy is −σ̂_b(u_0)."""
    if isinstance(floor, AikiKosugiFloor):
        kb, b = floor.kappa_b, floor.beta
        return kb * (-(b**3) / (2 * (h + b) ** 2) - h + b / 2) if h <= 0 else 0.0
    return primitive(float(h), floor)


def _curvatures(u, h):
    k = np.zeros_like(u)
    k[1:-1] = (u[2:] - 2 * u[1:-1] + u[:-2]) / h**2
    return k  # k_0 = k_N = 0: the discrete u_xx = 0


def forces(u, v, system, rod, floor):
    """m_i u_i'' for every node (MODEL.md §2, written out)."""
    n, h = system.n, system.h
    m = masses(n)
    eps = np.diff(u) / h - 1.0
    s = rod_stress(eps, rod)
    F = np.zeros(n + 1)
    F[:-1] += s          # f(ε_{i+½}) pulls node i up
    F[1:] -= s           # and node i+1 down
    if system.gamma:
        k = np.pad(_curvatures(u, h), 1)        # k_{-1} = k_{N+1} = 0 (absent terms)
        F -= system.gamma * h * (k[:-2] - 2 * k[1:-1] + k[2:]) / h**2
    if system.mu:
        dv = np.diff(v) / h
        F[:-1] += system.mu * dv
        F[1:] -= system.mu * dv
    F += m * system.g
    F[0] += floor_stress(u[0], floor) * damping_factor(v[0], system)
    return F


def damping_factor(v0, system):
    """The Hunt–Crossley factor max(0, 1 + α·(−v₀)) of the floor force (MODEL.md §1): α
    times the penetration rate −v₀, held at 0 so the floor never pulls."""
    return max(0.0, 1.0 - system.alpha * v0)


def acceleration(u, v, system, rod, floor):
    return forces(u, v, system, rod, floor) / masses(system.n)


def rhs(t, y, system, rod, floor):
    """First-order form d/dt [u, v] for ODE solvers."""
    n1 = system.n + 1
    u, v = y[:n1], y[n1:]
    return np.concatenate([v, acceleration(u, v, system, rod, floor)])


def energies(u, v, system, rod, floor):
    """The energies and observables of MODEL.md §3 (no time-integrated quantities)."""
    n, h = system.n, system.h
    m = masses(n)
    eps = np.diff(u) / h - 1.0
    k = _curvatures(u, h)
    out = {
        "energy_kinetic": 0.5 * np.sum(m * v**2),
        "energy_stretch": np.sum(h * rod_energy_density(eps, rod)),
        "energy_bend": 0.5 * system.gamma * np.sum(h * k[1:-1] ** 2),
        "energy_floor": -floor_energy(u[0], floor),
        "energy_gravity": -system.g * np.sum(m * u),
    }
    out["energy_total"] = sum(out.values())
    # 2R(v) and the power of the floor's damping, σ_b (1 − factor) v₀
    out["dissipation_rate"] = (system.mu * np.sum(h * (np.diff(v) / h) ** 2)
                               + floor_stress(u[0], floor)
                               * (1.0 - damping_factor(v[0], system)) * v[0])
    out["u_bottom"] = u[0]
    out["floor_force"] = floor_stress(u[0], floor)
    out["min_strain"] = eps.min()
    out["cm_height"] = np.sum(m * u)
    out["cm_velocity"] = np.sum(m * v)
    return out


def _quotient(P, s, a, b, small=1e-5):
    """(P(b) − P(a))/(b − a), or the midpoint stress s((a+b)/2) when |b − a| < ``small``
    (its error s''·(b−a)²/24 is then ≲ 1e-10 of the stress scale)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    near = np.abs(b - a) < small
    out = np.empty_like(a)
    if near.any():
        out[near] = s((a[near] + b[near]) / 2)
    if not near.all():
        out[~near] = (P(b[~near]) - P(a[~near])) / (b[~near] - a[~near])
    return out


def discrete_gradient(u1, u2, system, rod, floor):
    """∇̄V(u1, u2) of the energy-conserving step (MODEL.md §2, ``time.integrator = "energy"``):
    per segment the quotient of f̂, at node 0 that of −σ̂_b, the midpoint values of the
    bending and gravity gradients.  (u2 − u1)·∇̄V = V(u2) − V(u1)."""
    n, h = system.n, system.h
    e1 = np.diff(u1) / h - 1.0
    e2 = np.diff(u2) / h - 1.0
    q = _quotient(lambda e: rod_energy_density(e, rod), lambda e: rod_stress(e, rod), e1, e2)
    G = np.zeros(n + 1)
    G[1:] += q           # ∂V/∂u_{i+1} of segment i
    G[:-1] -= q
    fl = np.vectorize(lambda x: floor_energy(float(x), floor))
    fs = np.vectorize(lambda x: floor_stress(float(x), floor))
    G[0] -= _quotient(fl, fs, [u1[0]], [u2[0]])[0]
    if system.gamma:
        k = np.pad(_curvatures((u1 + u2) / 2, h), 1)
        G += system.gamma * h * (k[:-2] - 2 * k[1:-1] + k[2:]) / h**2
    G -= masses(n) * system.g
    return G


def discrete_gradient_residual(u1, v1, u2, v2, dt, system, rod, floor):
    """Residuals of the energy-conserving step: (u2 − u1 − dt v̄, M(v2 − v1) + dt ∇̄V +
    dt μ K v̄ − dt F_d e₀) with v̄ = (v1 + v2)/2, μKv̄ the gradient of the dissipation R and
    F_d the floor's damping on the floor's quotient at v̄₀."""
    vb = (v1 + v2) / 2
    visc = np.zeros_like(vb)
    if system.mu:
        dv = np.diff(vb) / system.h
        visc[:-1] -= system.mu * dv
        visc[1:] += system.mu * dv
    r_u = u2 - u1 - dt * vb
    r_v = masses(system.n) * (v2 - v1) + dt * discrete_gradient(u1, u2, system, rod, floor) + dt * visc
    if system.alpha:
        # the floor's damping on the quotient q_b of the floor's gradient: −q_b (φ(v̄₀) − 1)
        fl = np.vectorize(lambda x: floor_energy(float(x), floor))
        fs = np.vectorize(lambda x: floor_stress(float(x), floor))
        qb = _quotient(fl, fs, [u1[0]], [u2[0]])[0]
        r_v[0] -= dt * qb * (damping_factor(vb[0], system) - 1.0)
    return r_u, r_v
