"""The linear algebra of the Radau IIA step's simplified Newton iteration
(``integrators.radau``, whose module docstring derives it): the Hessian's diagonal terms,
the real and complex banded matrices λM + μK + H/λ, their factors and solves, and the rows
of the step's scratch array ``work`` that they and the step share.
"""
from __future__ import annotations

from ...kernels.banded import (add_bending, penta_factor, penta_solve, sym_tridiag_apply,
                               sym_tridiag_solve)
from ...kernels.mass import node_mass as _mass
from ...model.laws import deriv, value
from ..._jit import exact_step_kernel, step_kernel

# rows of the scratch array ``work`` (per-step scratch: nothing survives a step)
S = 0          # segment stresses (full_accel)
K = 1          # curvatures
FP = 2         # f'(ε_i) of uⁿ, per segment (the Hessian); entry N: the floor's damping
               # coefficient c₀ (``hessian_diagonal``)
ZU = 3         # stage increments Z_i: u part rows ZU + 2i, v part ZU + 2i + 1 (i = 0, 1, 2)
WU = 9         # transformed W = T⁻¹Z, same layout
DU = 15        # Newton update ΔW, same layout (the right-hand sides are solved in place)
FA = 21        # stage accelerations a(Y_i), rows FA + i
YU = 24        # a stage state (u, v)
YV = 25
RJ0 = 26       # real matrix diagonals (i,i), (i,i+1), (i,i+2)
RJ1 = 27
RJ2 = 28
RL1 = 29       # its factor (tridiagonal: RL1 eliminated couplings, RDI reciprocal pivots)
RL2 = 30
RDI = 31
RB = 32        # banded right-hand side / solution
CJ = 33        # complex matrix: rows CJ … CJ+5 = (re, im) of the diagonals (i,i+k), k = 0, 1, 2
CL = 39        # its LDLᵀ factor: (re, im) of l1 (i,i−1), l2 (i,i−2), 1/d
CB = 45        # complex right-hand side / solution (re, im)
EU = 47        # error estimate (u, v)
EV = 48
EA = 49        # acceleration at yⁿ + err (the refined estimate)
WORK_ROWS = 50


@step_kernel
def hessian_diagonal(system, rod, floor, u, v, fp):
    """f'(ε_i) of the segments of u into ``fp``; returns −∂F/∂u₀ (≥ 0) of the floor force
    F = σ_b(u₀)·φ, φ = max(0, 1 − α v₀) (−σ_b'(u₀) at α = 0), and leaves the damping
    coefficient c₀ = −∂F/∂v₀ = α σ_b(u₀) (0 where φ is held at 0) in ``fp[N]``: the
    Jacobian's velocity block is −M⁻¹(μK + c₀e₀e₀ᵀ)."""
    n = system.n
    ih = 1.0 / system.h
    for i in range(n):
        fp[i] = deriv((u[i + 1] - u[i]) * ih - 1.0, rod)
    fp[n] = 0.0
    if system.alpha > 0.0:
        av = system.alpha * v[0]
        if av < 1.0:
            fp[n] = system.alpha * value(u[0], floor)
        return -deriv(u[0], floor) * max(0.0, 1.0 - av)
    return -deriv(u[0], floor)


