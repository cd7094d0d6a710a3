"""Three-stage Radau IIA collocation (``time.integrator = "radau5"``): order 5, L-stable,
stiffly accurate, for stiff viscosity and stiff floors at tight tolerances.

It integrates the first-order form of MODEL.md §2, y = (u, v), y' = f(y) = (v, a(u, v)),
a = M⁻¹(−∇V(u) − μKv + F_d e₀) (``kernels.rates.full_accel``; F_d the floor's damping).  A step of length dt from yⁿ solves for the
stage increments Z_i = Y_i − yⁿ (i = 1, 2, 3, at c = (4 − √6)/10, (4 + √6)/10, 1)

    Z_i = dt Σ_j a_ij f(yⁿ + Z_j),      yⁿ⁺¹ = yⁿ + Z_3       (stiffly accurate)

with the Radau IIA matrix (a_ij) (Hairer & Wanner, *Solving Ordinary Differential
Equations II*, IV.8; the constants are those of their RADAU5 and of SciPy's ``Radau``).

Newton: simplified, with the Jacobian J = ∂f/∂y at yⁿ, in Hairer and Wanner's transformed
variables W = T⁻¹Z, which turn the 3 × 2(N+1) system into one real system with
(μ_r/dt I − J) and one complex with ((α − iβ)/dt I − J) (T diagonalises a⁻¹).  J has the
block form [[0, I], [−M⁻¹H, −M⁻¹C]] (H: the Hessian of V at uⁿ, tridiagonal for γ = 0,
pentadiagonal for γ > 0, σ_b' one-sided at u_0 = 0 like the force, times the floor's
damping factor; C = μK + c₀e₀e₀ᵀ, K = DᵀD/h, c₀ = ασ_b the floor's damping,
``radau_linear.hessian_diagonal``), so (λI − J)(x, y) = (r₁, r₂) reduces by y = λx − r₁ to
one banded symmetric system in x,

    (λM + C + H/λ) x = M r₁ + (M r₂ + C r₁)/λ,

whose matrix has a positive definite real part for every Re λ > 0, Re 1/λ > 0 (M SPD,
C, H positive semidefinite), so elimination without pivoting is safe for the complex λ too.
The real system is solved with the banded solvers of ``kernels.banded``; the complex one
with the complex LDLᵀ below.  Newton starts from Z = 0, so its first update needs no
evaluation (every stage is f(yⁿ), the state's own (v, a)): it is the collocation solution
of the problem linearised at yⁿ.  Convergence and divergence are judged by the
contraction rate as in SciPy's ``Radau``: converged once rate/(1 − rate)·‖ΔW‖ < κ,
κ = max(10 ε_mach/rtol, min(0.03, √rtol)); no convergence (or a rate ≥ 1, or no chance to
converge within the iterations left) returns NO_CONVERGENCE and the loop retries shorter.
Every stage state is checked (ε > −1, u_0 > −β, finite); one outside returns its failure
code.  Nothing is carried from one step to the next (the Jacobian and its factors are made
afresh each step), so a step depends on (yⁿ, dt) alone and a resumed run is bit for bit
the uninterrupted one.

Error estimate (Hairer's): err = (μ_r/dt I − J)⁻¹ (f(yⁿ) + Σ e_i Z_i / dt), an embedded
third-order solution filtered by the real factor so stiff components do not inflate it; when
it exceeds 1 it is refined once by err ← (μ_r/dt I − J)⁻¹ (f(yⁿ + err) + Σ e_i Z_i/dt).
Norm: the one error norm of every integrator (``control.height_scale``): the largest over
the 2(N+1) components of |err| over atol + rtol·max(|yⁿ|, |yⁿ⁺¹|) (velocities: atol·
``control.VELOCITY_SCALE``).
≤ 1 accepts; > 1 returns INACCURATE.  The next step is dt·fac·err^(−1/4) in [0.2, 10]×,
fac = 0.9·(2 n_max + 1)/(2 n_max + n_newton) (fewer Newton iterations, bolder steps).
The tolerances are used as given (like SciPy's ``Radau``; RADAU5 itself rescales them).

Dissipation: the Radau quadrature dt Σ b_i D(Y_i) over the stages (b_i = a_3i) of the
rate D, 2R(v) and the floor's damping,
exact for polynomials of degree 4, so E + dissipated = E₀ to the step's accuracy.
Order: 5 where the motion is non-stiff; with stiff viscosity (μ dt/h² ≫ 1) the stiff
components converge at the stage order 3 + 1 instead (tests/test_stepping_radau.py measures
both).  The state's ``a`` row carries the full acceleration, as for ``energy``.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels.forces import INACCURATE, NO_CONVERGENCE, NON_FINITE, OK, momentum
from ...kernels.rates import dissipation_rate, floor_dissipation_rate, full_accel
from ...model.laws import value
from ..control import height_scale, taylor_start, velocity_scale
from ..registry import counter_index
from ..step_result import StepResult
from .radau_linear import (DU, EA, EU, EV, FA, FP, K, S, WORK_ROWS, WU, YU, YV, ZU,
                           complex_matrix, hessian_diagonal, real_matrix, solve_complex,
                           solve_real)
from ..._jit import kernel, step_kernel

__all__ = ["Radau5", "initial", "step", "dense_setup", "dense", "dense_dissipated",
           "WORK_ROWS", "C", "E", "T", "TI", "MU_REAL", "ALPHA", "BETA", "B", "DENSE_L",
           "DENSE_W"]

NEWTON_ITERATIONS = counter_index("newton_iterations")
NEWTON_FAILURES = counter_index("newton_failures")

S6 = math.sqrt(6.0)
C = np.array([(4.0 - S6) / 10.0, (4.0 + S6) / 10.0, 1.0])
B = np.array([(16.0 - S6) / 36.0, (16.0 + S6) / 36.0, 1.0 / 9.0])   # the last row of a
E = np.array([-13.0 - 7.0 * S6, -13.0 + 7.0 * S6, -1.0]) / 3.0
# a⁻¹ = T diag(μ_r, [[α, −β], [β, α]]) T⁻¹ (Hairer & Wanner's RADAU5 constants)
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)
ALPHA = 3.0 + 0.5 * (3.0 ** (1.0 / 3.0) - 3.0 ** (2.0 / 3.0))
BETA = 0.5 * (3.0 ** (5.0 / 6.0) + 3.0 ** (7.0 / 6.0))
T = np.array([
    [0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
    [0.25021312296533332, 0.20412935229379994, -0.38294211275726192],
    [1.0, 1.0, 0.0]])
TI = np.array([
    [4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
    [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
    [0.50287263494578682, -2.57192694985560522, 0.59603920482822492]])
_T00, _T01, _T02 = T[0]
_T10, _T11, _T12 = T[1]
_TI00, _TI01, _TI02 = TI[0]
_TI10, _TI11, _TI12 = TI[1]
_TI20, _TI21, _TI22 = TI[2]
_C0, _C1 = C[0], C[1]
_B0, _B1, _B2 = B


def _collocation_weights():
    """Polynomial coefficients (highest power first, for Horner) of the dense output.

    ``L[i]``: the Lagrange basis polynomial of node c_i on the nodes {0, c_1, c_2, c_3 = 1}
    (i = 0, 1, 2 for c_1 … c_3), so that the collocation polynomial of the step is
    y(t + θ dt) = yⁿ + Σ_i L_i(θ) Z_i (its increment is 0 at θ = 0 and Z_i at c_i).
    ``W[k]``: ∫₀^θ of the basis polynomial of node k (k = 0: the node 0) on the same nodes,
    the weights of the interpolatory quadrature of a rate from the step's start to θ; at
    θ = 1 they are (0, b_1, b_2, b_3), the step's own Radau quadrature, because the
    four-node rule is exact to degree 4 like the Radau rule, which has weight 0 at node 0.
    """
    nodes = np.concatenate([[0.0], C])
    basis = []
    for k in range(4):
        others = np.delete(nodes, k)
        poly = np.poly1d(np.poly(others)) / np.prod(nodes[k] - others)
        basis.append(poly)
    lagrange = np.array([basis[k].coeffs for k in range(1, 4)])
    integrals = np.array([basis[k].integ().coeffs for k in range(4)])
    return lagrange, integrals


DENSE_L, DENSE_W = _collocation_weights()
_E0, _E1, _E2 = E

MAX_NEWTON = 7        # the first (free) update and up to six with stage evaluations
SAFETY = 0.9
FAC_MIN = 0.2
FAC_MAX = 10.0
EPS = 2.220446049250313e-16



class Radau5(NamedTuple):
    """Parameters of the Radau IIA step: error tolerances."""

    rtol: float
    atol: float


@step_kernel
def _factor(err, n_newton):
    """The next step over this one: 0.9 (2n_max+1)/(2n_max+n) err^(−1/4) in [0.2, 10]."""
    if not err > 0.0:
        return FAC_MAX
    fac = SAFETY * (2.0 * MAX_NEWTON + 1.0) / (2.0 * MAX_NEWTON + n_newton)
    return min(FAC_MAX, max(FAC_MIN, fac / math.sqrt(math.sqrt(err))))


@step_kernel
def _stage_state(u, v, work, j):
    """Rows YU, YV = yⁿ + Z_j."""
    zu = work[ZU + 2 * j]
    zv = work[ZU + 2 * j + 1]
    yu = work[YU]
    yv = work[YV]
    for i in range(u.size):
        yu[i] = u[i] + zu[i]
        yv[i] = v[i] + zv[i]


@step_kernel
def _newton(scheme, system, rod, floor, u, v, a, work, sstats, dt):
    """Simplified Newton on the transformed stage equations (module docstring); leaves Z
    in rows ZU….  Returns ``(status, value, iterations)``."""
    n1 = u.size
    lr = MU_REAL / dt
    cr = ALPHA / dt
    ci = -BETA / dt
    tol = max(10.0 * EPS / scheme.rtol, min(0.03, math.sqrt(scheme.rtol)))
    for r in range(ZU, DU):
        for i in range(n1):
            work[r, i] = 0.0
    old = 0.0
    for it in range(MAX_NEWTON):
        # right-hand sides: F·TI_k − (Λ W)_k, F_j = f(yⁿ + Z_j) (all f(yⁿ) at Z = 0)
        if it > 0:
            for j in range(3):
                _stage_state(u, v, work, j)
                status, val, _, _, _ = full_accel(system, rod, floor, work[YU],
                                                         work[YV], work[FA + j], work[S],
                                                         work[K], bool(False))
                if status != OK:
                    return status, val, it
        for i in range(n1):
            if it > 0:
                f0u = v[i] + work[ZU + 1, i]
                f1u = v[i] + work[ZU + 3, i]
                f2u = v[i] + work[ZU + 5, i]
                f0v = work[FA, i]
                f1v = work[FA + 1, i]
                f2v = work[FA + 2, i]
            else:
                f0u = f1u = f2u = v[i]
                f0v = f1v = f2v = a[i]
            w0u = work[WU, i]
            w0v = work[WU + 1, i]
            w1u = work[WU + 2, i]
            w1v = work[WU + 3, i]
            w2u = work[WU + 4, i]
            w2v = work[WU + 5, i]
            work[DU, i] = _TI00 * f0u + _TI01 * f1u + _TI02 * f2u - lr * w0u
            work[DU + 1, i] = _TI00 * f0v + _TI01 * f1v + _TI02 * f2v - lr * w0v
            work[DU + 2, i] = (_TI10 * f0u + _TI11 * f1u + _TI12 * f2u
                               - (cr * w1u - ci * w2u))
            work[DU + 3, i] = (_TI10 * f0v + _TI11 * f1v + _TI12 * f2v
                               - (cr * w1v - ci * w2v))
            work[DU + 4, i] = (_TI20 * f0u + _TI21 * f1u + _TI22 * f2u
                               - (cr * w2u + ci * w1u))
            work[DU + 5, i] = (_TI20 * f0v + _TI21 * f1v + _TI22 * f2v
                               - (cr * w2v + ci * w1v))
        solve_real(system, work, lr, work[DU], work[DU + 1], it == 0)
        solve_complex(system, work, cr, ci, work[DU + 2], work[DU + 4], work[DU + 3],
                       work[DU + 5])
        sstats[NEWTON_ITERATIONS] += 1
        nrm = 0.0
        for i in range(n1):
            iu = 1.0 / (scheme.atol + scheme.rtol * abs(u[i]))
            iv = 1.0 / (scheme.atol + scheme.rtol * abs(v[i]))
            for k in range(3):
                du = work[DU + 2 * k, i] * iu
                dv = work[DU + 2 * k + 1, i] * iv
                nrm += du * du + dv * dv
        nrm = math.sqrt(nrm / (6.0 * n1))
        if not math.isfinite(nrm):
            return NON_FINITE, nrm, it + 1
        rate = 0.0
        if it > 0:
            rate = nrm / old
            if rate >= 1.0 or rate ** (MAX_NEWTON - it) / (1.0 - rate) * nrm > tol:
                sstats[NEWTON_FAILURES] += 1
                return NO_CONVERGENCE, nrm, it + 1
        for r in range(6):
            for i in range(n1):
                work[WU + r, i] += work[DU + r, i]
        for p in range(2):   # Z = T W, for the u and the v parts
            w0 = work[WU + p]
            w1 = work[WU + 2 + p]
            w2 = work[WU + 4 + p]
            z0 = work[ZU + p]
            z1 = work[ZU + 2 + p]
            z2 = work[ZU + 4 + p]
            for i in range(n1):
                z0[i] = _T00 * w0[i] + _T01 * w1[i] + _T02 * w2[i]
                z1[i] = _T10 * w0[i] + _T11 * w1[i] + _T12 * w2[i]
                z2[i] = w0[i] + w1[i]
        if nrm == 0.0 or (it > 0 and rate / (1.0 - rate) * nrm < tol):
            return OK, 0.0, it + 1
        old = nrm
    sstats[NEWTON_FAILURES] += 1
    return NO_CONVERGENCE, old, MAX_NEWTON


@step_kernel
def _error(scheme, u, v, u2, v2, work):
    """Rows EU, EV in the one error norm (``control.height_scale``, ``velocity_scale``):
    the largest |err| over its scale."""
    e = 0.0
    eu = work[EU]
    ev = work[EV]
    for i in range(u.size):
        e = max(e, abs(eu[i]) / height_scale(scheme, u[i], u2[i]),
                abs(ev[i]) / velocity_scale(scheme, v[i], v2[i]))
    return e


@step_kernel
def _error_rhs(v, a, work, fu, fv, idt):
    """Rows EU, EV = (fu, fv) + Σ e_i Z_i / dt (fu, fv: f at yⁿ or at yⁿ + err)."""
    eu = work[EU]
    ev = work[EV]
    for i in range(v.size):
        zu = _E0 * work[ZU, i] + _E1 * work[ZU + 2, i] + _E2 * work[ZU + 4, i]
        zv = _E0 * work[ZU + 1, i] + _E1 * work[ZU + 3, i] + _E2 * work[ZU + 5, i]
        eu[i] = fu[i] + zu * idt
        ev[i] = fv[i] + zv * idt


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    """Full acceleration of the initial state and the first step (``control.taylor_start``,
    as ``energy``'s: the controller grows it from there)."""
    return taylor_start(scheme, system, rod, floor, u, v, a, work[S], work[K], work[ZU],
                        work[FP])


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    """Trial step from (u, v, a) into (u2, v2, a2); the inputs are never modified.

    Returns OK, INACCURATE (valid state, error estimate > 1: retry with ``dt_suggest``),
    NO_CONVERGENCE, or the failure code of a stage outside the admissible set."""
    n1 = u.size
    qb = hessian_diagonal(system, rod, floor, u, v, work[FP])
    lr = MU_REAL / dt
    real_matrix(system, work, lr, qb)
    complex_matrix(system, work, ALPHA / dt, -BETA / dt, qb)
    status, val, nit = _newton(scheme, system, rod, floor, u, v, a, work, sstats, dt)
    if status != OK:
        return StepResult(status, val, 0.0, 0.0, 0.0, 0.0, 0.0)
    zu = work[ZU + 4]
    zv = work[ZU + 5]
    for i in range(n1):
        u2[i] = u[i] + zu[i]
        v2[i] = v[i] + zv[i]
    status, val, emin, fl, _ = full_accel(system, rod, floor, u2, v2, a2, work[S],
                                                 work[K], bool(False))
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
    idt = 1.0 / dt
    _error_rhs(v, a, work, v, a, idt)
    solve_real(system, work, lr, work[EU], work[EV], bool(False))
    err = _error(scheme, u, v, u2, v2, work)
    if err > 1.0:
        # refined once from f(yⁿ + err) (stiff components of the first estimate removed)
        yu = work[YU]
        yv = work[YV]
        for i in range(n1):
            yu[i] = u[i] + work[EU, i]
            yv[i] = v[i] + work[EV, i]
        st = full_accel(system, rod, floor, yu, yv, work[EA], work[S], work[K],
                               bool(False))[0]
        if st == OK:
            _error_rhs(v, a, work, yv, work[EA], idt)
            solve_real(system, work, lr, work[EU], work[EV], bool(False))
            err = _error(scheme, u, v, u2, v2, work)
    if not math.isfinite(err):
        return StepResult(NON_FINITE, err, emin, fl, 0.0, 0.0, 0.0)
    diss = 0.0
    if system.mu > 0.0:
        # stage velocities V_j = vⁿ + Zv_j (V_3 = vⁿ⁺¹)
        yv = work[YV]
        for i in range(n1):
            yv[i] = v[i] + work[ZU + 1, i]
        d0 = dissipation_rate(system, yv)
        for i in range(n1):
            yv[i] = v[i] + work[ZU + 3, i]
        d1 = dissipation_rate(system, yv)
        diss = dt * (_B0 * d0 + _B1 * d1 + _B2 * dissipation_rate(system, v2))
    if system.alpha > 0.0:
        fr = 0.0
        for j in range(3):    # a loop, not literal stage indices (each a compile of its own)
            fr += (_B0 if j == 0 else _B1 if j == 1 else _B2) * _floor_rate(
                system, floor, u, v, work, j)
        diss += dt * fr
    w = momentum(v2, system.h)
    fac = _factor(err, nit)
    if err > 1.0:
        return StepResult(INACCURATE, err, emin, fl, dt * fac, w, diss)
    return StepResult(OK, 0.0, emin, fl, dt * fac, w, diss)


@step_kernel
def _horner(coef, x):
    r = 0.0
    for c in coef:
        r = r * x + c
    return r


@step_kernel
def dense_setup(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt):
    """Nothing to prepare: the collocation polynomial needs only the stage increments Z_i
    the step left in rows ZU…, which nothing overwrites before the next step."""
    return OK, 0.0


@step_kernel
def dense(scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo):
    """(u, v) at t + θ dt into ``uo``, ``vo``: the step's collocation polynomial
    yⁿ + Σ_i L_i(θ) Z_i (``DENSE_L``), of degree 3: yⁿ⁺¹ at θ = 1 (to rounding; the
    stiffly accurate last stage) and of the stage order 3 inside the step."""
    l0 = _horner(DENSE_L[0], theta)
    l1 = _horner(DENSE_L[1], theta)
    l2 = _horner(DENSE_L[2], theta)
    for i in range(u.size):
        uo[i] = u[i] + (l0 * work[ZU, i] + l1 * work[ZU + 2, i] + l2 * work[ZU + 4, i])
        vo[i] = v[i] + (l0 * work[ZU + 1, i] + l1 * work[ZU + 3, i] + l2 * work[ZU + 5, i])


@step_kernel
def _floor_rate(system, floor, u, v, work, j):
    """The floor's damping dissipation rate (``rates.floor_dissipation_rate``) at stage j
    (bottom height uⁿ₀ + Zu_j, velocity vⁿ₀ + Zv_j)."""
    u0 = u[0] + work[ZU + 2 * j, 0]
    return floor_dissipation_rate(system, value(u0, floor), v[0] + work[ZU + 2 * j + 1, 0])


@step_kernel
def dense_dissipated(scheme, system, floor, u, v, u2, v2, work, dt, theta):
    """The energy dissipated from the step's start to t + θ dt: the interpolatory
    quadrature of the dissipation rate (viscous 2R and the floor's damping) over the nodes
    0, c_1, c_2, 1 (``DENSE_W``), which at θ = 1 is the step's own Radau quadrature; 0 at
    μ = α = 0.  Uses row YV as scratch."""
    if not (system.mu > 0.0 or system.alpha > 0.0):
        return 0.0
    total = 0.0
    if system.mu > 0.0:
        yv = work[YV]
        total = _horner(DENSE_W[0], theta) * dissipation_rate(system, v)
        for j in range(2):
            for i in range(v.size):
                yv[i] = v[i] + work[ZU + 2 * j + 1, i]
            total += _horner(DENSE_W[j + 1], theta) * dissipation_rate(system, yv)
        total += _horner(DENSE_W[3], theta) * dissipation_rate(system, v2)
    if system.alpha > 0.0:
        total += (_horner(DENSE_W[0], theta)
                  * floor_dissipation_rate(system, value(u[0], floor), v[0]))
        for j in range(2):
            total += _horner(DENSE_W[j + 1], theta) * _floor_rate(system, floor, u, v, work, j)
        total += (_horner(DENSE_W[3], theta)
                  * floor_dissipation_rate(system, value(u2[0], floor), v2[0]))
    return dt * total
