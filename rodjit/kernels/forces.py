"""Compiled forces, stiffness bound, admissibility and energies of MODEL.md §2–3.

Node masses are h/2 at the ends and h inside (``kernels.mass``).

Speed (these loops are the hot path; benchmarks/bench_explicit.py): reductions inside
the loops are NaN-propagating min/max (``kernels.reduce``) or boolean flags, never a
running floating-point sum, so LLVM vectorises them without fast-math, and their results
do not depend on how they are vectorised; the stiffness bound comes from the strain range
(``max_deriv``), not from a second singular function per segment.
"""
import math

import numpy as np

from ..model.laws import deriv, lower, max_deriv, primitive, value
from .._jit import kernel, step_kernel
from .reduce import nan_max, nan_min
from .mass import node_mass

# status codes of a trial state
OK = 0
BAD_STRAIN = 1    # a segment strain reached the rod law's lower bound (−1)
BAD_FLOOR = 2     # the bottom reached the floor law's lower bound (−β)
NON_FINITE = 3    # a non-finite value appeared
INACCURATE = 4    # a valid trial state whose error estimate exceeds the tolerance: the loop
                  # retries with the scheme's dt_suggest (and accepts it under fixed steps)
NO_CONVERGENCE = 5  # an implicit step's nonlinear solve did not converge: a shorter step
TOO_CLOSE = 6     # a valid step that closed too much of the gap to a barrier: a shorter step


@kernel
def curvatures(u, h, k):
    """k_i = (u_{i+1} − 2u_i + u_{i−1})/h² inside, k_0 = k_N = 0 (the discrete u_xx = 0)."""
    n = u.size - 1
    ih2 = 1.0 / (h * h)
    k[0] = 0.0
    k[n] = 0.0
    for i in range(1, n):
        k[i] = (u[i + 1] - 2.0 * u[i] + u[i - 1]) * ih2


@kernel
def add_beam_term(u, out, k, h, scale, by_mass):
    """out_j += scale · (k_{j−1} − 2k_j + k_{j+1}) / h, terms past the ends absent.

    With scale = −γ this adds the bending force −∂V_bend/∂u_j (divided by m_j if
    ``by_mass``); with scale = 1 it applies the bending operator B (V_bend = γ/2 uᵀBu).
    """
    n = u.size - 1
    curvatures(u, h, k)
    ih = 1.0 / h
    # the end nodes (k_{−1}, k_{N+1} absent) and a branch-free loop that vectorises; each
    # branch updates the ends itself (rodjit._jit: literal flags)
    f0 = scale * (0.0 - 2.0 * k[0] + k[1]) * ih
    fn = scale * (k[n - 1] - 2.0 * k[n] + 0.0) * ih
    if by_mass:
        for j in range(1, n):
            out[j] += scale * (k[j - 1] - 2.0 * k[j] + k[j + 1]) * ih * ih
        out[0] += f0 * (2.0 * ih)
        out[n] += fn * (2.0 * ih)
    else:
        for j in range(1, n):
            out[j] += scale * (k[j - 1] - 2.0 * k[j] + k[j + 1]) * ih
        out[0] += f0
        out[n] += fn


