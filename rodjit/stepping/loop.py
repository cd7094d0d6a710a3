"""The compiled time loop: many steps per call, Python sees the state only between calls.

``advance`` steps until t_end, until an output buffer is full, or until ``max_steps``.
How a run is cut into calls never changes the steps taken, so a resumed run equals an
uninterrupted one bit for bit.

Outputs (snapshot and diagnostics rows at the grid times t0 + k·Δ, integer k) come one of
two ways.  Landing (every scheme without a dense output, fixed steps, and
``output.interpolate = false``): the steps land exactly on the output times, and each row
is the state of the step that ends there.  Dense output (``Control.dense``: ``dp54`` and
``dop853`` under adaptive steps): the steps aim at t_end only, and after each accepted step
from t to t_new every output time in (t, t_new − tol) is evaluated by the scheme's
continuous extension (``schemes.dense``; ``dense_setup`` once per step that has one, before
the step is accepted, so a failing extra stage retries the step shorter).  Such a row has
the grid time exactly, ``snap_step`` = the step count after the step, the energies of the
interpolated state (``forces.energies``, as for any row), ``dt`` = the proposal after the
step, and the dissipated energy at the step's start plus the scheme's extension of the
step's quadrature of ∫2R dt (``schemes.dense_dissipated``; a linear interpolation between
the step's ends would be first order only, and its error would show in E + dissipated,
which stays balanced to the extension's order).  An output time at t_new (within
tol), t_end above all, is the step's own state, as under landing (the row's time is the
grid time, or t_end).  Every row of a step is
written in the call that takes it: a step covers at most ``ctrl.dense_snapshots`` and
``ctrl.dense_diagnostics`` output times (one that would cover more ends on the last of
them; the buffers hold at least that many rows), and before a step the loop counts the
output times it covers and returns FULL first if the buffers cannot take them.  Neither
rule depends on how full the buffers are, so the steps are the same however the run is cut
into calls.  The state kept between calls is always a step's own state.

A trial step that fails (non-admissible, non-finite, no convergence) is retried shorter;
one that a scheme rejects for accuracy (status INACCURATE: its error estimate is too
large) is retried at the scheme's ``dt_suggest``, and under fixed steps accepted as it is
(a scheme then returns a valid state with INACCURATE).  Every step-size rule is in
``control``.

Floor crossings (σ_b has a kink at u_0 = 0).  An adaptive step never integrates across the
kink.  The embedded pairs, with a floor law that has an extension (``_holds_sides``), take
each trial with the law of the side of u_0 = 0 its start is on (``laws.Sided``), so its
force is smooth and its error estimate valid; a trial that leaves its side
(``events.hermite_exit``, an excursion inside the step included) is taken again ending
where it leaves (never stretched to an output time), one that leaves at once is taken on
the side it moves into, and a state left a sliver across the switch gets its derivative
under the law itself, so the next step starts consistent (once the step's outputs and
extremes are taken: its continuous extension is built on the step's own derivative, and
with the law's, a stiff floor's, snapshots inside such a step were off by 6.5e-3 of the
impact speed where the step itself was right to 3e-5).  The other schemes step with the
law itself and take an accepted step that crossed again, ending on the crossing.
"""
import numpy as np

from ..kernels.forces import BAD_STRAIN, INACCURATE, OK, TOO_CLOSE, energies, worst_segment
from ..kernels.rates import full_accel
from ..model.laws import lower
from ..model.laws.base import BOTH, CONTACT, FREE, Sided, has_extension
from . import control as C
from . import layout as L
from . import registry
from .events import crossing, hermite_exit, open_contact, stop_due, track, vibration_energy
from .extremes import step_extremes
from .observers import observe_start, observe_step, observe_stop, observe_values
from .outputs import dense_target, emit, emit_dense, emit_final, grid_time, next_target
from .schemes import dense_setup, has_dense, initial, step
from .._jit import kernel, overload


def _holds_sides(scheme_cls, floor_cls) -> bool:
    """Whether the loop holds the floor law to one side per trial step (``laws.Sided``):
    for the embedded pairs (``control`` rules ``pair-*``), whose error estimate assumes a
    smooth force, with a floor law that continues its contact branch (``Law.extension``)."""
    return (registry.entry_of(scheme_cls).step_rules.startswith("pair")
            and has_extension(floor_cls))


def _trial_floor(scheme, floor, side):
    """The floor law a trial step takes: ``Sided(floor, side)`` where the loop holds sides
    (``_holds_sides``), else ``floor`` itself (a compile-time choice)."""
    return Sided(floor, side) if _holds_sides(type(scheme), type(floor)) else floor


@overload(_trial_floor)
def _trial_floor_ov(scheme, floor, side):
    if _holds_sides(scheme.instance_class, floor.instance_class):
        return lambda scheme, floor, side: Sided(floor, side)
    return lambda scheme, floor, side: floor


