"""Discrete-gradient step (``time.integrator = "energy"``): an exact discrete energy balance.

The step from (uⁿ, vⁿ) solves, on the semi-discrete system of MODEL.md §2,

    uⁿ⁺¹ − uⁿ = dt v̄,   v̄ = (vⁿ + vⁿ⁺¹)/2,
    M(vⁿ⁺¹ − vⁿ) = −dt ∇̄V(uⁿ, uⁿ⁺¹) − dt μ K v̄ + dt F̄_d e₀,

with K = DᵀD/h (R(v) = μ/2 vᵀKv) and the discrete gradient ∇̄V: per segment the quotient
q_i = (f̂(εⁿ⁺¹) − f̂(εⁿ))/(εⁿ⁺¹ − εⁿ) (force +q_i on node i, −q_i on node i+1), at node 0
the quotient of σ̂_b, and the exact midpoint values γB(uⁿ + uⁿ⁺¹)/2 and −g m of the quadratic
bending and linear gravity energies.  Since (uⁿ⁺¹ − uⁿ)·∇̄V = V(uⁿ⁺¹) − V(uⁿ),

    Eⁿ⁺¹ − Eⁿ = −dt μ Σ h ((v̄_{i+1} − v̄_i)/h)² + dt F̄_d v̄₀                 (exactly),

which is the dissipation this step reports; F̄_d = −q_b·min(1, α v̄₀) is the floor's damping
(MODEL.md §1) on the floor's quotient q_b at the mean velocity, 0 at α = 0.  The barriers f̂ → ∞, −σ̂_b → ∞ then keep every
solution admissible, whatever dt.

Solve: with the unknown increment d = uⁿ⁺¹ − uⁿ and vⁿ⁺¹ = 2d/dt − vⁿ, the step is the root of

    F(d) = M(d − dt vⁿ) + dt²/2 ∇̄V(uⁿ, uⁿ + d) + dt μ/2 K d,

the gradient of a strictly convex function of d (each quotient is a function of one strain,
increasing since f' > 0 and σ_b' ≤ 0) with barriers at the admissible set's boundary: the
root is unique and Newton's method with its symmetric banded Jacobian (tridiagonal for γ = 0,
pentadiagonal for γ > 0; the quotients' exact derivatives, so the floor's kink at u_0 = 0 is
differentiated consistently) converges.  Iterates are kept admissible and the residual
decreasing by backtracking; no convergence in ``max_newton`` iterations returns
NO_CONVERGENCE (the loop retries a shorter step).

Step size by accuracy: the Taylor predictors u_p = uⁿ + dt vⁿ + dt²/2 aⁿ and
v_p = vⁿ + dt aⁿ + dt²/2 ȧⁿ have local errors −dt³ȧ/6 and −dt³ä/6, the step +dt³ȧ/12
and +dt³ä/12 (exact for linear forces), so (uⁿ⁺¹ − u_p)/3 and (vⁿ⁺¹ − v_p)/3 estimate the
step's local error.  Its size in the one error norm (``control.height_scale``,
``velocity_scale``: max over u and v of |e|/(atol + rtol·|y|)), per unit step
(``control.per_unit_step``: times ERROR_TIME/dt, so the global error follows the
tolerance), decides: ≤ 1 accepts, > 1 returns INACCURATE with a shorter ``dt_suggest``; the
next step is dt·0.9·err^(−1/2) (in [0.2, 5]×).  Newton starts from u_p + dt³ȧ/4, where the step lands up to O(dt⁴).
No stability limit enters: steps grow far beyond the explicit limit when the motion is smooth.
Componentwise scaling makes ``atol`` the accuracy of the bottom height in contact (|u_0| is
tiny there) and ``rtol`` that of the flight: raise atol to stop resolving every micro-contact.
The state's ``a`` row carries the full acceleration (viscosity included) for the predictors.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels.banded import (add_bending, penta_factor, penta_solve, sym_tridiag_apply,
                               sym_tridiag_solve)
from ...kernels.discrete_gradient import difference
from ...kernels.forces import (BAD_FLOOR, BAD_STRAIN, INACCURATE, NO_CONVERGENCE, NON_FINITE,
                               OK, add_beam_term, assemble)
from ...kernels.mass import inv_node_mass as _inv_mass, node_mass as _mass
from ...kernels.rates import add_floor_damping, add_viscous, jerk
from ...model.laws import lower
from ..control import (height_scale, per_unit_step, taylor_start, unit_step_factor,
                       velocity_scale)
from ..registry import counter_index
from ..step_result import StepResult
from ..._jit import kernel, step_kernel

__all__ = ["Energy", "initial", "step", "WORK_ROWS"]

# the step's counters in ``sstats`` (registry.SCHEME_STATS)
NEWTON_ITERATIONS = counter_index("newton_iterations")
NEWTON_FAILURES = counter_index("newton_failures")

NEWTON_TOL = 1e-10    # converged when the update is below this × |uⁿ⁺¹ − uⁿ| (see _newton)
MAX_NEWTON = 30
MAX_BACKTRACK = 40
ARMIJO = 1e-4
CHORD = 1e-2  # the factor is used again while a full update shrinks the residual this much
EPS = 2.220446049250313e-16

# rows of the scratch array ``work`` (all per-step scratch: nothing survives a step)
S = 0         # segment stresses (accel; the last Newton evaluation's, for the new state)
K = 1         # curvatures
E1 = 2        # strains of uⁿ
AD = 3        # ȧⁿ, the time derivative of the acceleration
DP = 4        # predictor increment u_p − uⁿ
R = 5         # Newton residual
J0 = 6        # Jacobian diagonals (i,i), (i,i+1), (i,i+2)
J1 = 7
J2 = 8
L1 = 9         # factor (L1 also the Thomas scratch)
L2 = 10
DINV = 11
DEL = 12      # Newton update
DT = 13       # line-search trial increment
SC = 14       # magnitude of the residual's terms (rounding scale)
UB = 15       # midpoint uⁿ + d/2 for the bending term
D = 16        # Newton iterate d
WORK_ROWS = 17


class Energy(NamedTuple):
    """Parameters of the discrete-gradient step: error tolerances and the Newton solve."""

    rtol: float
    atol: float
    newton_tol: float = NEWTON_TOL
    max_newton: int = MAX_NEWTON
    chord: float = CHORD


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    """Full acceleration of the initial state and the first step (``control.taylor_start``:
    the accuracy estimate from ȧ, at most the explicit limit 2/ω)."""
    return taylor_start(scheme, system, rod, floor, u, v, a, work[S], work[K], work[AD],
                        work[E1])


@step_kernel
def _evaluate(system, rod, floor, u, v, d, u2, dt, work, jac):
    """Residual F(d) (row R); leaves u² = uⁿ + d in ``u2``.  With ``jac`` it also
    assembles the Jacobian at d (rows J0–J2: M + dt²/2 (Σ_i q_i'/h (e_{i+1} − e_i)(e_{i+1} −
    e_i)ᵀ − q_b' e_0e_0ᵀ + γB/2) + dt μ/2 K, with q' the exact slopes of the computed
    quotients, so also across u_0 = 0) and the residual's rounding scale, in the same pass;
    the trial evaluations of a Newton iteration need the residual only.

    Without ``jac`` (a trial iterate: Newton's last evaluation is always one) it also leaves
    the stresses f(ε) of u² in row S.  Returns ``(status, |F|², |scale|², σ_b,
    min ε)`` in the norm |x|² = Σ x_i²/m_i (|scale|² = 0 without ``jac``), with the floor
    stress and the smallest strain of u²; status is BAD_STRAIN, BAD_FLOOR or NON_FINITE
    for an iterate outside the admissible set.  The scale sums the magnitudes of the
    residual's terms, plus the stress change that the rounding of u² in a strain causes,
    so 64 ε_mach × scale is the residual's rounding level.  One pass over the nodes: node i
    takes the terms of segments i − 1 (carried over) and i, and sets u²_{i+1} (a separate
    loop u² = uⁿ + d would be vectorised by LLVM into a pass of its own over the arrays,
    which costs more for short rods than the stores it saves).
    """
    n = system.n
    h = system.h
    ih = 1.0 / h
    r = work[R]
    sc = work[SC]
    e1 = work[E1]
    j0 = work[J0]
    j1 = work[J1]
    c2 = 0.5 * dt * dt
    cv = 0.5 * dt * system.mu * ih
    g = system.g
    lo = lower(rod)
    u2[0] = u[0] + d[0]
    if not u2[0] > lower(floor):
        return (BAD_FLOOR if math.isfinite(u2[0]) else NON_FINITE), 0.0, 0.0, 0.0, 0.0
    qb, qbp, fl = difference(u[0], u2[0], floor)
    st = work[S]
    emin = np.inf
    beam = system.gamma > 0.0
    cb = c2 * system.gamma
    if beam:   # the bending terms first, into rows R and SC
        ub = work[UB]
        for i in range(n + 1):
            ub[i] = u[i] + 0.5 * d[i]
            r[i] = 0.0
            sc[i] = 0.0
        add_beam_term(ub, r, work[K], h, cb, bool(False))
        if jac:
            kk = work[K]
            for i in range(1, n):   # magnitude of the bending terms, for the rounding scale
                t = abs(cb * kk[i]) * ih
                sc[i - 1] += t
                sc[i] += 2.0 * t
                sc[i + 1] += t
    rn = 0.0
    sn = 0.0
    t_prev = 0.0      # segment i − 1: its force term, scale term and Jacobian coupling
    a_prev = 0.0
    c_prev = 0.0
    bad = False
    nonfinite = False
    for i in range(n + 1):
        m = _mass(i, n, h)
        ri = m * (d[i] - dt * v[i]) - c2 * m * g
        if beam:
            ri += r[i]
        ri += t_prev
        si = 0.0
        ji = 0.0
        if jac:
            ji = m + c_prev
            si = m * (abs(d[i]) + abs(dt * v[i])) + c2 * m * abs(g)
            if beam:
                si += sc[i]
            si += a_prev
        if i < n:
            u2[i + 1] = u[i + 1] + d[i + 1]   # here, not in a loop of its own (docstring)
            e2 = (u2[i + 1] - u2[i]) * ih - 1.0
            bad |= not e2 > lo
            nonfinite |= not math.isfinite(e2)
            q, qp, sb = difference(e1[i], e2, rod)   # the slope only with jac
            if not jac:   # the stress of the final iterate: Newton ends on a trial
                st[i] = sb
            emin = min(emin, e2)
            tq = c2 * q
            tv = cv * (d[i + 1] - d[i])
            t = tq + tv
            ri -= t
            t_prev = t
            if jac:
                c = c2 * qp * ih + cv
                ji += c
                j1[i] = -c
                c_prev = c
                at = abs(tq) + abs(tv) + c2 * qp * (abs(u2[i]) + abs(u2[i + 1])) * ih
                si += at
                a_prev = at
        if i == 0:
            ri -= c2 * qb
            if jac:
                ji -= c2 * qbp
                si += c2 * abs(qb)
            if system.alpha > 0.0:
                # the floor's damping at the mean velocity v̄₀ = d₀/dt: the force term
                # −q_b·min(1, α v̄₀) (``rates.floor_damping`` with σ_b → q_b); with the
                # elastic term −q_b' φ + q_b α/dt [α v̄₀ < 1] ≥ 0 on the diagonal
                av = system.alpha * (d[0] / dt)
                fd = -qb * min(1.0, av)
                ri -= c2 * fd
                if jac:
                    ji += c2 * qbp * min(1.0, av)
                    if av < 1.0:
                        ji += c2 * qb * (system.alpha / dt)
                    si += c2 * abs(fd)
        r[i] = ri
        if jac:
            j0[i] = ji
        im = _inv_mass(i, n, ih)
        rn += ri * ri * im
        sn += si * si * im
    if bad:
        return (NON_FINITE if nonfinite else BAD_STRAIN), 0.0, 0.0, 0.0, 0.0
    if jac:
        j1[n] = 0.0
        if beam:
            _add_bending_jacobian(system, work, c2, ih)
    if not math.isfinite(rn + sn):
        return NON_FINITE, 0.0, 0.0, 0.0, 0.0
    return OK, rn, sn, fl, emin


@step_kernel
def _add_bending_jacobian(system, work, c2, ih):
    """Rows J0–J2 += c2 γ/2 B, B = h CᵀC with curvature rows (1, −2, 1)/h²."""
    n = system.n
    j0 = work[J0]
    j1 = work[J1]
    j2 = work[J2]
    for i in range(n + 1):
        j2[i] = 0.0
    add_bending(j0, j1, j2, 0.5 * c2 * system.gamma * ih * ih * ih, n)


@step_kernel
def _newton_update(system, work, fresh):
    """y = J⁻¹F into row DEL (the update is δ = −y: negation is exact, so this is −J⁻¹F
    bit for bit without a pass that negates F) with the banded solvers (tridiagonal for
    γ = 0, else pentadiagonal): a ``fresh`` Jacobian (rows J0–J2) is factored into rows
    L1, L2, DINV, else their factor is used again."""
    y = work[DEL]
    r = work[R]
    if system.gamma > 0.0:
        if fresh:
            penta_factor(work[J0], work[J1], work[J2], work[L1], work[L2], work[DINV])
        penta_solve(work[L1], work[L2], work[DINV], r, y)
    elif fresh:
        sym_tridiag_solve(work[J0], work[J1], r, y, work[L1], work[DINV])
    else:
        sym_tridiag_apply(work[J1], work[L1], work[DINV], r, y)


@step_kernel
def _newton(scheme, system, rod, floor, u, v, u2, dt, work, sstats):
    """Solve F(d) = 0 from the start value in row D; leaves d in row ``row`` (D or DT:
    an accepted trial iterate changes places with the old one instead of being copied) and
    uⁿ + d in ``u2``, its stresses in row S.  Returns ``(status, value, row, σ_b, min ε)``
    (the floor stress and smallest strain of uⁿ + d): OK, NO_CONVERGENCE with the last
    update size in ``value``, or the first evaluation's BAD_STRAIN, BAD_FLOOR or NON_FINITE
    if the start is not admissible (row D then unchanged).

    Converged when the residual is at its rounding level (64 ε_mach × the size of its
    terms at the iterate the update came from: they change by the update, which is tiny
    next to them by then), or when the update is at most newton_tol × |d|∞: that update is
    applied and leaves a residual O(update²) by quadratic convergence (after a chord update
    O(update × the Jacobian's change since its factor), as small).  Each update is
    backtracked until the iterate is admissible and the residual drops (Armijo).  The start
    value is always updated once (the Taylor predictor is never a root to rounding, so its
    residual is not tested).  The first iteration evaluates residual, Jacobian and scale in
    one pass at the start and factors the Jacobian; trial iterates evaluate the residual
    alone.  A later iteration reuses that factor (a chord step, no evaluation: the accepted
    trial left its residual in row R) while the previous full update shrank the residual by
    a factor ``chord`` (so the iterate is close: the Jacobian moved by about the update's
    relative size, and the chord step contracts nearly as Newton's would); otherwise it
    evaluates and factors afresh at its iterate.  Steps in contact need two updates (their
    start is off by about the local error, which the accuracy control sets near the
    tolerance), so the second is one solve with the stored factor instead of an evaluation
    and a factorisation.  Norms are compared squared.
    """
    n1 = u.size
    row = D
    d = work[D]
    y = work[DEL]
    dtr = work[DT]
    rounding2 = (64.0 * EPS) ** 2
    last = np.inf
    fresh = bool(True)   # a run-time flag (rodjit._jit: literal flags)
    rn2 = 0.0
    sn2 = 0.0
    for it in range(scheme.max_newton):
        if fresh:
            # ``jac`` literal: each pass compiled for its own (rodjit._jit: literal flags)
            status, rn2, sn2, fl, emin = _evaluate(system, rod, floor, u, v, d, u2, dt,
                                                   work, True)
            if status != OK:   # only the start can be outside: trials are backtracked
                return status, 0.0, row, 0.0, 0.0
        _newton_update(system, work, fresh)
        sstats[NEWTON_ITERATIONS] += 1
        dmax = 0.0
        dref = 0.0
        for i in range(n1):   # the norms and the full-step trial in one pass
            dmax = max(dmax, abs(y[i]))
            dref = max(dref, abs(d[i]))
            dtr[i] = d[i] - y[i]
        last = dmax
        if not math.isfinite(dmax):
            break
        small = dmax <= scheme.newton_tol * dref
        alpha = 1.0
        accepted = False
        rt2 = 0.0
        for _ in range(MAX_BACKTRACK):
            if alpha < 1.0:
                for i in range(n1):
                    dtr[i] = d[i] - alpha * y[i]
            status, rt2, _, fl, emin = _evaluate(system, rod, floor, u, v, dtr, u2, dt, work,
                                                 False)
            armijo = 1.0 - ARMIJO * alpha
            if status == OK and (small or rt2 <= armijo * armijo * rn2
                                 or rt2 <= rounding2 * sn2):
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            break
        d, dtr = dtr, d
        row = DT if row == D else D
        if rt2 <= rounding2 * sn2 or (small and alpha == 1.0):
            return OK, 0.0, row, fl, emin
        # the next update from the same factor while a full update contracts the residual
        # fast (row R holds the residual at the new iterate, from its trial evaluation)
        fresh = not (alpha == 1.0 and rt2 <= scheme.chord * scheme.chord * rn2)
        rn2 = rt2
    sstats[NEWTON_FAILURES] += 1
    return NO_CONVERGENCE, last, row, 0.0, 0.0


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    """Trial step from (u, v, a) into (u2, v2, a2); the inputs are never modified.

    Returns a ``StepResult`` with status OK, INACCURATE (valid state, error estimate > 1:
    retry with ``dt_suggest``), NO_CONVERGENCE, or a non-admissible/non-finite code.
    """
    n = system.n
    h = system.h
    ih = 1.0 / h
    n1 = n + 1
    e1 = work[E1]
    dp = work[DP]
    ad = work[AD]
    d = work[D]
    jerk(system, rod, floor, u, v, a, ad, work[K], e1)
    # the Taylor predictor dp (error estimate); Newton's start is dp + dt³ȧ/4, the step's
    # own leading-order deviation from it (module docstring), pulled back toward uⁿ
    # (halved) while it is outside the admissible set (the first residual evaluation
    # reports that, before Newton changes anything)
    hdt2 = 0.5 * dt * dt
    c3 = 0.5 * dt * hdt2          # dt³/4
    for i in range(n1):
        dp[i] = dt * v[i] + hdt2 * a[i]
        d[i] = dp[i] + c3 * ad[i]
    alpha = 1.0
    for _ in range(60):
        status, val, row, fl, emin = _newton(scheme, system, rod, floor, u, v, u2, dt, work,
                                             sstats)
        if status != BAD_STRAIN and status != BAD_FLOOR:
            break
        alpha *= 0.5
        for i in range(n1):
            d[i] = alpha * (dp[i] + c3 * ad[i])
    if status != OK:
        return StepResult(status, val, 0.0, 0.0, 0.0, 0.0, 0.0)
    d = work[row]
    # vⁿ⁺¹ from the increment itself: 2(u2 − u)/dt would amplify the rounding of u2 by 1/dt
    # (u2 = uⁿ + d is Newton's last iterate already)
    idt2 = 2.0 / dt
    for i in range(n1):
        v2[i] = idt2 * d[i] - v[i]
    # the full acceleration of the new state from the stresses of Newton's last evaluation,
    # which was at this state (``full_accel`` without evaluating the laws again)
    assemble(u2, a2, work[S], work[K], fl, system, bool(True))
    add_viscous(system, v2, a2)
    add_floor_damping(system, fl, v2, a2)
    # error estimate (module docstring), momentum, dissipation μ dt Σ h ((v̄_{i+1} − v̄_i)/h)²;
    # max(|eu|/su, |ev|/sv) as max(|eu| sv, |ev| su)/(su sv): one division per node
    err = 0.0
    w = 0.0
    finite = True
    for i in range(n1):
        finite &= abs(a2[i]) < np.inf
        eu = abs(d[i] - dp[i])
        ev = abs(v2[i] - (v[i] + dt * a[i] + hdt2 * ad[i]))
        su = height_scale(scheme, u[i], u2[i])        # the one norm (control.py)
        sv = velocity_scale(scheme, v[i], v2[i])
        err = max(err, max(eu * sv, ev * su) / (su * sv))
        w += _mass(i, n, h) * v2[i]
    err = per_unit_step(err / 3.0, dt)   # per unit step (control.per_unit_step)
    if not finite:
        return StepResult(NON_FINITE, np.nan, emin, fl, 0.0, 0.0, 0.0)
    diss = 0.0
    if system.mu > 0.0:
        for i in range(n):
            dv = 0.5 * ((v[i + 1] + v2[i + 1]) - (v[i] + v2[i]))
            diss += dv * dv
        diss *= dt * system.mu * ih
    if system.alpha > 0.0:
        # the floor's damping: −dt F_d v̄₀ = q_b·min(1, α v̄₀)·d₀ with v̄₀ = d₀/dt, the
        # force of the step's residual, so the balance stays exact
        qb = difference(u[0], u2[0], floor)[0]
        diss += qb * min(1.0, system.alpha * (d[0] / dt)) * d[0]
    if not math.isfinite(err):
        return StepResult(NON_FINITE, err, emin, fl, 0.0, 0.0, 0.0)
    fac = unit_step_factor(err)
    if err > 1.0:
        return StepResult(INACCURATE, err, emin, fl, dt * fac, w, diss)
    return StepResult(OK, 0.0, emin, fl, dt * fac, w, diss)
