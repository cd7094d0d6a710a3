"""Kick–drift–kick schemes: ``verlet`` and ``semi-implicit`` as rows of one stage table.

A step is the symmetric composition

    V(dt/2) ∘ K(dt/2) ∘ D(dt) ∘ K(dt/2) ∘ V(dt/2),

K a kick with the explicit acceleration, D the drift of the linear part, V a viscous
sub-step.  With the floor's damping (α > 0) the composition has the sub-step
F(dt/2) = ``viscous.floor_damping_flow`` at each end (m₀v₀' = F_d at fixed heights, solved
exactly; symmetric, so the step stays second order).  A row of ``STAGES`` chooses each
operator:

============== ============================== ===================================== ==========
scheme         K kicks with                   D                                     V
============== ============================== ===================================== ==========
verlet         stretch, bending, floor, g     u += dt v                             CN
semi-implicit  stretch, floor, g, and the     implicit midpoint on u' = v,          none
               viscous term (IMEX_KICK)       M v' = −γBu (``beam``; u += dt v
                                              when γ = 0)
============== ============================== ===================================== ==========

``verlet`` is symmetric, second order, symplectic for μ = 0, and stable for dt·ω ≤ 2 with
ω² bounded in ``accel`` (bending included), and CN's viscous limit μ·dt·4/h² ≤ 4·cfl keeps
Crank–Nicolson from ringing.

``semi-implicit`` (IMEX_KICK) puts the viscosity inside the kicks:

    v½ = (M + dt/2·μK)⁻¹ (M v + dt/2·F(u))        backward Euler in μK, F explicit
    (u⁺, v½') = D(dt)(u, v½)                       midpoint beam drift (u⁺ = u + dt v½ at γ = 0)
    v⁺ = v½' + dt/2·M⁻¹(F(u⁺) − μK v½')            its adjoint: forward Euler in μK

The last kick is the adjoint of the first and D is symmetric, so the step is symmetric,
hence second order; in the viscous term the two kicks compose to Crank–Nicolson (|R| ≤ 1,
unconditionally stable).  The velocity that moves u has been through the implicit viscous
kick, so short waves feel the viscous resistance that balances the stretch and floor
forces: a viscous sub-step split off the kicks (V) does not, and is O(1) wrong once
μ·dt·4/h² ≫ 1.  Its bound has stretch and floor alone, whatever γ and μ.  One tridiagonal
solve per step (its factorisation is kept while dt is unchanged).  The full-step velocity
of the stiffest viscous modes alternates in sign (CN's R → −1); v½ does not.

Error control (``tolerance``): the estimate covers the heights and the velocities, as the
other schemes' estimates do.  For u'' = a(u) the step is

    u⁺ = u + dt·v + dt²/2·a,      v⁺ = v + dt/2·(a + a⁺),      a⁺ = a(u⁺),

and with ȧ, ä the derivatives of a along the motion, a(u⁺) = a + dt·ȧ + dt²/2·ä + O(dt³)
(u⁺ is exact to O(dt³)), against the exact u(dt) = u + dt·v + dt²/2·a + dt³/6·ȧ + O(dt⁴)
and v(dt) = v + dt·a + dt²/2·ȧ + dt³/6·ä + O(dt⁴).  The local errors are therefore

    heights      u⁺ − u(dt) = −dt³/6·ȧ + O(dt⁴),
    velocities   v⁺ − v(dt) = (1/4 − 1/6)·dt³·ä = dt³/12·ä + O(dt⁴),

both O(dt³).  Heights: a⁺ − a = dt·ȧ + O(dt²), so dt²/6·(a⁺ − a) is the leading term, from
the two kicks' accelerations alone.  Velocities: the two accelerations cannot tell ä from
ȧ (a⁺ − a is their sum to O(dt³)), so the estimate takes ȧ at the start as well, the jerk
ȧ₀ = −M⁻¹H(u)·v of the kick acceleration (``rates.jerk`` without the viscous term, and
without the bending term where the kicks leave it out): a⁺ − a − dt·ȧ₀ = dt²/2·ä + O(dt³),
and dt/6·(a⁺ − a − dt·ȧ₀) is the velocities' leading term, consistent at order 3 like the
heights' one (its ratio to the true local error → 1 as dt → 0: 1.0000 at dt = 3e-5 on a
smooth flight, the heights' 1.003; tests/test_stepping_kdk_error.py).  The
trapezoid-versus-Euler difference dt/2·(a⁺ − a) would cost no jerk, but it is O(dt²), the
error of a first-order step: it would hold verlet's velocities to a first-order scheme's
steps.  The jerk costs one pass over the segments (the stress law's derivative, which
``accel`` also evaluates for its bound), no force evaluation and no scratch of its own
(rows of the workspace that the step is done with): a trial under tolerance control costs 27 % more at N = 5 and 12 % at N = 200
(``paper-mu0``, 172 → 218 and 859 → 959 ns on a loaded two-core machine).  It pays: with
the heights' part alone, on ``paper-mu0`` at rtol 1e-6, atol 1e-9 the bottom node's
velocity in contact ends 7.9e-3 m/s off over the first second (25× dp54's error there);
with both parts 5.1e-4 m/s, level with ``energy`` and ``dp54``, at 2.2× the steps
(tests/test_stepping_tolerance_state.py).  Its price is highest where the rod is long and
viscous: ``semi-implicit`` on ``paper-mu100`` at N = 200 to t = 1.2 takes 151 066 steps
(45 023 with the heights' part alone, ``energy`` 38 192), most after the impact; the
estimate covers the explicit forces only, not the viscous terms that damp the short waves.

Each component is scaled as in the one error norm, heights by atol + rtol·max(|u|, |u⁺|)
(``control.height_scale``), velocities by atol·``control.VELOCITY_SCALE`` +
rtol·max(|v|, |v⁺|) (``control.velocity_scale``); the ratio is the largest over both, per
unit step (``control.per_unit_step``: times ERROR_TIME/dt, so the global error follows the
tolerance).  A ratio above 1 rejects the step (INACCURATE), and the next step is
dt·0.9·ratio^(−1/2) (order 2), capped at ``control.STABILITY_CFL`` × the stability limit.
The estimate covers the explicitly treated forces (the kicks'); the implicitly treated
viscous and beam terms are not in it.  Under fixed steps (``time.dt``) it chooses nothing,
so the parameters have ``tolerance`` off there (``registry``) and the step skips it.

The row is a compile-time constant of the scheme's parameter type (``stages``): each
scheme compiles to its own straight-line step, and only the sub-steps of its own row are
compiled at all (``_for_rows``).  A new kick–drift–kick variant is one more
parameter class and one more row (plus its line in ``registry``).
"""
import math
from typing import NamedTuple

