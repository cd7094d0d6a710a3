"""Contact episodes and bounces (MODEL.md §3), tracked step by step inside the loop.

An episode is a maximal interval with u_0 < 0; its ends are located inside the step from
the side of the step that is out of contact (where the force is smooth).  A bounce is one
physical impact: the episodes from the first contact after a flight to the release after
which the rod flies.  A *flight* follows a release when the bottom then stays off the floor
for at least ``FLIGHT_TIME`` τ (the driver sets τ = π h/c, the period of the highest mode
of the semi-discrete rod) and the centre of mass turns over (w from + to −) before the next
contact: the rod leaves rising and comes back falling.  So the bounce closes, online, at the
first step that ends out of contact with both true; a contact before that continues it.
"""
import numpy as np

from ..kernels.forces import energies
from . import layout as L
from .._jit import exact_kernel, kernel, step_kernel

# a bounce is ambiguous (its restitution says more about the rod's vibration than about the
# impact) when its approach speed |w_impact| is below this fraction of the vibrational
# velocity scale sqrt(2 E_vib/m) at the impact (MODEL.md §3)
AMBIGUOUS_SPEED = 0.2


@step_kernel
def stop_due(ctrl, count, u, v, k, system, rod, floor):
    """Whether the run ends before t_end at the state (u, v) (``k``: a scratch row):
    ``ctrl.stop_bounces`` bounces are over (``time.stop_after_bounces``), or the bottom is
    in contact with the energy below ``ctrl.rest_energy``, the lift-off energy: the energy
    never increases, so the rod never leaves the floor again (``time.stop_at_rest``).
    Read from what a checkpoint keeps, so a resumed run stops where an uninterrupted one
    does."""
    if ctrl.stop_bounces > 0 and count[L.BOUNCES_TOTAL] >= ctrl.stop_bounces:
        return True
    if ctrl.rest_energy > -np.inf and u[0] < 0.0:
        ke, st, be, fe, ge, emin, z, w = energies(u, v, k, system, rod, floor)
        return ke + st + be + fe + ge < ctrl.rest_energy
    return False


@kernel
def _root(c0, c1, c2):
    """The root in [0, 1] of c0 + c1 s + c2 s² nearest 0, given a sign change on [0, 1]."""
    if c0 == 0.0:
        return 0.0
    lo = 0.0
    hi = 1.0
    neg0 = c0 < 0.0
    for _ in range(60):
        s = 0.5 * (lo + hi)
        if ((c0 + s * (c1 + s * c2)) < 0.0) == neg0:
            lo = s
        else:
            hi = s
    return 0.5 * (lo + hi)


@kernel
def touchdown(ua, va, ub, dt):
    """Fraction of the step at which u_0 reaches 0 coming from above.

    Uses only the start of the step, which is out of contact: the quadratic through
    (u_a, v_a) and u_b is the Taylor polynomial with the start's acceleration (for Verlet,
    u_b = u_a + dt v_a + dt²/2 a_a exactly), blind to the floor force after the crossing."""
    return _root(ua, dt * va, ub - ua - dt * va)


@kernel
def release(ua, ub, vb, dt):
    """Fraction of the step at which u_0 climbs back to 0; uses only the end of the step,
    which is out of contact (the backward Taylor quadratic from (u_b, v_b) through u_a)."""
    # p(s) = u_b − (1−s) dt v_b + (1−s)² c with c = u_a − u_b + dt v_b, written in s
    c = ua - ub + dt * vb
    return _root(ub - dt * vb + c, dt * vb - 2.0 * c, c)


@kernel
def crossing(ua, va, ub, vb, dt):
    """Fraction of the step where u_0 crosses 0, from whichever side is out of contact."""
    if ua >= 0.0:
        return touchdown(ua, va, ub, dt)
    return release(ua, ub, vb, dt)


EXIT_SAMPLES = 16


@kernel
def _quintic(s, ua, b1, b2, c3, c4, c5):
    return ua + s * (b1 + s * (b2 + s * (c3 + s * (c4 + s * c5))))