@step_kernel
def real_matrix(system, work, lam, qb):
    """Rows RJ0–RJ2 = λM + μK + H/λ (real λ); factored into RL1, RL2, RDI if γ > 0
    (the tridiagonal factor is made with the first solve)."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    il = 1.0 / lam
    fp = work[FP]
    j0 = work[RJ0]
    j1 = work[RJ1]
    prev = 0.0
    for i in range(n + 1):
        d = lam * _mass(i, n, h) + prev
        if i < n:
            c = (system.mu + fp[i] * il) * ih
            d += c
            j1[i] = -c
            prev = c
        j0[i] = d
    j0[0] += qb * il
    if system.alpha > 0.0:
        j0[0] += fp[n]      # the floor's damping c₀ (``hessian_diagonal``)
    j1[n] = 0.0
    if system.gamma > 0.0:
        j2 = work[RJ2]
        for i in range(n + 1):
            j2[i] = 0.0
        add_bending(j0, j1, j2, system.gamma * il * ih * ih * ih, n)
        penta_factor(j0, j1, j2, work[RL1], work[RL2], work[RDI])


@step_kernel
def complex_matrix(system, work, lr, li, qb):
    """Rows CJ… = λM + μK + H/λ for λ = lr + i li, and its complex LDLᵀ into rows CL…"""
    n = system.n
    h = system.h
    ih = 1.0 / h
    den = lr * lr + li * li
    ir = lr / den          # 1/λ
    ii = -li / den
    fp = work[FP]
    a0r = work[CJ]
    a0i = work[CJ + 1]
    a1r = work[CJ + 2]
    a1i = work[CJ + 3]
    a2r = work[CJ + 4]
    a2i = work[CJ + 5]
    pr = 0.0
    pi = 0.0
    for i in range(n + 1):
        m = _mass(i, n, h)
        dr = lr * m + pr
        di = li * m + pi
        if i < n:
            cr = (system.mu + fp[i] * ir) * ih
            ci = fp[i] * ii * ih
            dr += cr
            di += ci
            a1r[i] = -cr
            a1i[i] = -ci
            pr = cr
            pi = ci
        a0r[i] = dr
        a0i[i] = di
        a2r[i] = 0.0
        a2i[i] = 0.0
    a0r[0] += qb * ir
    a0i[0] += qb * ii
    if system.alpha > 0.0:
        a0r[0] += fp[n]     # the floor's damping c₀ (real)
    a1r[n] = 0.0
    a1i[n] = 0.0
    if system.gamma > 0.0:
        w = system.gamma * ih * ih * ih
        add_bending(a0r, a1r, a2r, w * ir, n)
        add_bending(a0i, a1i, a2i, w * ii, n)
    complex_factor(work)


@exact_step_kernel
def complex_factor(work):
    """LDLᵀ of the complex symmetric pentadiagonal matrix in rows CJ… (as
    ``banded.penta_factor``, in complex arithmetic) into rows CL… (l1, l2, 1/d)."""
    a0r = work[CJ]
    a0i = work[CJ + 1]
    a1r = work[CJ + 2]
    a1i = work[CJ + 3]
    a2r = work[CJ + 4]
    a2i = work[CJ + 5]
    l1r = work[CL]
    l1i = work[CL + 1]
    l2r = work[CL + 2]
    l2i = work[CL + 3]
    dir_ = work[CL + 4]
    dii = work[CL + 5]
    n1 = a0r.size
    d_m2 = 0.0 + 0.0j
    d_m1 = 0.0 + 0.0j
    prev_l1 = 0.0 + 0.0j
    for i in range(n1):
        li2 = 0.0 + 0.0j
        li1 = 0.0 + 0.0j
        if i >= 2:
            li2 = complex(a2r[i - 2], a2i[i - 2]) / d_m2
        if i >= 1:
            li1 = (complex(a1r[i - 1], a1i[i - 1]) - li2 * d_m2 * prev_l1) / d_m1
        d = complex(a0r[i], a0i[i]) - li1 * li1 * d_m1 - li2 * li2 * d_m2
        inv = 1.0 / d
        l1r[i] = li1.real
        l1i[i] = li1.imag
        l2r[i] = li2.real
        l2i[i] = li2.imag
        dir_[i] = inv.real
        dii[i] = inv.imag
        prev_l1 = li1
        d_m2 = d_m1
        d_m1 = d


@exact_step_kernel
def complex_solve(work, xr, xi):
    """Solve in place with the factor of ``complex_factor`` (x = re + i im)."""
    l1r = work[CL]
    l1i = work[CL + 1]
    l2r = work[CL + 2]
    l2i = work[CL + 3]
    dir_ = work[CL + 4]
    dii = work[CL + 5]
    n1 = xr.size
    for i in range(n1):
        z = complex(xr[i], xi[i])
        if i >= 1:
            z -= complex(l1r[i], l1i[i]) * complex(xr[i - 1], xi[i - 1])
        if i >= 2:
            z -= complex(l2r[i], l2i[i]) * complex(xr[i - 2], xi[i - 2])
        xr[i] = z.real
        xi[i] = z.imag
    for i in range(n1):
        z = complex(xr[i], xi[i]) * complex(dir_[i], dii[i])
        xr[i] = z.real
        xi[i] = z.imag
    for i in range(n1 - 1, -1, -1):
        z = complex(xr[i], xi[i])
        if i + 1 < n1:
            z -= complex(l1r[i + 1], l1i[i + 1]) * complex(xr[i + 1], xi[i + 1])
        if i + 2 < n1:
            z -= complex(l2r[i + 2], l2i[i + 2]) * complex(xr[i + 2], xi[i + 2])
        xr[i] = z.real
        xi[i] = z.imag


@step_kernel
def solve_real(system, work, lam, ru, rv, fresh):
    """(λI − J)(x, y) = (ru, rv) in place for the real λ = μ_r/dt (module docstring):
    x from the banded system, y = λx − r₁.  ``fresh``: the first solve of the step
    (the tridiagonal factor is made with it)."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    il = 1.0 / lam
    mu = system.mu
    b = work[RB]
    for i in range(n + 1):
        kr = 0.0     # (K r₁)_i = Σ over the adjacent segments (r₁_i − r₁_j)/h
        if i > 0:
            kr += ru[i] - ru[i - 1]
        if i < n:
            kr += ru[i] - ru[i + 1]
        m = _mass(i, n, h)
        b[i] = m * ru[i] + (m * rv[i] + mu * kr * ih) * il
    if system.alpha > 0.0:
        b[0] += work[FP, n] * ru[0] * il     # + c₀ r₁ / λ at node 0
    if system.gamma > 0.0:
        penta_solve(work[RL1], work[RL2], work[RDI], b, b)
    elif fresh:
        sym_tridiag_solve(work[RJ0], work[RJ1], b, b, work[RL1], work[RDI])
    else:
        sym_tridiag_apply(work[RJ1], work[RL1], work[RDI], b, b)
    for i in range(n + 1):
        rv[i] = lam * b[i] - ru[i]
        ru[i] = b[i]