from ...kernels.banded import tridiag_solve
from ...kernels.forces import INACCURATE, NON_FINITE, OK, accel, kick, momentum
from ...kernels.mass import node_mass
from ...kernels.rates import jerk
from ...kernels.reduce import nan_max
from ...model.laws import value
from .. import workspace as W
from ..beam import beam_midpoint
from ..control import (FAC_MIN, STABILITY_CFL, height_scale, per_unit_step,
                       unit_step_factor, velocity_scale)
from ..stability import explicit_dt
from ..step_result import StepResult
from ..viscous import factored, floor_damping_flow, viscous_cn, viscous_sdirk2
from ..._jit import kernel, overload, step_kernel

__all__ = ["Verlet", "SemiImplicit", "Stages", "STAGES", "stages", "initial", "step"]


class Verlet(NamedTuple):
    """``tolerance``: steps from the local error estimate of heights and velocities in
    the one error norm (rtol, atol; module docstring), capped at ``control.STABILITY_CFL``
    × the stability limit; else cfl × the stability limit."""

    cfl: float
    rtol: float = 1e-6
    atol: float = 1e-9
    tolerance: bool = False


class SemiImplicit(NamedTuple):
    """As ``Verlet``."""

    cfl: float
    rtol: float = 1e-6
    atol: float = 1e-9
    tolerance: bool = False


# the drift D and the viscous sub-step V
DRIFT = 0            # u += dt v
BEAM_MIDPOINT = 1    # implicit midpoint on u' = v, M v' = −γBu (a plain drift when γ = 0)
CRANK_NICOLSON = 0
SDIRK2 = 1
IMEX_KICK = 2        # no V: the kicks carry the viscous term (first implicit, second explicit)


class Stages(NamedTuple):
    """One row of the stage table."""

    kick_bending: bool    # K includes the bending force (and ω² its stiffness)
    drift: int            # DRIFT or BEAM_MIDPOINT
    viscous: int          # CRANK_NICOLSON, SDIRK2 or IMEX_KICK
    viscous_limit: bool   # the step bound includes the viscous sub-step's limit


STAGES = {
    Verlet: Stages(kick_bending=True, drift=DRIFT, viscous=CRANK_NICOLSON,
                   viscous_limit=True),
    SemiImplicit: Stages(kick_bending=False, drift=BEAM_MIDPOINT, viscous=IMEX_KICK,
                         viscous_limit=False),
}