def _sides(scheme, floor):
    """``_holds_sides`` of the run's types; a constant in compiled code."""
    return _holds_sides(type(scheme), type(floor))


@overload(_sides)
def _sides_ov(scheme, floor):
    on = _holds_sides(scheme.instance_class, floor.instance_class)
    return lambda scheme, floor: on


@kernel
def start(scheme, ctrl, system, rod, floor, obs, arrays):
    """Initial acceleration, energy, first step proposal, contact state, the observer's
    start (``obs``: its parameters, ``observers``) and the outputs at t0, in the run's
    ``arrays`` (``arrays.RunArrays``).  Returns OK or a failure code (then ``arrays.fail``
    says why)."""
    state = arrays.state
    work = arrays.work
    clock = arrays.clock
    count = arrays.count
    ev = arrays.ev
    snap_t = arrays.snap_t
    snap_step = arrays.snap_step
    snap_u = arrays.snap_u
    snap_v = arrays.snap_v
    diag = arrays.diag
    fail = arrays.fail
    u = state[0]
    v = state[1]
    a = state[2]
    # the pairs' steps take the floor law as ``Sided`` (``_trial_floor``): the start takes
    # it too (the law itself), so their kernels compile for one floor type, not two
    r = initial(scheme, system, rod, _trial_floor(scheme, floor, BOTH), u, v, a, work)
    status = r.status
    if status != OK:
        fail[L.F_CODE] = status
        fail[L.F_T] = clock[L.T]
        fail[L.F_VALUE] = r.value
        fail[L.F_INDEX] = worst_segment(u, system.h) if status == BAD_STRAIN else 0
        fail[L.F_DT] = 0.0
        return L.FAILED
    ke, st, be, fe, ge, emin, z, w = energies(u, v, work[1], system, rod, floor)
    clock[L.E0] = ke + st + be + fe + ge
    clock[L.W] = w
    clock[L.DT] = C.propose(ctrl, r.dt_suggest, np.inf, bool(False))
    clock[L.EMIN] = emin
    if u[0] < 0.0:
        open_contact(ev, clock[L.T], w, u[0], r.floor_force, emin, ke - 0.5 * w * w + st + be)
    emit(state, work, system, rod, floor, clock, count, arrays.times, clock[L.T],
         clock[L.DT], count[L.STEP], snap_t, snap_step, snap_u, snap_v, diag, bool(False))
    observe_start(obs, arrays.observed, system, rod, floor, clock[L.T], u, v)
    observe_values(obs, arrays.observed)
    count[L.STARTED] = 1
    return OK