@step_kernel
def solve_complex(system, work, lr, li, rur, rui, rvr, rvi):
    """(λI − J)(x, y) = (r₁, r₂) in place for the complex λ = lr + i li."""
    n = system.n
    h = system.h
    ih = 1.0 / h
    mu = system.mu
    lam = complex(lr, li)
    il = 1.0 / lam
    br = work[CB]
    bi = work[CB + 1]
    for i in range(n + 1):
        krr = 0.0
        kri = 0.0
        if i > 0:
            krr += rur[i] - rur[i - 1]
            kri += rui[i] - rui[i - 1]
        if i < n:
            krr += rur[i] - rur[i + 1]
            kri += rui[i] - rui[i + 1]
        m = _mass(i, n, h)
        r1 = complex(rur[i], rui[i])
        z = m * r1 + (m * complex(rvr[i], rvi[i]) + mu * ih * complex(krr, kri)) * il
        if i == 0 and system.alpha > 0.0:
            z += work[FP, n] * r1 * il       # + c₀ r₁ / λ at node 0
        br[i] = z.real
        bi[i] = z.imag
    complex_solve(work, br, bi)
    for i in range(n + 1):
        x = complex(br[i], bi[i])
        y = lam * x - complex(rur[i], rui[i])
        rur[i] = x.real
        rui[i] = x.imag
        rvr[i] = y.real
        rvi[i] = y.imag
