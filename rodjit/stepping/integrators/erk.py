"""Embedded explicit Runge–Kutta pairs: ``dp54`` (Dormand–Prince 5(4)) and ``dop853``
(Dormand–Prince 8(5,3)), with error control, for smooth motion at tight tolerances.

Both integrate the first-order form of MODEL.md §2, y = (u, v), y' = (v, a(u, v)), with
``a`` the full acceleration M⁻¹(−∇V(u) − μKv) (``energy.full_accel``).  A step of length
dt from yⁿ with stages k_j = f(Y_j), Y_j = yⁿ + dt Σ_{l<j} a_jl k_l, is

    yⁿ⁺¹ = yⁿ + dt Σ_j b_j k_j,       error estimate  dt Σ_j e_j k_j  (j up to the new point)

(the coefficients are Dormand and Prince's, as in Hairer, Nørsett & Wanner, *Solving
Ordinary Differential Equations I*, and SciPy's RK45/DOP853).  Both pairs are FSAL: the
last stage is f(yⁿ⁺¹), so the new state's derivative (v, a) is the state's own rows and the
next step reuses it; a resumed run reads it from the checkpointed state (``a`` row).

Error norm: the one norm of every integrator (``control.height_scale``,
``velocity_scale``), the largest over the 2(N+1) components of u and v of the error divided
by atol + rtol·max(|yⁿ|, |yⁿ⁺¹|) (velocities: atol·``control.VELOCITY_SCALE``); for dop853
Hairer's combined 5th/3rd-order estimate err₅²/√(err₅² + 0.01 err₃²), each in that norm.
≤ 1 accepts; > 1 returns INACCURATE and the loop retries at ``dt_suggest``.  The next step
is dt·0.9·err^(−1/(q+1)), at least 0.2 dt (q = 4 for dp54, 7 for dop853); how much it may
exceed the previous proposal is the loop's rule (``control.PAIR_GROWTH``: 10× for dp54, 6×
for dop853, none right after a rejection).  Fixed steps (``time.dt``) are all accepted.

Admissibility: every stage state is checked (ε > −1, u_0 > −β, finite); a stage outside
returns its failure code and the loop retries a quarter of the step.  The floor force has
a kink at u_0 = 0 (σ_b' jumps from 0 to 3κ_b/β), which the error estimate cannot see: a
pair stepping across it stalls near 1e-4, and a pair that only ends its accepted steps on
the crossings rejects trial after trial there.  So the loop (``loop.advance``) gives each
adaptive trial the floor law of the side its start is on (``laws.Sided``: σ_b ≡ 0, or the
contact branch continued past 0), a smooth force for which the estimate holds, and takes a
trial that leaves its side again, ending on the crossing.  The step's stages never see
the kink, whatever side they reach.

Explicit pairs are stability-bound: dt times every eigenvalue of the linearised system must
stay inside the pair's stability region (it reaches about −3.3 on the negative real axis for
dp54 and about −6 for dop853; viscosity adds real eigenvalues down to about −4μ/h², the
floor in contact frequencies from √(6κ_b/(βh)) up), so with stiff viscosity, a stiff floor
or a long rod the error controller keeps the step near that limit (rejecting the steps
that grow past it) and ``energy`` is the better choice.  On the imaginary axis (the
undamped oscillations of the rod) the regions reach only |z| ≈ 1.0 (dp54) and 6.0
(dop853) (``imaginary_limit``, from each tableau's stability polynomial).  A mode the
motion does not excite (the rod in free fall) leaves the error estimate blind to it, so
without a cap the steps of a free flight would grow until ω·dt is far outside, and the
rounding seeded in that mode would grow each step; the next step is therefore capped at
``STABILITY_CAP`` / ω, ω the Gershgorin bound at the new state (and, with viscosity, at
``VISCOUS_CAP`` · h²/(4μ): dense output below).

The energy is not conserved exactly: at μ = 0 it drifts by an amount that follows the
tolerance (tests/test_stepping_erk.py).  The dissipated energy is the pair's quadrature
(weights b_j) of the dissipation rate D over the stages (``rates.total_dissipation_rate``:
2R(v) and the floor's damping), consistent to the pair's order.

Dense output (``dense_setup``, ``dense``): after an accepted step from yⁿ at t to yⁿ⁺¹ at
t + dt, the pair's continuous extension gives y(t + θ dt), 0 ≤ θ ≤ 1, in Hairer's form

    y(θ) = yⁿ + θ(Δ + θ'(B + θ(C + θ'(R₅ + θ(R₆ + θ'(R₇ + θ R₈))))))      θ' = 1 − θ

with Δ = yⁿ⁺¹ − yⁿ, B = dt f(yⁿ) − Δ, C = Δ − dt f(yⁿ⁺¹) − B (a cubic Hermite part that
takes both ends and both slopes exactly) and R_m = dt Σ_j d_mj k_j over the stages.
``dp54``: the 4th-order extension of Shampine (1986) that Hairer's DOPRI5 uses (HNW I,
§II.6, "Dense output"; R₅ only, coefficients d_j of dopri5.f, the last column of SciPy's
RK45 interpolation matrix), free: it needs only the step's own stages.  ``dop853``: the
7th-order extension of Hairer's DOP853 (dop853.f; SciPy's ``dop853_coefficients``), R₅ … R₈
from the step's stages, its new point and three extra stages at c = 0.1, 0.2 and 7/9,
which ``dense_setup`` evaluates once for a step with an output time inside it (every
output of that step reuses them); an extra stage outside the admissible set returns its
failure code, and the loop retries the step shorter.  θ = 0 gives yⁿ exactly, θ = 1 gives
yⁿ⁺¹ to rounding (yⁿ + Δ).  An extension has its own stability function |y(θ)| for
y' = λy (``dense_amplification``): near the edge of the step's region dop853's reaches
about 15 at interior θ (z ≈ −6, and ±5.9i; uncapped, rows of the paper's runs at
rtol = atol = 1e-2 had 10⁴ times the initial energy), dp54's about 1.07 at −3.3.  The
caps of the next step (``STABILITY_CAP``, ``VISCOUS_CAP``) keep z where neither the step
nor its extension grows a mode by more than ``DENSE_GROWTH``.  The dissipated energy is
the same extension of the step's quadrature (``dense_dissipated``: k_j = D at stage j), so
E + dissipated at an interpolated row keeps the balance to the extension's order, and θ = 1
gives the step's own increment.  The extension's code is written for any pair in ``DENSE``
(extra stages, up to ``DENSE_TERMS_MAX`` terms R_m).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...kernels.forces import INACCURATE, NON_FINITE, OK, momentum
from ...kernels.rates import full_accel, total_dissipation_rate
from ..control import height_scale, velocity_scale
from ..step_result import StepResult
from . import erk_tableau as T
from .erk_tableau import (DENSE_GROWTH, DENSE_TERMS_MAX, IMAG_SAFETY, Dense, Tableau,
                          imaginary_limit, stability_polynomial)
from ..._jit import kernel, overload, step_kernel

__all__ = ["DP54", "DOP853", "TABLEAUS", "DENSE", "tableau", "dense_tableau", "initial",
           "step", "dense_setup", "dense", "dense_dissipated", "work_rows", "dense_amplification",
           "dense_limits", "dense_rows", "STABILITY_CAP", "VISCOUS_CAP", "DENSE_GROWTH",
           "DENSE_TERMS_MAX", "IMAG_SAFETY", "Dense", "Tableau", "imaginary_limit",
           "stability_polynomial"]


class DP54(NamedTuple):
    """Dormand–Prince 5(4): six stages and the new point (FSAL), order 5."""

    rtol: float
    atol: float


class DOP853(NamedTuple):
    """Dormand–Prince 8(5,3): twelve stages and the new point (FSAL), order 8."""

    rtol: float
    atol: float


SAFETY = 0.9
FAC_MIN = 0.2

# rows of the scratch array ``work``: the stresses and curvatures of ``accel``, then for each
# stage j ≥ 1 its velocity (the u-derivative) and acceleration (the v-derivative); stage 0
# is the state's own (v, a), the new point (stage index s, s the number of stages) the
# trial's (v2, a2), and its two rows are free: row 2s holds the height of a dense-output
# extra stage (indices s + 1, …, rows as for the stages); after them, two rows (u and v
# parts) for each dense-output term R_m (``dense_rows``)
S = 0
K = 1


@step_kernel
def stage_rows(j):
    """The work rows (velocity, acceleration) of stage j ≥ 1."""
    return 2 * j, 2 * j + 1


# the coefficients and the caps they give, keyed by the parameter classes (``erk_tableau``)
_NAME = {DP54: "dp54", DOP853: "dop853"}
TABLEAUS = {P: T.TABLEAUS[n] for P, n in _NAME.items()}
DENSE = {P: T.DENSE[n] for P, n in _NAME.items() if n in T.DENSE}
STABILITY_CAP = {P: T.STABILITY_CAP[n] for P, n in _NAME.items()}
VISCOUS_CAP = {P: T.VISCOUS_CAP[n] for P, n in _NAME.items()}


def dense_rows(params_type) -> int:
    """The first work row of the dense-output terms R_m (after every stage's rows)."""
    return T.dense_rows(_NAME[params_type])


def work_rows(params_type) -> int:
    """Scratch rows the pair needs (``erk_tableau.work_rows``)."""
    return T.work_rows(_NAME[params_type])


def dense_amplification(params_type, z, thetas) -> np.ndarray:
    """``erk_tableau.dense_amplification`` of the pair."""
    return T.dense_amplification(_NAME[params_type], z, thetas)


def dense_limits(params_type) -> tuple[float, float]:
    """``erk_tableau.dense_limits`` of the pair."""
    return T.dense_limits(_NAME[params_type])


def tableau(scheme):
    t = TABLEAUS[type(scheme)]
    return t.a, t.b, t.e, t.e3, t.combined, t.q


def step_caps(scheme):
    """``(STABILITY_CAP, VISCOUS_CAP)`` of the scheme: the largest ω·dt and dt·4μ/h² its
    steps may take."""
    return STABILITY_CAP[type(scheme)], VISCOUS_CAP[type(scheme)]


@overload(step_caps)
def _step_caps_ov(scheme):
    caps = STABILITY_CAP[scheme.instance_class], VISCOUS_CAP[scheme.instance_class]
    return lambda scheme: caps


@step_kernel
def _capped(scheme, system, dt, om2):
    """``dt`` within the scheme's caps at the state whose Gershgorin bound of ω² is
    ``om2`` (module docstring)."""
    imag, visc = step_caps(scheme)
    if om2 > 0.0:
        dt = min(dt, imag / math.sqrt(om2))
    if system.mu > 0.0:
        dt = min(dt, visc * system.h * system.h / (4.0 * system.mu))
    return dt


@overload(tableau)
def _tableau_ov(scheme):
    t = TABLEAUS[scheme.instance_class]
    a, b, e, e3, combined, q = t.a, t.b, t.e, t.e3, t.combined, t.q
    return lambda scheme: (a, b, e, e3, combined, q)


def dense_tableau(scheme):
    t = DENSE[type(scheme)]
    return t.ax, t.d


@overload(dense_tableau)
def _dense_tableau_ov(scheme):
    t = DENSE[scheme.instance_class]
    ax, d = t.ax, t.d
    return lambda scheme: (ax, d)


@step_kernel
def _power(x, p):
    return math.pow(x, p)


@step_kernel
def _factor(err, q):
    """SAFETY·err^(−1/(q+1)), at least FAC_MIN.  No upper clamp here: the loop caps the
    growth over the previous *proposal* (``control.propose``), so a step cut short to land
    on an output time or a floor crossing (whose error is tiny) does not shrink the next."""
    if not err > 0.0:
        return np.inf
    return max(FAC_MIN, SAFETY * _power(err, -1.0 / (q + 1.0)))


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    """Full acceleration of the initial state and Hairer's starting step: h0 = 0.01‖y‖/‖f‖,
    then from a trial Euler step the step whose error (‖f'‖ h^(q+1)) is 0.01, at most 100 h0,
    and at most ``STABILITY_CAP`` / ω (the stability limit of undamped oscillation)."""
    status, val, emin, fl, om2 = full_accel(system, rod, floor, u, v, a, work[S], work[K],
                                            bool(True))
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
    _, _, _, _, _, q = tableau(scheme)
    n1 = u.size
    d0 = 0.0
    d1 = 0.0
    for i in range(n1):
        su = scheme.atol + scheme.rtol * abs(u[i])
        sv = scheme.atol + scheme.rtol * abs(v[i])
        d0 += (u[i] / su) ** 2 + (v[i] / sv) ** 2
        d1 += (v[i] / su) ** 2 + (a[i] / sv) ** 2
    m = 2.0 * n1
    d0 = math.sqrt(d0 / m)
    d1 = math.sqrt(d1 / m)
    h0 = 0.01 * d0 / d1 if d0 > 1e-5 and d1 > 1e-5 else 1e-6
    h0 = _capped(scheme, system, h0, om2)
    u1 = work[2]   # stage rows as scratch
    v1 = work[3]
    a1 = work[4]
    for i in range(n1):
        u1[i] = u[i] + h0 * v[i]
        v1[i] = v[i] + h0 * a[i]
    st1 = full_accel(system, rod, floor, u1, v1, a1, work[S], work[K], bool(False))[0]
    dt = h0
    if st1 == OK:
        d2 = 0.0
        for i in range(n1):
            su = scheme.atol + scheme.rtol * abs(u[i])
            sv = scheme.atol + scheme.rtol * abs(v[i])
            d2 += ((v1[i] - v[i]) / su) ** 2 + ((a1[i] - a[i]) / sv) ** 2
        d2 = math.sqrt(d2 / m) / h0
        dm = max(d1, d2)
        h1 = (max(1e-6, 1e-3 * h0) if dm <= 1e-15
              else _power(0.01 / dm, 1.0 / (q + 1.0)))
        dt = min(100.0 * h0, h1)
        if om2 > 0.0:
            dt = min(dt, 2.0 / math.sqrt(om2))
    return StepResult(OK, 0.0, emin, fl, dt, 0.0, 0.0)


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    """Trial step from (u, v, a) into (u2, v2, a2); the inputs are never modified.

    Returns OK or INACCURATE (valid state, error estimate > 1: retry with ``dt_suggest``),
    or the failure code of the first stage outside the admissible set."""
    A, B, E, E3, combined, q = tableau(scheme)
    ns = B.size
    n1 = u.size
    diss = B[0] * total_dissipation_rate(system, floor, v, u[0])
    # stages 1 … ns−1; the stage height goes into u2 (scratch until the new point)
    for j in range(1, ns):
        rv, ra = stage_rows(j)
        vj = work[rv]
        aj = work[ra]
        for i in range(n1):
            du = A[j, 0] * v[i]
            dv = A[j, 0] * a[i]
            for l in range(1, j):
                cl = A[j, l]
                if cl != 0.0:
                    du += cl * work[2 * l, i]
                    dv += cl * work[2 * l + 1, i]
            u2[i] = u[i] + dt * du
            vj[i] = v[i] + dt * dv
        status, val, emin, fl, _ = full_accel(system, rod, floor, u2, vj, aj, work[S],
                                              work[K], bool(False))
        if status != OK:
            return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
        if B[j] != 0.0:
            diss += B[j] * total_dissipation_rate(system, floor, vj, u2[0])
    # the new point
    for i in range(n1):
        du = B[0] * v[i]
        dv = B[0] * a[i]
        for l in range(1, ns):
            cl = B[l]
            if cl != 0.0:
                du += cl * work[2 * l, i]
                dv += cl * work[2 * l + 1, i]
        u2[i] = u[i] + dt * du
        v2[i] = v[i] + dt * dv
    status, val, emin, fl, om2 = full_accel(system, rod, floor, u2, v2, a2, work[S],
                                            work[K], bool(True))
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
    # error norm over u and v (module docstring)
    e5 = 0.0
    e3 = 0.0
    for i in range(n1):
        eu = E[0] * v[i] + E[ns] * v2[i]
        ev = E[0] * a[i] + E[ns] * a2[i]
        fu = E3[0] * v[i] + E3[ns] * v2[i]
        fv = E3[0] * a[i] + E3[ns] * a2[i]
        for l in range(1, ns):
            cl = E[l]
            if cl != 0.0:
                eu += cl * work[2 * l, i]
                ev += cl * work[2 * l + 1, i]
            if combined:
                c3 = E3[l]
                if c3 != 0.0:
                    fu += c3 * work[2 * l, i]
                    fv += c3 * work[2 * l + 1, i]
        su = height_scale(scheme, u[i], u2[i])       # the one norm (control.py): a max
        sv = velocity_scale(scheme, v[i], v2[i])
        e5 = max(e5, abs(eu) / su, abs(ev) / sv)
        if combined:
            e3 = max(e3, abs(fu) / su, abs(fv) / sv)
    if combined:
        den = e5 * e5 + 0.01 * e3 * e3
        err = dt * e5 * e5 / math.sqrt(den) if den > 0.0 else 0.0
    else:
        err = dt * e5
    if not math.isfinite(err):
        return StepResult(NON_FINITE, err, emin, fl, 0.0, 0.0, 0.0)
    w = momentum(v2, system.h)
    diss *= dt
    fac = _factor(err, q)
    dt_next = dt * fac
    dt_next = _capped(scheme, system, dt_next, om2)
    if err > 1.0:
        return StepResult(INACCURATE, err, emin, fl, dt_next, w, diss)
    return StepResult(OK, 0.0, emin, fl, dt_next, w, diss)


@step_kernel
def _combine(coef, v, a, v2, a2, work, ns, i):
    """Σ_j coef[j] k_j at node i over the stage indices of ``coef`` (the pair's stages, the
    new point ns, the extra stages): its u part (velocities) and v part (accelerations)."""
    su = coef[0] * v[i]
    sv = coef[0] * a[i]
    for j in range(1, coef.size):
        c = coef[j]
        if c != 0.0:
            if j == ns:
                su += c * v2[i]
                sv += c * a2[i]
            else:
                su += c * work[2 * j, i]
                sv += c * work[2 * j + 1, i]
    return su, sv


@step_kernel
def dense_setup(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt):
    """Prepare the dense output of the step of length dt from (u, v, a) to (u2, v2, a2)
    that just left its stages in ``work``: evaluate the extra stages (dop853) and store the
    terms R_m.  Returns ``(status, value)``: OK, or the failure code of an extra stage
    outside the admissible set and its offending number."""
    A, _, _, _, _, _ = tableau(scheme)
    AX, D = dense_tableau(scheme)
    ns = A.shape[0]
    n1 = u.size
    us = work[2 * ns]
    for e in range(AX.shape[0]):
        j = ns + 1 + e
        vj = work[2 * j]
        aj = work[2 * j + 1]
        for i in range(n1):
            su, sv = _combine(AX[e], v, a, v2, a2, work, ns, i)
            us[i] = u[i] + dt * su
            vj[i] = v[i] + dt * sv
        status, val, _, _, _ = full_accel(system, rod, floor, us, vj, aj, work[S], work[K],
                                          bool(False))
        if status != OK:
            return status, val
    base = 2 * D.shape[1]
    for m in range(D.shape[0]):
        ru = work[base + 2 * m]
        rv = work[base + 2 * m + 1]
        for i in range(n1):
            su, sv = _combine(D[m], v, a, v2, a2, work, ns, i)
            ru[i] = dt * su
            rv[i] = dt * sv
    return OK, 0.0


@step_kernel
def dense(scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo):
    """(u, v) at t + θ dt into ``uo``, ``vo``, from the step's ends and the terms R_m that
    ``dense_setup`` stored (module docstring); reads nothing else, so every output time of
    the step reuses one setup."""
    _, D = dense_tableau(scheme)
    nt = D.shape[0]
    base = 2 * D.shape[1]
    s = theta
    s1 = 1.0 - theta
    for i in range(u.size):
        # R_5 … R_m from the innermost: R_{5+k} is multiplied by θ' for even k, θ for odd k
        tu = 0.0
        tv = 0.0
        for k in range(nt - 1, -1, -1):
            f = s1 if k % 2 == 0 else s
            tu = f * (work[base + 2 * k, i] + tu)
            tv = f * (work[base + 2 * k + 1, i] + tv)
        du = u2[i] - u[i]
        dv = v2[i] - v[i]
        bu = dt * v[i] - du
        bv = dt * a[i] - dv
        cu = du - dt * v2[i] - bu
        cv = dv - dt * a2[i] - bv
        uo[i] = u[i] + s * (du + s1 * (bu + s * (cu + tu)))
        vo[i] = v[i] + s * (dv + s1 * (bv + s * (cv + tv)))


@step_kernel
def _stage_bottom(A, AX, v, v2, work, ns, j):
    """Σ_l a_jl k_l at node 0 of stage j's height rates (A's row, or AX's for an extra
    stage; index ``ns``: the new point)."""
    coef = A[j] if j < ns else AX[j - ns - 1]
    s = coef[0] * v[0]
    for l in range(1, coef.size):
        if coef[l] != 0.0:
            s += coef[l] * (v2[0] if l == ns else work[2 * l, 0])
    return s


@step_kernel
def dense_dissipated(scheme, system, floor, u, v, u2, v2, work, dt, theta):
    """The energy dissipated from the step's start to t + θ dt, the continuous extension of
    the step's quadrature Σ b_j D_j dt (module docstring); 0 at μ = α = 0.  Needs the
    stages and ``dense_setup``'s extra stages in ``work``; ``floor``: the step's law."""
    if not (system.mu > 0.0 or system.alpha > 0.0):
        return 0.0
    A, B, _, _, _, _ = tableau(scheme)
    AX, D = dense_tableau(scheme)
    ns = A.shape[0]
    nt = D.shape[0]
    r0 = total_dissipation_rate(system, floor, v, u[0])
    r1 = total_dissipation_rate(system, floor, v2, u2[0])
    total = 0.0          # Σ b_j r_j
    t5 = 0.0             # Σ d_mj r_j, m = 5 … 8 (DENSE_TERMS_MAX)
    t6 = 0.0
    t7 = 0.0
    t8 = 0.0
    for j in range(D.shape[1]):
        bj = B[j] if j < ns else 0.0
        used = bj != 0.0
        for k in range(nt):
            used = used or D[k, j] != 0.0
        if not used:
            continue
        r = r0 if j == 0 else r1 if j == ns else total_dissipation_rate(
            system, floor, work[2 * j], u[0] + dt * _stage_bottom(A, AX, v, v2, work, ns, j))
        total += bj * r
        t5 += D[0, j] * r
        if nt > 1:
            t6 += D[1, j] * r
        if nt > 2:
            t7 += D[2, j] * r
        if nt > 3:
            t8 += D[3, j] * r
    s = theta
    s1 = 1.0 - theta
    tail = 0.0
    if nt > 3:
        tail = s * (dt * t8)
    if nt > 2:
        tail = s1 * (dt * t7 + tail)
    if nt > 1:
        tail = s * (dt * t6 + tail)
    tail = s1 * (dt * t5 + tail)
    delta = dt * total
    b0 = dt * r0 - delta
    c0 = delta - dt * r1 - b0
    return s * (delta + s1 * (b0 + s * (c0 + tail)))