@kernel
def advance(scheme, ctrl, system, rod, floor, obs, arrays, max_steps):
    """Step from the state in ``arrays.state`` (u, v, a rows) and leave the new state
    there; ``arrays.trial`` (3 rows) holds the trial states, ``arrays.interp`` (2 rows) the
    interpolated (u, v) of a dense output (module docstring; ``arrays.RunArrays``).  The
    observer ``obs`` sees every accepted step and may end the run; its values are in
    ``arrays.observed`` when the call returns (``observers``).

    Returns layout.DONE, FULL, PAUSED or FAILED.
    """
    state = arrays.state
    trial = arrays.trial
    work = arrays.work
    interp = arrays.interp
    sstats = arrays.sstats
    clock = arrays.clock
    count = arrays.count
    ev = arrays.ev
    snap_t = arrays.snap_t
    snap_step = arrays.snap_step
    snap_u = arrays.snap_u
    snap_v = arrays.snap_v
    diag = arrays.diag
    episodes = arrays.episodes
    bounces = arrays.bounces
    fail = arrays.fail
    times = arrays.times
    observed = arrays.observed
    cur = state
    nxt = trial
    swapped = False
    t = clock[L.T]
    dtp = clock[L.DT]
    t_end = clock[L.T_END]
    tol = clock[L.TOL]
    diss = clock[L.DISSIPATED]
    w = clock[L.W]
    refined = False
    sides = _sides(scheme, floor)
    forced = 0      # 1: the trial takes the side it is moving into; 2: the law itself
    # no break can come between a rejection and the next acceptance; a run-time flag
    # (rodjit._jit: literal flags)
    after_reject = bool(False)
    fixed = ctrl.dt_fixed > 0.0
    interpolate = ctrl.dense and has_dense(scheme)   # a constant False without one
    inside = False   # the trial step has an output time inside it (dense output)
    emin_cur = clock[L.EMIN]
    rod_lo = lower(rod)
    floor_lo = lower(floor)
    cap_s = snap_t.size
    cap_d = diag.shape[0]
    cap_e = episodes.shape[0]
    cap_b = bounces.shape[0]
    taken = 0
    code = L.PAUSED
    while True:
        if t >= t_end - tol:
            code = L.DONE
            break
        if (stop_due(ctrl, count, cur[0], cur[1], work[1], system, rod, floor)
                or observe_stop(obs, observed)):
            # the run ends here (``time.stop_after_bounces``, ``time.stop_at_rest``, the
            # observer's ``stop``): its last rows at t, once the buffers have room for them
            if count[L.N_SNAP] >= cap_s or count[L.N_DIAG] >= cap_d:
                code = L.FULL
                break
            clock[L.DISSIPATED] = diss
            emit_final(cur, work, system, rod, floor, clock, count, times, t, dtp,
                       count[L.STEP], snap_t, snap_step, snap_u, snap_v, diag)
            clock[L.T_END] = t      # the run's end: complete, as one that reached t_end
            code = L.DONE
            break
        if taken >= max_steps:
            code = L.PAUSED
            break
        if (count[L.N_SNAP] >= cap_s or count[L.N_DIAG] >= cap_d
                or count[L.N_EP] >= cap_e or count[L.N_BOUNCE] >= cap_b):
            code = L.FULL
            break
        if interpolate:
            target, dt, land, n_s, n_d = dense_target(ctrl, fixed, clock, count, times, t,
                                                      dtp)
            if count[L.N_SNAP] + n_s > cap_s or count[L.N_DIAG] + n_d > cap_d:
                code = L.FULL   # before the step: it is the same whatever the buffers held
                break
        else:
            target = next_target(clock, count, times)
            dt, land = C.step_to(ctrl, fixed, target - t, dtp)
        u = cur[0]
        v = cur[1]
        u2 = nxt[0]
        v2 = nxt[1]
        side = BOTH
        if sides and not fixed:
            # The pairs step with the floor law of the side of u_0 = 0 the trial starts on
            # (at 0, the side it moves into): the force along the step is smooth, so the
            # error estimate holds, and a trial that leaves its side is taken again ending
            # where it leaves (below).  A step that ends on a crossing is never stretched
            # to an output time.
            if refined and dt > dtp:
                dt = dtp
                land = False
            into = u[0] > 0.0 or (u[0] == 0.0 and v[0] >= 0.0)
            if forced == 1:
                into = not into
            side = FREE if into else CONTACT
            if forced == 2:
                side = BOTH
        tfloor = _trial_floor(scheme, floor, side)
        r = step(scheme, system, rod, tfloor, u, v, cur[2], u2, v2, nxt[2], work, sstats, dt)
        status = r.status
        val = r.value
        emin = r.min_strain
        if status == INACCURATE and fixed:
            status = OK   # fixed steps: the state is valid; the error estimate is not asked
        if sides and status == OK and not fixed and side != BOTH:
            # where u_0 first leaves the trial's side, an excursion inside the step included
            sc = hermite_exit(u[0], v[0], cur[2][0], u2[0], v2[0], nxt[2][0], dt, side == FREE)
            if sc <= 1.0 and not refined:
                if sc > C.EVENT_MIN and sc * dt >= ctrl.dt_min:
                    dtp = sc * dt
                    refined = True
                    continue
                # it leaves its side at once: the same step on the other side, and if it
                # leaves that too, with the law itself; the start's derivative once under
                # the law those trials take (it differs from the one at the start by the
                # floor stress across the switch)
                forced += 1
                nside = BOTH if forced == 2 else (CONTACT if side == FREE else FREE)
                full_accel(system, rod, _trial_floor(scheme, floor, nside), u, v, cur[2],
                           work[0], work[1], bool(False))
                dtp = dt
                count[L.REJECTED] += 1
                continue
        elif (status == OK and not fixed and not refined
                and (u[0] < 0.0) != (u2[0] < 0.0)):
            # σ_b has a kink at u_0 = 0 (its stiffness jumps from 0 to 3κ_b/β): a step that
            # straddles it makes an O(dt²) energy error, and one sized for flight that ends
            # even slightly inside the floor closes with a kick at the contact stiffness.
            # Retry once, ending on the crossing, so every step sees a smooth force.
            sc = crossing(u[0], v[0], u2[0], v2[0], dt)
            if sc > C.EVENT_MIN and sc * dt >= ctrl.dt_min:
                dtp = sc * dt
                refined = True
                continue
        refined = False
        if status == OK and ctrl.gap > 0.0 and not fixed:
            # The barriers stiffen like (gap)^-4: an explicit step sized by the stiffness at
            # its start can close most of a gap and leave a state no step can recover from.
            # Approach ε = −1 and u_0 = −β geometrically: reject a step that closed more
            # than twice the allowed fraction of either gap.
            keep = C.gap_keep(ctrl)
            if (emin - rod_lo < keep * (emin_cur - rod_lo)
                    or u2[0] - floor_lo < keep * (u[0] - floor_lo)):
                status = TOO_CLOSE
                val = emin
        if status == OK and interpolate:
            t_new = target if land else t + dt
            inside = min(grid_time(clock, count, times, L.K_SNAP, L.SNAP_DT, int(0)),
                         grid_time(clock, count, times, L.K_DIAG, L.DIAG_DT, int(0))
                         ) < t_new - tol
            if inside:
                # the extra stages of the continuous extension, once for every output of
                # the step; one outside the admissible set retries the step shorter
                status, val = dense_setup(scheme, system, rod, tfloor, u, v, cur[2], u2, v2,
                                          nxt[2], work, dt)
        # a bounce open or opening: its extremes come from inside the step (``extremes``),
        # by the dense output of a scheme that has one (set up here if no output needed it)
        extremes = ev[L.B_NEP] > 0.0 or u2[0] < 0.0
        if status == OK and has_dense(scheme) and extremes and not (interpolate and inside):
            status, val = dense_setup(scheme, system, rod, tfloor, u, v, cur[2], u2, v2, nxt[2],
                                      work, dt)
        if status != OK:
            count[L.REJECTED] += 1
            retry = C.retry(status == INACCURATE, r.dt_suggest, dt)
            if fixed or retry < ctrl.dt_min:
                fail[L.F_CODE] = status
                fail[L.F_T] = t
                fail[L.F_VALUE] = val
                fail[L.F_INDEX] = worst_segment(u2, system.h) if status == BAD_STRAIN else 0
                fail[L.F_DT] = dt
                code = L.FAILED
                break
            dtp = retry
            after_reject = True
            continue
        # the step ended a sliver across the switch: once its outputs and extremes are
        # taken (from the step's own derivative: its continuous extension reads it), the
        # new state's derivative under the law itself, so the next step starts consistent
        resync = sides and side != BOTH and (side == FREE) != (u2[0] >= 0.0)
        forced = 0
        t_new = target if land else t + dt
        evib = 0.0     # the vibration energy at a new bounce's impact (its step's start)
        if ev[L.B_NEP] == 0.0 and ev[L.IN_CONTACT] == 0.0 and u2[0] < 0.0:
            evib = vibration_energy(u, v, work[1], system, rod, floor)
        u0x = u2[0]
        ffx = r.floor_force
        eminx = emin
        if extremes:
            u0x, ffx, eminx = step_extremes(scheme, cur, nxt, work, interp, system, floor, dt,
                                            ffx, eminx)
        track(ev, count, episodes, bounces, t, t_new - t, system.g, u[0], v[0], u2[0], v2[0],
              w, r.w, ffx, eminx, evib, u0x)
        diss_old = diss
        diss += r.dissipated
        w = r.w
        t_old = t
        t = t_new
        cur, nxt = nxt, cur
        swapped = not swapped
        count[L.STEP] += 1
        taken += 1
        observe_step(obs, observed, system, rod, floor, t_old, t, nxt[0], nxt[1],
                     cur[0], cur[1])
        dtp = C.propose(ctrl, r.dt_suggest, dtp, after_reject)
        after_reject = bool(False)
        if ctrl.gap > 0.0 and not fixed:
            dtp = min(dtp, C.gap_limit(ctrl, dt, emin_cur - rod_lo, emin - rod_lo),
                      C.gap_limit(ctrl, dt, u[0] - floor_lo, u2[0] - floor_lo))
        emin_cur = emin
        if interpolate:
            if inside:
                emit_dense(scheme, nxt, cur, work, interp, system, rod, floor, tfloor, clock,
                           count, times, t_old, dt, t, diss_old, dtp, count[L.STEP], snap_t,
                           snap_step, snap_u, snap_v, diag)
            clock[L.DISSIPATED] = diss
            # an output time at the step's end: its own state (at the grid's time unless
            # the step landed there, as on t_end)
            emit(cur, work, system, rod, floor, clock, count, times, t, dtp, count[L.STEP],
                 snap_t, snap_step, snap_u, snap_v, diag, not land)
        elif land:
            clock[L.DISSIPATED] = diss
            emit(cur, work, system, rod, floor, clock, count, times, t, dtp, count[L.STEP],
                 snap_t, snap_step, snap_u, snap_v, diag, bool(False))
        if resync:
            full_accel(system, rod, _trial_floor(scheme, floor, BOTH), cur[0], cur[1], cur[2],
                       work[0], work[1], bool(False))
    clock[L.T] = t
    clock[L.DT] = dtp
    clock[L.DISSIPATED] = diss
    clock[L.W] = w
    clock[L.EMIN] = emin_cur
    observe_values(obs, observed)
    if swapped:
        for r in range(state.shape[0]):
            for i in range(state.shape[1]):
                state[r, i] = cur[r, i]
    return code
