"""The rates of the first-order form of MODEL.md §2 that every integrator shares: the full
acceleration a = M⁻¹(−∇V(u) − μKv), its time derivative along the motion, and the viscous
dissipation rate 2R(v).

One definition each, so the integrators (``stepping/integrators``) and the loop evaluate
the same right-hand side bit for bit.
"""
from ..model.laws import deriv
from .._jit import step_kernel
from .forces import OK, accel, add_beam_term
from .mass import inv_node_mass as _inv_mass

__all__ = ["full_accel", "add_viscous", "jerk", "dissipation_rate"]


@step_kernel
def full_accel(system, rod, floor, u, v, a, s, k, bound):
    """a = M⁻¹(−∇V(u) − μKv): ``accel`` with bending plus the viscous force.  Returns
    ``accel``'s ``(status, value, min_strain, floor_force, omega2)`` (omega2 = 0 unless
    ``bound``: only the first step's proposal uses it)."""
    res = accel(u, a, s, k, system, rod, floor, bool(True), bound)
    if res[0] == OK:
        add_viscous(system, v, a)
    return res


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
    """ȧ = M⁻¹(−H(u)v − μKa), the time derivative of the acceleration along the motion
    (H: Hessian of V; σ_b' one-sided at u_0 = 0 like the force itself).  Also leaves the
    segment strains of u in ``strains`` (the step needs them, and they are computed here).

    ``beam`` False leaves out the bending term and ``viscous`` False the viscous one (``a``
    is then not read): the derivative of an explicit acceleration of ``forces.accel``, the
    kick acceleration of the kick–drift–kick schemes (their error estimate, ``kdk``)."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    mu = system.mu
    # out_i = (t_i − t_{i−1})/m_i with the segment terms t (no zeroing pass: LLVM makes it
    # a memset call, which costs more than the whole loop for a short rod); the bending
    # term is added already divided by the masses, as in ``forces.assemble``
    t_prev = -deriv(u[0], floor) * v[0]
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