def stages(scheme) -> Stages:
    """The stage-table row of a scheme (compiled: a constant of its parameter type)."""
    return STAGES[type(scheme)]


@overload(stages)
def _stages_ov(scheme):
    row = STAGES[scheme.instance_class]
    return lambda scheme: row


@step_kernel
def _suggest(scheme, st, system, floor, om2, u0, v0):
    """The stability-based step: cfl × the limit, or under tolerance control its cap
    STABILITY_CFL × the limit.  Crank–Nicolson's viscous limit is one of accuracy (it
    rings, and the split viscous sub-step lags the kicks), not of stability, so it stays
    at time.cfl under either control."""
    if not scheme.tolerance:
        return explicit_dt(system, floor, om2, u0, v0, scheme.cfl, st.viscous_limit)
    dt = explicit_dt(system, floor, om2, u0, v0, STABILITY_CFL, bool(False))
    if st.viscous_limit and system.mu > 0.0:
        dt = min(dt, scheme.cfl * system.h * system.h / (2.0 * system.mu))
    return dt


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    """Acceleration of the initial state and the first step's bound (under tolerance
    control the first trial is the cap; its error ratio shortens it if it must)."""
    st = stages(scheme)
    status, val, emin, fl, om2 = accel(u, a, work[W.S], work[W.K], system, rod, floor,
                                       st.kick_bending, bool(True))
    return StepResult(status, val, emin, fl,
                      _suggest(scheme, st, system, floor, om2, u[0], v[0]), 0.0, 0.0)


@step_kernel
def _stiffness(v, h, n):
    """vᵀKv = Σ (v_{i+1} − v_i)²/h, twice the Rayleigh function over μ."""
    acc = 0.0
    for i in range(n):
        d = v[i + 1] - v[i]
        acc += d * d
    return acc / h


@step_kernel
def _imex_first_kick(v, a, v2, tau, system, work):
    """v2 = (M + τμK)⁻¹ M (v + τ a): the half kick implicit in the viscous term."""
    n = system.n
    h = system.h
    off = factored(tau * system.mu, h, n, work)
    rhs = work[W.VRHS]
    for i in range(n + 1):
        rhs[i] = node_mass(i, n, h) * (v[i] + tau * a[i])
    tridiag_solve(off, work[W.VCP], work[W.VINV], rhs, v2)


@step_kernel
def _imex_second_kick(v2, a2, tau, system):
    """v2 += τ(a2 − μM⁻¹K v2), its explicit adjoint (in place: K v2 is formed first)."""
    n = system.n
    h = system.h
    c = tau * system.mu / h
    prev = v2[0]
    for i in range(n + 1):
        kv = 0.0
        if i > 0:
            kv += v2[i] - prev
        if i < n:
            kv += v2[i] - v2[i + 1]
        prev = v2[i]
        v2[i] += tau * a2[i] - c * kv / node_mass(i, n, h)


@step_kernel
def _error_ratio(scheme, u, u2, v, v2, a, a2, ad, dt):
    """The predicted local error over its tolerance, the largest over heights and
    velocities (module docstring): max_i of dt²/6·|a2_i − a_i| / ``height_scale`` and of
    dt/6·|a2_i − a_i − dt·ad_i| / ``velocity_scale`` (``ad``: ȧ of the kick acceleration
    at the start)."""
    cu = dt * dt / 6.0
    cv = dt / 6.0
    r = 0.0
    for i in range(u.size):
        # nan_max: a reduction LLVM vectorises (Python's max is a chain of selects that
        # it does not); with its two divisions per node the loop then takes a third of
        # the time
        da = a2[i] - a[i]
        r = nan_max(r, nan_max(cu * abs(da) / height_scale(scheme, u[i], u2[i]),
                               cv * abs(da - dt * ad[i]) / velocity_scale(scheme, v[i], v2[i])))
    return r


@step_kernel
def _estimate(scheme, st, system, rod, floor, u, v, a, u2, v2, a2, work, dt):
    """``_error_ratio`` of a finished trial step.  The jerk at the start goes into rows
    the step is done with: V0 (the viscous sub-step's copy), with the velocity's
    curvatures in K and the strains in S (both refilled by the next ``accel``)."""
    ad = work[W.V0]
    jerk(system, rod, floor, u, v, a, ad, work[W.K], work[W.S], st.kick_bending,
         bool(False))
    return _error_ratio(scheme, u, u2, v, v2, a, a2, ad, dt)


