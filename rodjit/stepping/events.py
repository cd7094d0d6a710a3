"""Contact episodes and bounces (MODEL.md §3), tracked step by step inside the loop.

An episode is a maximal interval with u_0 < 0; its ends are interpolated inside the step
with the cubic Hermite interpolant of (u_0, v_0).  A bounce collects the episodes between
two apexes of the centre of mass (w from + to − with no contact active).
"""
import numba
import numpy as np

from . import layout as L


@numba.njit(cache=True)
def crossing(ua, va, ub, vb, dt):
    """Fraction s ∈ [0, 1] of the step where the Hermite cubic of u_0 changes sign
    (ua and ub on opposite sides of 0, or ua == 0)."""
    if ua == 0.0:
        return 0.0
    lo = 0.0
    hi = 1.0
    sa = ua < 0.0
    for _ in range(60):
        s = 0.5 * (lo + hi)
        s2 = s * s
        s3 = s2 * s
        p = ((2 * s3 - 3 * s2 + 1) * ua + (s3 - 2 * s2 + s) * dt * va
             + (-2 * s3 + 3 * s2) * ub + (s3 - s2) * dt * vb)
        if (p < 0.0) == sa:
            lo = s
        else:
            hi = s
    return 0.5 * (lo + hi)


@numba.njit(cache=True)
def _update_extremes(ev, u0, ff, emin):
    ev[L.CUR_MIN_U0] = min(ev[L.CUR_MIN_U0], u0)
    ev[L.CUR_MAX_FF] = max(ev[L.CUR_MAX_FF], ff)
    ev[L.CUR_MIN_EPS] = min(ev[L.CUR_MIN_EPS], emin)


@numba.njit(cache=True)
def open_contact(ev, t, w, u0, ff, emin):
    """A contact episode starts at t (also used when the run starts in contact)."""
    ev[L.IN_CONTACT] = 1.0
    ev[L.EP_START] = t
    if ev[L.B_NEP] == 0.0:
        ev[L.B_T_IMPACT] = t
        ev[L.B_W_IMPACT] = w
        ev[L.B_T_RELEASE] = np.nan
        ev[L.B_W_RELEASE] = np.nan
        ev[L.CUR_MIN_U0] = u0
        ev[L.CUR_MAX_FF] = ff
        ev[L.CUR_MIN_EPS] = emin
    ev[L.B_NEP] += 1.0


@numba.njit(cache=True)
def track(ev, count, episodes, bounces, t, dt, g, u0a, v0a, u0b, v0b, wa, wb, ffb, eminb):
    """Update the bookkeeping for the accepted step (t, t+dt]; write finished episodes
    and bounces into their buffers (the caller guarantees one free row in each).

    Internal forces cancel in w = Σ m v, so out of contact w changes by g only: the
    centre-of-mass velocity at a crossing follows exactly from the step end that is out
    of contact."""
    if ev[L.IN_CONTACT] == 0.0:
        if u0b < 0.0:
            s = crossing(u0a, v0a, u0b, v0b, dt)
            open_contact(ev, t + s * dt, wa + g * s * dt, u0b, ffb, eminb)
        elif ev[L.B_NEP] > 0.0:
            _update_extremes(ev, u0b, ffb, eminb)
    else:
        _update_extremes(ev, u0b, ffb, eminb)
        if u0b >= 0.0:
            s = crossing(u0a, v0a, u0b, v0b, dt)
            tc = t + s * dt
            j = count[L.N_EP]
            episodes[j, 0] = ev[L.EP_START]
            episodes[j, 1] = tc
            count[L.N_EP] += 1
            count[L.EPISODES_TOTAL] += 1
            ev[L.IN_CONTACT] = 0.0
            ev[L.B_T_RELEASE] = tc
            ev[L.B_W_RELEASE] = wb - g * (1.0 - s) * dt
            ev[L.REL_MIN_U0] = ev[L.CUR_MIN_U0]
            ev[L.REL_MAX_FF] = ev[L.CUR_MAX_FF]
            ev[L.REL_MIN_EPS] = ev[L.CUR_MIN_EPS]
    # an apex closes the bounce (its last episode has ended: no contact is active)
    if ev[L.IN_CONTACT] == 0.0 and wa > 0.0 and wb <= 0.0 and ev[L.B_NEP] > 0.0:
        j = count[L.N_BOUNCE]
        write_bounce(bounces[j], ev, False)
        count[L.N_BOUNCE] += 1
        count[L.BOUNCES_TOTAL] += 1
        ev[L.B_NEP] = 0.0


@numba.njit(cache=True)
def write_bounce(row, ev, is_open):
    """One bounce record (layout.BOUNCE_COLUMNS) from the bookkeeping; an open bounce has
    no release yet, so its release fields are NaN and its extremes run to now."""
    row[0] = ev[L.B_T_IMPACT]
    row[2] = ev[L.B_NEP]
    row[3] = ev[L.B_W_IMPACT]
    if is_open:
        row[1] = np.nan
        row[4] = np.nan
        row[5] = np.nan
        row[6] = ev[L.CUR_MIN_U0]
        row[7] = ev[L.CUR_MAX_FF]
        row[8] = ev[L.CUR_MIN_EPS]
    else:
        row[1] = ev[L.B_T_RELEASE]
        row[4] = ev[L.B_W_RELEASE]
        row[5] = -ev[L.B_W_RELEASE] / ev[L.B_W_IMPACT] if ev[L.B_W_IMPACT] != 0.0 else np.nan
        row[6] = ev[L.REL_MIN_U0]
        row[7] = ev[L.REL_MAX_FF]
        row[8] = ev[L.REL_MIN_EPS]
