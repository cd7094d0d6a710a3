"""The first-impact observables of one run in compiled code, for the ensemble engine
(``stepping.ensemble``): the same definitions as the NumPy reference
``records.observables`` (``first_impact``, ``macroscopic_contacts``, ``flight_groups``,
``_flight_state``, ``_open_episode_start``), evaluated for the first macroscopic contact only
(the only one ``impact_values`` reads), over the arrays a batch keeps of a run:

* ``track`` rows: the diagnostics columns TRACK (``T_*`` below; ``ImpactTrack``'s
  TRACK_COLUMNS) of every sample, in time order;
* ``eps`` rows: the finished contact episodes (t_start, t_end);
* ``brows`` rows: the bounce table (``layout.BOUNCE_ROW_COLUMNS`` and ``open`` last), the
  pending bounce included.

Every operation is the reference's, in its order, compiled without fused multiply-adds
(``exact_kernel``): a value here equals the NumPy one to the bit.  What needs the
configuration beyond the run (the lift-off energy that tells ``no lift-off`` from
``open``) and the reason texts are left to the caller: ``first_contact`` returns a code.
"""
import math

import numpy as np

from . import layout as L
from .._jit import exact_kernel, exact_step_kernel

# columns of a track row (records.observables.TRACK_COLUMNS, in that order)
T_T = 0
T_W = 1            # cm_velocity
T_Z = 2            # cm_height
T_KE = 3           # energy_kinetic
T_ES = 4           # energy_stretch
T_EB = 5           # energy_bend
T_U0 = 6           # u_bottom
T_FF = 7           # floor_force
T_E = 8            # energy_total
TRACK_SIZE = 9
# the track row's columns in a diagnostics row
TRACK_FROM_DIAG = (L.D_T, L.D_CM_VELOCITY, L.D_CM_HEIGHT, L.D_ENERGY_KINETIC,
                   L.D_ENERGY_STRETCH, L.D_ENERGY_BEND, L.D_U_BOTTOM, L.D_FLOOR_FORCE,
                   L.D_ENERGY_TOTAL)
BR_OPEN = len(L.BOUNCE_ROW_COLUMNS)    # the ``open`` column of a bounce row here
BROW_SIZE = BR_OPEN + 1

# codes of ``first_contact``
LIFT_OFF = 0
OPEN_AT_END = 1    # still in contact at the end: "no lift-off" or "open" (lift-off energy)
NO_IMPACT = 2
UNDEFINED = 3      # fewer than two diagnostics samples

# the values ``first_contact`` writes into ``out``
O_RESTITUTION = 0
O_APEX = 1
O_CONTACT_TIME = 2
O_T_IMPACT = 3
O_W_IMPACT = 4
O_REBOUND = 5
O_MIN_U0 = 6
O_EV_IMPACT = 7
O_E_END = 8        # energy_total of the last sample
O_T_LAST = 9       # time of the last sample
OUT_SIZE = 10


@exact_step_kernel
def _vibration(track, k):
    w = track[k, T_W]
    return track[k, T_KE] - 0.5 * w * w + track[k, T_ES] + track[k, T_EB]


@exact_step_kernel
def _carried(track, nd, g, t, lo, hi, before, out3):
    """``_flight_state``: (w, z, energy_vibration) at ``t`` along the free-flight parabola
    from the sample nearest ``t`` inside (lo, hi) into ``out3``; False without one."""
    k = -1
    if before:
        for j in range(nd):
            tj = track[j, T_T]
            if tj <= t and tj > lo:
                k = j
    else:
        for j in range(nd):
            tj = track[j, T_T]
            if tj >= t and tj < hi:
                k = j
                break
    if k < 0:
        return False
    d = t - track[k, T_T]
    w_s = track[k, T_W]
    z_s = track[k, T_Z]
    out3[0] = w_s + g * d
    out3[1] = z_s + w_s * d + 0.5 * g * d * d
    out3[2] = _vibration(track, k)
    return True


@exact_step_kernel
def _open_start(track, nd, eps, ne, brows, nb):
    """``_open_episode_start``: the start of the episode still running at the end."""
    if ne == 0 and nb > 0:
        return brows[0, L.BC_T_IMPACT]
    after = eps[ne - 1, 1] if ne > 0 else -np.inf
    for k in range(nd):
        t = track[k, T_T]
        u = track[k, T_U0]
        if t > after and u < 0:
            if k == 0 or track[k - 1, T_T] <= after:
                return t
            t0 = track[k - 1, T_T]
            u0 = track[k - 1, T_U0]
            return t0 + (t - t0) * u0 / (u0 - u)
    return after if math.isfinite(after) else 0.0


@exact_step_kernel
def _episode(eps, ne, k, open_start, start):
    """t_start (``start``) or t_end of episode ``k``, the open one (index ne) appended."""
    if k < ne:
        return eps[k, 0] if start else eps[k, 1]
    return open_start if start else np.nan