@step_kernel
def accel(u, a, s, k, system, rod, floor, beam, bound=True):
    """Explicit acceleration a = M⁻¹(stretch + floor [+ bending if ``beam``]) + g.

    Fills ``a`` (and the segment stresses ``s``, curvatures ``k``).  Returns
    ``(status, value, min_strain, floor_force, omega2)``: ``status``/``value`` flag a
    non-admissible or non-finite state, ``omega2`` bounds the largest squared frequency of
    the explicit part (Gershgorin on M⁻¹K: 4 max f'/h² + 2|σ_b'|/h [+ 16γ/h⁴]); with
    ``bound=False`` (a scheme whose step does not need it) it is 0 and no derivative is
    evaluated.
    """
    n = system.n
    h = system.h
    ih = 1.0 / h
    # one pass over the segments: stresses, strain range, finiteness (vectorised)
    emin = np.inf
    emax = -np.inf
    bad = False
    for i in range(n):
        e = (u[i + 1] - u[i]) * ih - 1.0
        emin = nan_min(emin, e)   # NaN if any strain is NaN
        emax = nan_max(emax, e)
        st = value(e, rod)
        s[i] = st
        bad |= not abs(st) < np.inf
    u0 = u[0]
    if not (math.isfinite(emin) and math.isfinite(emax) and math.isfinite(u0)):
        return NON_FINITE, emin + u0, emin, 0.0, np.inf
    if not emin > lower(rod):
        return BAD_STRAIN, emin, emin, 0.0, np.inf
    if not u0 > lower(floor):
        return BAD_FLOOR, u0, emin, 0.0, np.inf
    fl = value(u0, floor)
    fd = 0.0
    fpmax = 0.0
    if bound:
        fd = abs(deriv(u0, floor))
        fpmax = max_deriv(u, ih, emin, emax, rod)   # the largest f' over the segments
    if bad or not math.isfinite(fl + fpmax + fd):
        return NON_FINITE, fl + fpmax, emin, fl, np.inf
    assemble(u, a, s, k, fl, system, beam)
    omega2 = 4.0 * fpmax * ih * ih + 2.0 * fd * ih
    if beam and system.gamma > 0.0 and bound:
        omega2 += 16.0 * system.gamma * ih * ih * ih * ih
    return OK, 0.0, emin, fl, omega2


@step_kernel
def assemble(u, a, s, k, fl, system, beam):
    """a = M⁻¹(stretch + floor [+ bending if ``beam``]) + g from the segment stresses ``s``
    and the floor stress ``fl`` (curvatures into ``k``): the part of ``accel`` after the
    stresses, for a scheme that has them already."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    g = system.g
    ie = 2.0 * ih
    a[0] = (s[0] + fl) * ie + g
    for i in range(1, n):
        a[i] = (s[i] - s[i - 1]) * ih + g
    a[n] = -s[n - 1] * ie + g
    if beam and system.gamma > 0.0:
        add_beam_term(u, a, k, h, -system.gamma, bool(True))


@step_kernel
def kick(v, a, tau, h):
    """v += tau·a; returns the momentum Σ m_i v_i of the result (see ``momentum``)."""
    for i in range(v.size):
        v[i] += tau * a[i]
    return momentum(v, h)


@step_kernel
def momentum(v, h):
    """Σ m_i v_i = h·(v_1 + … + v_{N−1}) + h/2·(v_0 + v_N).

    The inner sum runs in four interleaved partial sums, a fixed order (the same result in
    every run) that vectorises; one running sum would be a chain of dependent additions as
    long as the rod, which no vector unit can shorten."""
    n = v.size - 1
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    i = 1
    while i + 3 < n:
        s0 += v[i]
        s1 += v[i + 1]
        s2 += v[i + 2]
        s3 += v[i + 3]
        i += 4
    while i < n:
        s0 += v[i]
        i += 1
    return h * ((s0 + s1) + (s2 + s3)) + (0.5 * h) * (v[0] + v[n])


@kernel
def worst_segment(u, h):
    """Index of the most compressed segment (for error messages)."""
    n = u.size - 1
    best = 0
    emin = np.inf
    for i in range(n):
        e = (u[i + 1] - u[i]) / h - 1.0
        if not e >= emin:  # also catches NaN
            emin = e
            best = i
    return best


@step_kernel
def energies(u, v, k, system, rod, floor):
    """``(kinetic, stretch, bend, floor, gravity, min_strain, cm_height, cm_velocity)``."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    ke = 0.0
    z = 0.0
    w = 0.0
    for i in range(n + 1):
        m = node_mass(i, n, h)
        ke += m * v[i] * v[i]
        z += m * u[i]
        w += m * v[i]
    stretch = 0.0
    emin = np.inf
    for i in range(n):
        e = (u[i + 1] - u[i]) * ih - 1.0
        emin = min(emin, e)
        stretch += primitive(e, rod)
    bend = 0.0
    if system.gamma > 0.0:
        curvatures(u, h, k)
        for i in range(1, n):
            bend += k[i] * k[i]
        bend *= 0.5 * system.gamma * h
    return (0.5 * ke, h * stretch, bend, -primitive(u[0], floor), -system.g * z, emin, z, w)