@kernel
def hermite_exit(ua, va, aa, ub, vb, ab, dt, free):
    """Fraction of the step where u_0 first leaves its side along the quintic Hermite
    interpolant of both ends (height, velocity and acceleration at each; ``free``: the side
    u_0 ≥ 0, else u_0 < 0), or 2.0 if it stays on it: the exits of a step whose force is
    smooth (a floor law held to one side), an excursion inside the step included.  The
    interpolant is accurate to O(dt⁶); it is sampled at ``EXIT_SAMPLES`` points and the
    first exit found by bisection."""
    b1 = dt * va
    b2 = 0.5 * dt * dt * aa
    r0 = ub - (ua + b1 + b2)
    r1 = dt * vb - (b1 + 2.0 * b2)
    r2 = dt * dt * ab - 2.0 * b2
    c3 = 10.0 * r0 - 4.0 * r1 + 0.5 * r2
    c4 = -15.0 * r0 + 7.0 * r1 - r2
    c5 = 6.0 * r0 - 3.0 * r1 + 0.5 * r2
    first = 2.0
    for k in range(1, EXIT_SAMPLES + 1):
        s = k / EXIT_SAMPLES
        if k == EXIT_SAMPLES:
            ps = ub
        else:
            ps = _quintic(s, ua, b1, b2, c3, c4, c5)
        if (ps < 0.0) if free else (ps >= 0.0):
            first = s
            break
    if first > 1.0:
        return 2.0
    lo = first - 1.0 / EXIT_SAMPLES
    hi = first
    for _ in range(50):
        s = 0.5 * (lo + hi)
        ps = _quintic(s, ua, b1, b2, c3, c4, c5)
        if (ps < 0.0) if free else (ps >= 0.0):
            hi = s
        else:
            lo = s
    return 0.5 * (lo + hi)


@kernel
def _update_extremes(ev, u0, ff, emin):
    ev[L.CUR_MIN_U0] = min(ev[L.CUR_MIN_U0], u0)
    ev[L.CUR_MAX_FF] = max(ev[L.CUR_MAX_FF], ff)
    ev[L.CUR_MIN_EPS] = min(ev[L.CUR_MIN_EPS], emin)


@exact_kernel
def vibration_energy(u, v, k, system, rod, floor):
    """Kinetic + stretch + bend energy about the centre of mass (total mass 1), the
    ``energy_vibration`` of the diagnostics; ``k`` is scratch for the curvatures."""
    ke, st, be, fe, ge, emin, z, w = energies(u, v, k, system, rod, floor)
    return ke - 0.5 * w * w + st + be


@kernel
def open_contact(ev, t, w, u0, ff, emin, evib):
    """A contact episode starts at t (also used when the run starts in contact); ``evib``
    is the vibration energy at t, read only if the episode opens a bounce."""
    ev[L.IN_CONTACT] = 1.0
    ev[L.EP_START] = t
    ev[L.FLIGHT] = 0.0
    if ev[L.B_NEP] == 0.0:
        ev[L.B_T_IMPACT] = t
        ev[L.B_W_IMPACT] = w
        ev[L.B_EV_IMPACT] = evib
        ev[L.B_T_RELEASE] = np.nan
        ev[L.B_W_RELEASE] = np.nan
        ev[L.CUR_MIN_U0] = u0
        ev[L.CUR_MAX_FF] = ff
        ev[L.CUR_MIN_EPS] = emin
    else:
        _update_extremes(ev, u0, ff, emin)
    ev[L.B_NEP] += 1.0


