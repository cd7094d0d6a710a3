"""The rates of the first-order form of MODEL.md §2 that every integrator shares: the full
acceleration a = M⁻¹(−∇V(u) − μKv + F_d e₀), its time derivative along the motion, and the
dissipation rates: the viscous 2R(v) and the floor's −F_d v₀ (F_d the Hunt–Crossley part of
the floor force, ``floor_damping``).

One definition each, so the integrators (``stepping/integrators``) and the loop evaluate
the same right-hand side bit for bit.
"""
from ..model.laws import deriv, value
from .._jit import step_kernel
from .forces import OK, accel, add_beam_term
from .mass import inv_end_mass, inv_node_mass as _inv_mass

__all__ = ["full_accel", "add_viscous", "add_floor_damping", "floor_damping", "jerk",
           "dissipation_rate", "floor_dissipation_rate", "total_dissipation_rate"]


@step_kernel
def full_accel(system, rod, floor, u, v, a, s, k, bound):
    """a = M⁻¹(−∇V(u) − μKv + F_d e₀): ``accel`` with bending plus the viscous force and the
    floor's damping.  Returns ``accel``'s ``(status, value, min_strain, floor_force,
    omega2)`` (floor_force the elastic σ_b(u₀); omega2 = 0 unless ``bound``: only the
    first step's proposal uses it)."""
    res = accel(u, a, s, k, system, rod, floor, bool(True), bound)
    if res[0] == OK:
        add_viscous(system, v, a)
        add_floor_damping(system, res[3], v, a)
    return res


@step_kernel
def floor_damping(system, fl, v0):
    """F_d = σ_b·(max(0, 1 − α v₀) − 1) = −σ_b·min(1, α v₀): the Hunt–Crossley part of the
    floor force σ_b·max(0, 1 − α v₀) (MODEL.md §1; −v₀ is the penetration rate, and the
    factor is kept ≥ 0 so that the floor never pulls), from the elastic floor stress
    ``fl`` = σ_b(u₀) ≥ 0.  0 at α = 0 and off the floor."""
    return -fl * min(1.0, system.alpha * v0)


@step_kernel
def add_floor_damping(system, fl, v, a):
    """a₀ += F_d/m₀ (``floor_damping``); nothing at α = 0."""
    if system.alpha > 0.0:
        a[0] += floor_damping(system, fl, v[0]) * inv_end_mass(1.0 / system.h)


@step_kernel
def floor_dissipation_rate(system, fl, v0):
    """−F_d v₀ = σ_b·min(1, α v₀)·v₀ ≥ 0, the power the floor's damping removes (σ_b ≥ 0:
    α σ_b v₀² while the factor is positive, σ_b v₀ where it is held at 0)."""
    if system.alpha > 0.0:
        return -floor_damping(system, fl, v0) * v0
    return 0.0


@step_kernel
def add_viscous(system, v, a):
    """a −= M⁻¹μKv, the viscous part of the full acceleration."""
    if system.mu > 0.0:
        n = system.n
        ih = 1.0 / system.h
        c = system.mu * ih
        for i in range(n):
            t = c * (v[i + 1] - v[i])
            a[i] += t * _inv_mass(i, n, ih)
            a[i + 1] -= t * _inv_mass(i + 1, n, ih)


@step_kernel
def jerk(system, rod, floor, u, v, a, out, k, strains, beam=True, viscous=True):
    """ȧ = M⁻¹(−H(u)v − μKa + Ḟ_d e₀), the time derivative of the acceleration along the
    motion (H: Hessian of V; σ_b' one-sided at u_0 = 0 like the force itself; Ḟ_d that of
    the floor's damping, ``floor_damping``).  Also leaves the segment strains of u in
    ``strains`` (the step needs them, and they are computed here).

    ``beam`` False leaves out the bending term and ``viscous`` False the viscous one and the
    floor's damping (``a`` is then not read): the derivative of an explicit acceleration of
    ``forces.accel``, the kick acceleration of the kick–drift–kick schemes (their error
    estimate, ``kdk``)."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    mu = system.mu
    # out_i = (t_i − t_{i−1})/m_i with the segment terms t (no zeroing pass: LLVM makes it
    # a memset call, which costs more than the whole loop for a short rod); the bending
    # term is added already divided by the masses, as in ``forces.assemble``
    t_prev = -deriv(u[0], floor) * v[0]
    if viscous and system.alpha > 0.0:
        # Ḟ_d = −σ_b' v₀ min(1, α v₀) − σ_b α a₀ (the last while α v₀ < 1)
        av = system.alpha * v[0]
        fd = deriv(u[0], floor) * v[0] * min(1.0, av)
        if av < 1.0:
            fd += value(u[0], floor) * system.alpha * a[0]
        t_prev += fd
    for i in range(n):
        e = (u[i + 1] - u[i]) * ih - 1.0
        strains[i] = e
        if viscous:
            t = deriv(e, rod) * ih * (v[i + 1] - v[i]) + mu * ih * (a[i + 1] - a[i])
        else:
            t = deriv(e, rod) * ih * (v[i + 1] - v[i])
        out[i] = (t - t_prev) * _inv_mass(i, n, ih)
        t_prev = t
    out[n] = -t_prev * _inv_mass(n, n, ih)
    if beam and system.gamma > 0.0:
        add_beam_term(v, out, k, h, -system.gamma, bool(True))


@step_kernel
def dissipation_rate(system, v):
    """2R(v) = μ/h Σ (v_{i+1} − v_i)², the viscous dissipation rate."""
    r = 0.0
    for i in range(system.n):
        d = v[i + 1] - v[i]
        r += d * d
    return system.mu / system.h * r


@step_kernel
def total_dissipation_rate(system, floor, v, u0):
    """The whole dissipation rate at velocities ``v`` and bottom height ``u0``: the
    viscous 2R(v) plus the floor's damping power (each only where its coefficient is > 0)."""
    r = 0.0
    if system.mu > 0.0:
        r = dissipation_rate(system, v)
    if system.alpha > 0.0:
        r += floor_dissipation_rate(system, value(u0, floor), v[0])
    return r