def _for_rows(uses, kernel):
    """``kernel`` as a step operator of the stage table: called with the scheme first, it
    compiles to ``kernel`` for the schemes whose row ``uses`` it and to a stub (0.0) for
    the others, whose step calls it only in branches their row's constants make dead.  So
    a scheme's run compiles the kernels of its own row only (verlet never the beam
    midpoint, semi-implicit never Crank–Nicolson)."""
    def operator(scheme, *args):
        return kernel(*args)

    @overload(operator)
    def _operator_ov(scheme, *args):
        if uses(STAGES[scheme.instance_class]):
            return lambda scheme, *args: kernel(*args)
        return lambda scheme, *args: 0.0

    return operator


_cn = _for_rows(lambda st: st.viscous == CRANK_NICOLSON, viscous_cn)
_sdirk2 = _for_rows(lambda st: st.viscous == SDIRK2, viscous_sdirk2)
_imex_first = _for_rows(lambda st: st.viscous == IMEX_KICK, _imex_first_kick)
_imex_second = _for_rows(lambda st: st.viscous == IMEX_KICK, _imex_second_kick)
_beam_drift = _for_rows(lambda st: st.drift == BEAM_MIDPOINT, beam_midpoint)


@step_kernel
def _viscous(scheme, st, vin, vout, tau, system, work):
    if st.viscous == SDIRK2:
        return _sdirk2(scheme, vin, vout, tau, system, work)
    return _cn(scheme, vin, vout, tau, system, work)


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    """Trial step from (u, v, a) into (u2, v2, a2); the inputs are never modified.

    ``dt_suggest`` is cfl × the stability limit at the new state, or under tolerance
    control the step from the error ratio (at most STABILITY_CFL × the limit); a step
    whose ratio exceeds 1 returns INACCURATE.
    """
    st = stages(scheme)
    n = system.n
    h = system.h
    hdt = 0.5 * dt
    diss = 0.0
    imex = st.viscous == IMEX_KICK and system.mu > 0.0
    beam = st.drift == BEAM_MIDPOINT and system.gamma > 0.0
    vin = v
    if system.alpha > 0.0:
        # the floor's damping sub-step F(dt/2) around the rest, at the heights it finds
        vin = work[W.VF]
        for i in range(n + 1):
            vin[i] = v[i]
        diss += floor_damping_flow(system, value(u[0], floor), vin, hdt)
    if imex:
        _imex_first(scheme, vin, a, v2, hdt, system, work)
        diss += hdt * system.mu * _stiffness(v2, h, n)
    elif system.mu > 0.0:
        diss += _viscous(scheme, st, vin, v2, hdt, system, work)
        for i in range(n + 1):
            v2[i] += hdt * a[i]
    elif not beam:
        # no viscous sub-step and a plain drift: the kick and the drift in one pass
        # (each value as the two passes make it)
        for i in range(n + 1):
            vi = vin[i] + hdt * a[i]
            v2[i] = vi
            u2[i] = u[i] + dt * vi
    else:
        for i in range(n + 1):
            v2[i] = vin[i] + hdt * a[i]
    if beam:
        _beam_drift(scheme, system, u, v2, u2, dt, work)
    elif imex or system.mu > 0.0:
        for i in range(n + 1):
            u2[i] = u[i] + dt * v2[i]
    status, val, emin, fl, om2 = accel(u2, a2, work[W.S], work[W.K], system, rod, floor,
                                       st.kick_bending, bool(True))
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, diss)
    if imex:
        diss += hdt * system.mu * _stiffness(v2, h, n)
        _imex_second(scheme, v2, a2, hdt, system)
        w = momentum(v2, h)
    else:
        w = kick(v2, a2, hdt, h)
        if system.mu > 0.0:   # both viscous sub-steps conserve momentum: w is unchanged
            diss += _viscous(scheme, st, v2, v2, hdt, system, work)
    if system.alpha > 0.0:
        diss += floor_damping_flow(system, fl, v2, hdt)
        w = momentum(v2, h)
    dts = _suggest(scheme, st, system, floor, om2, u2[0], v2[0])
    if scheme.tolerance:
        # per unit step (control.per_unit_step): the global error follows the tolerance
        err = per_unit_step(_estimate(scheme, st, system, rod, floor, u, vin, a, u2, v2, a2,
                                      work, dt), dt)
        if not math.isfinite(err):
            return StepResult(NON_FINITE, err, emin, fl, 0.0, 0.0, diss)
        if err > 1.0:
            return StepResult(INACCURATE, err, emin, fl,
                              min(dts, dt * max(FAC_MIN, unit_step_factor(err))), w, diss)
        dts = min(dts, dt * unit_step_factor(err))
    return StepResult(OK, 0.0, emin, fl, dts, w, diss)