@exact_step_kernel
def apex(g, w_i, z_i, w_r, z_r):
    """``observables._apex_restitution``."""
    if g > 0 or w_i >= 0:
        return np.nan
    a = -2.0 * g
    num = w_r * w_r + a * (z_r - 0.5)
    den = w_i * w_i + a * (z_i - 0.5)
    if not den > 0:
        return np.nan
    return math.sqrt(max(num, 0.0) / den)


@exact_kernel
def first_contact(track, nd, eps, ne, brows, nb, g, tau, t_final, in_contact, out, st):
    """The first macroscopic contact of a run (``records.observables.first_impact``) into
    ``out`` (``O_*``; ``st`` is 3 floats of scratch).  Returns LIFT_OFF, OPEN_AT_END,
    NO_IMPACT or UNDEFINED; ``track`` has ``nd`` rows, ``eps`` ``ne``, ``brows`` ``nb``."""
    for j in range(OUT_SIZE):
        out[j] = np.nan
    if nd < 2:
        return UNDEFINED
    out[O_E_END] = track[nd - 1, T_E]
    out[O_T_LAST] = track[nd - 1, T_T]
    ostart = _open_start(track, nd, eps, ne, brows, nb) if in_contact else np.nan
    n_all = ne + 1 if in_contact else ne
    if n_all == 0:
        return NO_IMPACT
    # the first group of ``flight_groups``: episodes 0..b
    b = 0
    for k in range(1, n_all):
        t_rel = _episode(eps, ne, k - 1, ostart, False)
        t_next = _episode(eps, ne, k, ostart, True)
        flight = False
        if t_next - t_rel >= tau:
            w_r = -1.0
            if _carried(track, nd, g, t_rel, t_rel, t_next, False, st):
                w_r = st[0]
            flight = w_r > 0 and (g >= 0 or t_rel + w_r / -g < t_next)
        if flight:
            break
        b = k
    t_imp = _episode(eps, ne, 0, ostart, True)
    t_rel = _episode(eps, ne, b, ostart, False)
    is_open = math.isnan(t_rel)
    next_start = _episode(eps, ne, b + 1, ostart, True) if b + 1 < n_all else np.inf
    if _carried(track, nd, g, t_imp, -np.inf, t_imp, True, st):
        w_i = st[0]
        z_i = st[1]
        ev_i = st[2]
    else:       # the run starts in contact: the initial sample is the impact
        w_i = track[0, T_W]
        z_i = track[0, T_Z]
        ev_i = _vibration(track, 0)
    w_r = np.nan
    z_r = np.nan
    if not is_open:
        if not _carried(track, nd, g, t_rel, t_rel, next_start, False, st):
            # released at the very end of the run: the nearest sample
            k = 0
            best = abs(track[0, T_T] - t_rel)
            for j in range(1, nd):
                d = abs(track[j, T_T] - t_rel)
                if d < best:
                    best = d
                    k = j
            st[0] = track[k, T_W]
            st[1] = track[k, T_Z]
        w_r = st[0]
        z_r = st[1]
    end = t_final if is_open else t_rel
    rebound = 0.0
    any_inside = False
    wmax = -np.inf
    umin = np.inf
    unan = False
    for j in range(nd):
        tj = track[j, T_T]
        if tj >= t_imp and tj <= end:
            w = track[j, T_W]       # finite: a block with a non-finite row is refused
            if w > wmax:
                wmax = w
            any_inside = True
            u = track[j, T_U0]
            if u != u:
                unan = True
            elif u < umin:
                umin = u
    if any_inside:
        rebound = max(0.0, wmax)
    if not is_open and w_r > rebound:
        rebound = w_r
    n_u = 0
    for j in range(nb):
        bi = brows[j, L.BC_T_IMPACT]
        br = brows[j, L.BC_T_RELEASE]
        bo = brows[j, BR_OPEN] != 0.0
        if bi >= t_imp and (br <= end or (bo and is_open)):
            u = brows[j, L.BC_MIN_U0]
            n_u += 1
            if u != u:
                unan = True
            elif u < umin:
                umin = u
    if unan:
        umin = np.nan
    elif not any_inside and n_u == 0:
        umin = np.nan
    out[O_T_IMPACT] = t_imp
    out[O_W_IMPACT] = w_i
    out[O_REBOUND] = rebound
    out[O_MIN_U0] = umin
    out[O_EV_IMPACT] = ev_i
    if is_open:
        return OPEN_AT_END
    out[O_RESTITUTION] = -w_r / w_i if w_i < 0 else np.nan
    out[O_APEX] = apex(g, w_i, z_i, w_r, z_r)
    out[O_CONTACT_TIME] = t_rel - t_imp
    return LIFT_OFF