@step_kernel
def track(ev, count, episodes, bounces, t, dt, g, u0a, v0a, u0b, v0b, wa, wb, ffb, eminb,
          evib, u0x):
    """Update the bookkeeping for the accepted step (t, t+dt]; write finished episodes
    and bounces into their buffers (the caller guarantees one free row in each).
    ``evib``: the vibration energy at the step's start, needed (and computed by the
    caller) only when the step touches down with no bounce open.  ``u0x``, ``ffb``,
    ``eminb``: the smallest u_0, the largest floor force and the smallest strain over the
    step (inside it too, ``stepping.extremes``), which the open bounce's extremes take in.

    Internal forces cancel in w = Σ m v, so out of contact w changes by g only: the
    centre-of-mass velocity at a crossing follows exactly from the step end that is out
    of contact."""
    if ev[L.IN_CONTACT] == 0.0:
        if u0b < 0.0:
            s = touchdown(u0a, v0a, u0b, dt)
            open_contact(ev, t + s * dt, wa + g * s * dt, u0x, ffb, eminb, evib)
        elif ev[L.B_NEP] > 0.0:
            _update_extremes(ev, u0x, ffb, eminb)
    else:
        _update_extremes(ev, u0x, ffb, eminb)
        if u0b >= 0.0:
            s = release(u0a, u0b, v0b, dt)
            tc = t + s * dt
            j = count[L.N_EP]
            episodes[j, L.EC_T_START] = ev[L.EP_START]
            episodes[j, L.EC_T_END] = tc
            count[L.N_EP] += 1
            count[L.EPISODES_TOTAL] += 1
            ev[L.IN_CONTACT] = 0.0
            ev[L.B_T_RELEASE] = tc
            ev[L.B_W_RELEASE] = wb - g * (1.0 - s) * dt
            # without gravity pulling it back, the rod flies if it leaves rising
            ev[L.FLIGHT] = 1.0 if (g >= 0.0 and ev[L.B_W_RELEASE] > 0.0) else 0.0
            ev[L.REL_MIN_U0] = ev[L.CUR_MIN_U0]
            ev[L.REL_MAX_FF] = ev[L.CUR_MAX_FF]
            ev[L.REL_MIN_EPS] = ev[L.CUR_MIN_EPS]
    if ev[L.IN_CONTACT] == 0.0 and ev[L.B_NEP] > 0.0:
        if wa > 0.0 and wb <= 0.0:
            ev[L.FLIGHT] = 1.0          # the centre of mass turned over off the floor
        # a flight: τ off the floor since the release and the turn-over; the bounce is over
        if ev[L.FLIGHT] != 0.0 and t + dt - ev[L.B_T_RELEASE] >= ev[L.FLIGHT_TIME]:
            j = count[L.N_BOUNCE]
            write_bounce(bounces[j], ev, bool(False))   # the type Python calls it with
            count[L.N_BOUNCE] += 1
            count[L.BOUNCES_TOTAL] += 1
            ev[L.B_NEP] = 0.0
            ev[L.FLIGHT] = 0.0


@kernel
def write_bounce(row, ev, is_open):
    """One bounce record (layout.BOUNCE_ROW_COLUMNS) from the bookkeeping; an open bounce has
    no release yet, so its release fields are NaN and its extremes run to now.  It is
    ambiguous if open, if it did not start falling (w_impact >= 0: the run started in
    contact) or if its approach speed is below AMBIGUOUS_SPEED of the vibrational velocity
    scale sqrt(2 E_vib) at the impact."""
    w_i = ev[L.B_W_IMPACT]
    e_vib = ev[L.B_EV_IMPACT]
    row[L.BC_T_IMPACT] = ev[L.B_T_IMPACT]
    row[L.BC_N_EPISODES] = ev[L.B_NEP]
    row[L.BC_W_IMPACT] = w_i
    row[L.BC_ENERGY_VIBRATION_IMPACT] = e_vib
    # NaN: not known (a bounce open at a checkpoint of run-file format 1 or 2)
    known = e_vib == e_vib
    e_pos = e_vib if e_vib > 0.0 else 0.0
    scale = np.sqrt(w_i * w_i + 2.0 * e_pos) if known else np.nan   # speed brought in
    ambiguous = (is_open or not w_i < 0.0
                 or (known and -w_i < AMBIGUOUS_SPEED * np.sqrt(2.0 * e_pos)))
    row[L.BC_AMBIGUOUS] = 1.0 if ambiguous else 0.0
    if is_open:
        row[L.BC_T_RELEASE] = np.nan
        row[L.BC_W_RELEASE] = np.nan
        row[L.BC_RESTITUTION] = np.nan
        row[L.BC_RESTITUTION_ENERGY] = np.nan
        row[L.BC_MIN_U0] = ev[L.CUR_MIN_U0]
        row[L.BC_MAX_FLOOR_FORCE] = ev[L.CUR_MAX_FF]
        row[L.BC_MIN_STRAIN] = ev[L.CUR_MIN_EPS]
    else:
        row[L.BC_T_RELEASE] = ev[L.B_T_RELEASE]
        row[L.BC_W_RELEASE] = ev[L.B_W_RELEASE]
        row[L.BC_RESTITUTION] = (-ev[L.B_W_RELEASE] / w_i if w_i != 0.0 else np.nan)
        row[L.BC_RESTITUTION_ENERGY] = (ev[L.B_W_RELEASE] / scale if scale > 0.0
                                        else np.nan)   # NaN > 0 is false
        row[L.BC_MIN_U0] = ev[L.REL_MIN_U0]
        row[L.BC_MAX_FLOOR_FORCE] = ev[L.REL_MAX_FF]
        row[L.BC_MIN_STRAIN] = ev[L.REL_MIN_EPS]
