"""Viscous sub-steps v' = −μ M⁻¹K v (K: the discrete −∂²/∂x² of R(v) = μ/2 vᵀKv), and the
floor's damping sub-step m₀v₀' = F_d (``rates.floor_damping``) at fixed heights.

The viscous ones conserve momentum (K annihilates constants); all return the kinetic energy
they remove, computed as −Σ m (v₁−v₀)(v₁+v₀)/2 (no cancellation when it is small).
"""
import math

from ..kernels.banded import tridiag_factor, tridiag_solve
from ..kernels.mass import end_mass, node_mass
from . import workspace as W
from .._jit import kernel, step_kernel


@kernel
def _matrix(d, c, h, n):
    """Diagonal of M + cK into ``d``; returns its constant off-diagonal −c/h."""
    ih = 1.0 / h
    for i in range(n + 1):
        if 0 < i < n:
            d[i] = h + 2.0 * c * ih
        else:
            d[i] = 0.5 * h + c * ih
    return -c * ih


@step_kernel
def factored(c, h, n, work):
    """Factor M + cK into work rows VCP, VINV unless they hold that factorisation already
    (same c: the two viscous sub-steps of a step, and every step while dt stays the same,
    e.g. at the viscous step limit); returns the off-diagonal.  A reused factorisation is
    the one that would be recomputed, bit for bit."""
    memo = work[W.MEMO]
    if memo[0] == c:
        return -c * (1.0 / h)   # = _matrix's off-diagonal
    d = work[W.VD]
    off = _matrix(d, c, h, n)
    tridiag_factor(d, off, work[W.VCP], work[W.VINV])
    memo[0] = c
    return off


@step_kernel
def _kinetic_drop(v0, v1, h, n):
    acc = 0.0
    for i in range(n + 1):
        m = node_mass(i, n, h)
        acc += m * (v0[i] - v1[i]) * (v0[i] + v1[i])
    # both sub-steps contract the kinetic energy (|R(z)| ≤ 1 for the M-self-adjoint
    # operator), so a negative value is rounding: the dissipated energy never decreases
    return max(0.5 * acc, 0.0)


@step_kernel
def viscous_cn(vin, vout, tau, system, work):
    """Crank–Nicolson over ``tau``: symmetric, second order; rings if μτλ ≫ 1, so the
    Verlet step keeps μτ·4/h² ≤ 2·cfl.  ``vout`` may alias ``vin``."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    c = 0.5 * tau * system.mu
    rhs = work[W.VRHS]
    v0 = work[W.V0]
    off = factored(c, h, n, work)
    for i in range(n + 1):
        v0[i] = vin[i]
    # rhs = (M − cK) v0
    for i in range(n + 1):
        m = node_mass(i, n, h)
        kv = 0.0
        if i > 0:
            kv += v0[i] - v0[i - 1]
        if i < n:
            kv += v0[i] - v0[i + 1]
        rhs[i] = m * v0[i] - c * kv * ih
    tridiag_solve(off, work[W.VCP], work[W.VINV], rhs, vout)
    return _kinetic_drop(v0, vout, h, n)


GAMMA_SDIRK = 1.0 - 1.0 / math.sqrt(2.0)


@step_kernel
def viscous_sdirk2(vin, vout, tau, system, work):
    """Two-stage, stiffly accurate SDIRK (γ = 1 − 1/√2) over ``tau``: second order and
    L-stable, so stiff viscous modes are damped, never ringing, at any μτ/h².
    ``vout`` may alias ``vin``."""
    n = system.n
    h = system.h
    gs = GAMMA_SDIRK
    c = gs * tau * system.mu
    rhs = work[W.VRHS]
    v0 = work[W.V0]
    off = factored(c, h, n, work)
    for i in range(n + 1):
        v0[i] = vin[i]
        m = node_mass(i, n, h)
        rhs[i] = m * v0[i]
    tridiag_solve(off, work[W.VCP], work[W.VINV], rhs, vout)       # stage 1: Y1
    r = (1.0 - gs) / gs
    for i in range(n + 1):
        m = node_mass(i, n, h)
        rhs[i] = m * (v0[i] + r * (vout[i] - v0[i]))
    tridiag_solve(off, work[W.VCP], work[W.VINV], rhs, vout)       # stage 2 = result
    return _kinetic_drop(v0, vout, h, n)


@step_kernel
def floor_damping_flow(system, fl, v, tau):
    """v₀ after τ of m₀ v₀' = −σ_b·min(1, α v₀) with the heights held (σ_b = ``fl``, the
    elastic floor stress at them), solved exactly: at c = σ_b/m₀ a constant deceleration
    −c while α v₀ > 1 (F_d = −σ_b: the whole floor force held at 0), then
    v₀ ∝ exp(−cα t).  Unconditionally
    stable, however stiff c·α·τ.  Returns the kinetic energy it removes (≥ 0: |v₀|
    decreases, or v₀ > 1/α falls toward 1/α)."""
    if not (system.alpha > 0.0 and fl > 0.0):
        return 0.0
    a = system.alpha
    m = end_mass(system.h)
    c = fl / m
    w0 = v[0]
    w = w0
    t = tau
    if a * w > 1.0:
        t1 = (w - 1.0 / a) / c          # when α v₀ reaches 1
        if t <= t1:
            w -= c * t
            t = 0.0
        else:
            w = 1.0 / a
            t -= t1
    if t > 0.0:
        w *= math.exp(-c * a * t)
    v[0] = w
    return max(0.5 * m * (w0 - w) * (w0 + w), 0.0)
