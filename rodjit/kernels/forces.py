"""Compiled forces, stiffness bound, admissibility and energies of MODEL.md §2–3.

Node masses are h/2 at the ends and h inside; ``inv_m`` below means 1/m_i.
"""
import math

import numpy as np

from ..model.laws import deriv, lower, primitive, value
from .._jit import kernel

# status codes of a trial state
OK = 0
BAD_STRAIN = 1    # a segment strain reached the rod law's lower bound (−1)
BAD_FLOOR = 2     # the bottom reached the floor law's lower bound (−β)
NON_FINITE = 3    # a non-finite value appeared
INACCURATE = 4    # a valid trial state whose error estimate exceeds the tolerance: the loop
                  # retries with the scheme's dt_suggest (and accepts it under fixed steps)
NO_CONVERGENCE = 5  # an implicit step's nonlinear solve did not converge: a shorter step


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
    for j in range(n + 1):
        km = k[j - 1] if j >= 1 else 0.0
        kp = k[j + 1] if j + 1 <= n else 0.0
        fj = scale * (km - 2.0 * k[j] + kp) * ih
        if by_mass:
            fj *= (2.0 * ih) if (j == 0 or j == n) else ih
        out[j] += fj


@kernel
def accel(u, a, s, k, system, rod, floor, beam):
    """Explicit acceleration a = M⁻¹(stretch + floor [+ bending if ``beam``]) + g.

    Fills ``a`` (and the segment stresses ``s``, curvatures ``k``).  Returns
    ``(status, value, min_strain, floor_force, omega2)``: ``status``/``value`` flag a
    non-admissible or non-finite state, ``omega2`` bounds the largest squared frequency of
    the explicit part (Gershgorin on M⁻¹K: 4 max f'/h² + 2|σ_b'|/h [+ 16γ/h⁴]).
    """
    n = system.n
    h = system.h
    ih = 1.0 / h
    g = system.g
    emin = np.inf
    fpmax = 0.0
    chk = 0.0
    for i in range(n):
        e = (u[i + 1] - u[i]) * ih - 1.0
        emin = min(emin, e)
        st = value(e, rod)
        s[i] = st
        chk += st
        fpmax = max(fpmax, deriv(e, rod))
    u0 = u[0]
    if not (math.isfinite(emin) and math.isfinite(u0)):
        return NON_FINITE, emin + u0, emin, 0.0, np.inf
    if not emin > lower(rod):
        return BAD_STRAIN, emin, emin, 0.0, np.inf
    if not u0 > lower(floor):
        return BAD_FLOOR, u0, emin, 0.0, np.inf
    fl = value(u0, floor)
    fd = abs(deriv(u0, floor))
    if not math.isfinite(chk + fl + fpmax + fd):
        return NON_FINITE, chk + fl, emin, fl, np.inf
    ie = 2.0 * ih
    a[0] = (s[0] + fl) * ie + g
    for i in range(1, n):
        a[i] = (s[i] - s[i - 1]) * ih + g
    a[n] = -s[n - 1] * ie + g
    omega2 = 4.0 * fpmax * ih * ih + 2.0 * fd * ih
    if beam and system.gamma > 0.0:
        add_beam_term(u, a, k, h, -system.gamma, True)
        omega2 += 16.0 * system.gamma * ih * ih * ih * ih
    return OK, 0.0, emin, fl, omega2


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


@kernel
def energies(u, v, k, system, rod, floor):
    """``(kinetic, stretch, bend, floor, gravity, min_strain, cm_height, cm_velocity)``."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    ke = 0.0
    z = 0.0
    w = 0.0
    for i in range(n + 1):
        m = h if 0 < i < n else 0.5 * h
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
