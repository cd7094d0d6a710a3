"""The first-impact observables of a run (docs/MODEL.md §3): its first macroscopic contact,
computed as the run drains, in a fixed-size state.  The one implementation of them: a
sweep point's driver (``stepping.trajectory``: the CPU engine's batch call and a GPU
thread) runs it compiled, block by block as the loop drains; a run writer, a sweep
point's sink, a run file read back and a ``Result`` run it through
``records.impact.ImpactStream``.

The definitions are those of the macroscopic contacts (``records.contacts``: a contact
ends at a release followed by τ off the floor and a turn-over of the centre of mass), for
the first contact only: the impact state carried along the free-flight parabola from the
last sample at or before its start, the release state from the first sample at or after
its end (the nearest sample when none follows), the largest w and the smallest u_0 from
the impact to the release (to the end of the run while it is open), the u_0 extremes of
the bounce rows inside it, and the energy left at the end.

A run's track is read for a handful of things only, each tied to a time that the episode
rows fix: the sample last at or before the first contact's start (the impact state), the
first sample at or after each release (the flight test of a gap and the release state),
the sample nearest the release when none follows it, the extremes of w and u_0 from the
impact to the group's end, the first sample inside the floor after the last finished
episode (the start of an episode still open at the end), and the last sample.  Each is
kept here as it goes by, in the state ``s`` (``SIZE`` doubles, ``S_*`` below): a few
scalars and five track rows.  Nothing needs look-back, because the loop writes an
episode's row in the step that ends it, together with that step's samples, so:

* a block's episode rows are merged with its samples by time (``block``): every sample at
  or after an episode's end is taken after that episode, every earlier one before it;
* the first contact's start is known at the drain of the block it begins in, from the
  loop's ``ev`` (an episode still open) or from its episode row, before that block's
  samples are taken; all samples of earlier blocks lie before it (a reader of a whole run
  that knows the start beforehand gives it first, ``contact_start``);
* the macroscopic contact grows one episode at a time: the samples after the latest
  release are kept apart (``S_G*``) until the next episode says whether that gap was a
  flight (the group ends there, they are dropped) or not (they join the group, ``S_M*``).

Every kernel is compiled without fused multiply-adds (``exact_kernel``), so the
interpreter running their Python functions (``_jit.python_module``) computes the same
bits; tests/test_impact_stream.py feeds real runs in blocks of every size, compiled and
as Python, against the whole-table definitions (``records.contacts.first_impact``).  The
row arrays are indexed row first (``diag[j][c]``), so that the Python form also takes
lists.  One assumption about ties: the sample nearest a release at the very end of a run
(no sample after it) is taken to be the latest one, which holds whenever that sample lies
in the second half of [0, t_release] (then the distances are exact differences).
"""
import math

import numpy as np

from . import layout as L
from .._jit import exact_kernel

# columns of a kept track row (the ``R_*`` rows of the state)
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
# the diagnostics columns a sample is read from (``block``), in T_* order
TRACK_FROM_DIAG = (L.D_T, L.D_CM_VELOCITY, L.D_CM_HEIGHT, L.D_ENERGY_KINETIC,
                   L.D_ENERGY_STRETCH, L.D_ENERGY_BEND, L.D_U_BOTTOM, L.D_FLOOR_FORCE,
                   L.D_ENERGY_TOTAL)

# codes of ``finish``
LIFT_OFF = 0
OPEN_AT_END = 1    # still in contact at the end: "no lift-off" or "open" (lift-off energy)
NO_IMPACT = 2
UNDEFINED = 3      # fewer than two diagnostics samples

# the values ``finish`` writes into ``out``
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

# scalars of the state
S_ND = 0           # samples taken
S_NE = 1           # finished episodes taken
S_NB = 2           # bounce rows taken
S_S0 = 3           # the first contact's start (NaN: not begun yet)
S_EB = 4           # the end of the group's latest episode (its candidate end)
S_DONE = 5         # 1: the group ended at a flight (S_EB is its end, S_NEXT the next start)
S_NEXT = 6
S_PREV_T = 7       # the latest sample's t and u_0
S_PREV_U = 8
S_AFTER = 9        # the end of the latest finished episode (-inf: none)
S_O_FOUND = 10     # the first sample inside the floor after S_AFTER, and the one before it
S_O_T = 11
S_O_U = 12
S_O_PT = 13
S_O_PU = 14
S_O_PREV = 15      # 1: a sample before it exists
S_HAS_PRE = 16
S_HAS_POST = 17
S_M_ANY = 18       # the group's samples from the impact to S_EB: any, max w, min u_0, NaN u_0
S_M_WMAX = 19
S_M_UMIN = 20
S_M_UNAN = 21
S_G_ANY = 22       # the samples after S_EB, until the next episode decides
S_G_WMAX = 23
S_G_UMIN = 24
S_G_UNAN = 25
S_B_N = 26         # bounce rows inside the group: count, min u_0, NaN u_0
S_B_UMIN = 27
S_B_UNAN = 28
S_B0 = 29          # t_impact of the first bounce row
# track rows (T_* columns)
R_PRE = 30                          # the last sample at or before the contact's start
R_FIRST = R_PRE + TRACK_SIZE      # the first sample
R_LAST = R_FIRST + TRACK_SIZE     # the last sample
R_NEAR = R_LAST + TRACK_SIZE      # the first sample of the latest time
R_POST = R_NEAR + TRACK_SIZE      # the first sample at or after S_EB
ST = R_POST + TRACK_SIZE          # 3 doubles of scratch for ``finish`` (its ``st``)
SIZE = ST + 3


@exact_kernel
def reset(s):
    """An empty state: no sample, episode or bounce yet."""
    for j in range(SIZE):
        s[j] = 0.0
    s[S_S0] = np.nan
    s[S_EB] = np.nan
    s[S_NEXT] = np.inf
    s[S_AFTER] = -np.inf
    s[S_M_WMAX] = -np.inf
    s[S_M_UMIN] = np.inf
    s[S_G_WMAX] = -np.inf
    s[S_G_UMIN] = np.inf
    s[S_B_UMIN] = np.inf


@exact_kernel
def _keep(s, r, t, w, z, ke, es, eb, u0, ff, e):
    s[r + T_T] = t
    s[r + T_W] = w
    s[r + T_Z] = z
    s[r + T_KE] = ke
    s[r + T_ES] = es
    s[r + T_EB] = eb
    s[r + T_U0] = u0
    s[r + T_FF] = ff
    s[r + T_E] = e


@exact_kernel
def contact_start(s, t):
    """The first contact begins at ``t`` (its episode row, or the loop's ``ev`` while it is
    open); the samples at or after ``t`` taken so far (at most the last one, at ``t``
    exactly) join it."""
    if s[S_S0] == s[S_S0]:
        return
    s[S_S0] = t
    if s[S_HAS_PRE] != 0.0 and s[R_PRE + T_T] >= t:
        _inside(s, S_M_ANY, s[R_PRE + T_W], s[R_PRE + T_U0])


@exact_kernel
def _inside(s, a, w, u):
    """Fold a sample into the accumulator at ``a`` (S_M_ANY or S_G_ANY)."""
    if w > s[a + 1]:
        s[a + 1] = w
    s[a] = 1.0
    if u != u:
        s[a + 3] = 1.0
    elif u < s[a + 2]:
        s[a + 2] = u


@exact_kernel
def sample(s, t, w, z, ke, es, eb, u0, ff, e):
    """Take one diagnostics sample (its TRACK_FROM_DIAG columns)."""
    nd = s[S_ND]
    if nd == 0.0:
        _keep(s, R_FIRST, t, w, z, ke, es, eb, u0, ff, e)
        _keep(s, R_NEAR, t, w, z, ke, es, eb, u0, ff, e)
    elif t > s[R_NEAR + T_T]:
        _keep(s, R_NEAR, t, w, z, ke, es, eb, u0, ff, e)
    _keep(s, R_LAST, t, w, z, ke, es, eb, u0, ff, e)
    # the start of an episode open at the end (``open_start``)
    if s[S_O_FOUND] == 0.0 and t > s[S_AFTER] and u0 < 0:
        s[S_O_FOUND] = 1.0
        s[S_O_T] = t
        s[S_O_U] = u0
        s[S_O_PREV] = 1.0 if nd > 0.0 else 0.0
        s[S_O_PT] = s[S_PREV_T]
        s[S_O_PU] = s[S_PREV_U]
    s0 = s[S_S0]
    known = s0 == s0
    if not known or t <= s0:
        _keep(s, R_PRE, t, w, z, ke, es, eb, u0, ff, e)
        s[S_HAS_PRE] = 1.0
    if known and t >= s0 and s[S_DONE] == 0.0:
        eb_t = s[S_EB]
        if s[S_NE] == 0.0 or t <= eb_t:
            _inside(s, S_M_ANY, w, u0)
        else:
            _inside(s, S_G_ANY, w, u0)
        if s[S_NE] > 0.0 and s[S_HAS_POST] == 0.0 and t >= eb_t:
            _keep(s, R_POST, t, w, z, ke, es, eb, u0, ff, e)
            s[S_HAS_POST] = 1.0
    s[S_PREV_T] = t
    s[S_PREV_U] = u0
    s[S_ND] = nd + 1.0


@exact_kernel
def _flight(s, t_next, g, tau):
    """Whether the gap from S_EB to the next contact at ``t_next`` is a flight: at least
    τ off the floor, the centre of mass rising at the release (carried back from the
    first sample after it; a gap holding no sample is no flight) and, for g < 0, its apex
    before ``t_next``."""
    t_rel = s[S_EB]
    if t_next - t_rel >= tau:
        w_r = -1.0
        if s[S_HAS_POST] != 0.0 and s[R_POST + T_T] < t_next:
            d = t_rel - s[R_POST + T_T]
            w_r = s[R_POST + T_W] + g * d
        return w_r > 0 and (g >= 0 or t_rel + w_r / -g < t_next)
    return False


@exact_kernel
def _join_gap(s):
    if s[S_G_ANY] != 0.0:
        if s[S_G_WMAX] > s[S_M_WMAX]:
            s[S_M_WMAX] = s[S_G_WMAX]
        s[S_M_ANY] = 1.0
        if s[S_G_UNAN] != 0.0:
            s[S_M_UNAN] = 1.0
        if s[S_G_UMIN] < s[S_M_UMIN]:
            s[S_M_UMIN] = s[S_G_UMIN]
    s[S_G_ANY] = 0.0
    s[S_G_WMAX] = -np.inf
    s[S_G_UMIN] = np.inf
    s[S_G_UNAN] = 0.0


@exact_kernel
def episode(s, t_start, t_end, g, tau):
    """Take one finished contact episode; every sample before ``t_end`` was taken before,
    every later one comes after (``block``)."""
    contact_start(s, t_start)
    first = s[S_NE] == 0.0
    s[S_NE] += 1.0
    s[S_AFTER] = t_end
    s[S_O_FOUND] = 0.0
    if s[S_DONE] != 0.0:
        return
    if not first and _flight(s, t_start, g, tau):
        s[S_DONE] = 1.0
        s[S_NEXT] = t_start
        return
    _join_gap(s)
    s[S_EB] = t_end
    s[S_HAS_POST] = 0.0


@exact_kernel
def bounce(s, t_impact, t_release, min_u0):
    """Take one closed bounce row (its release lies at or before S_EB, or the group ended
    after it: it is inside the group when it starts at or after the impact)."""
    if s[S_NB] == 0.0:
        s[S_B0] = t_impact
    s[S_NB] += 1.0
    if t_impact >= s[S_S0] and (s[S_DONE] == 0.0 or t_release <= s[S_EB]):
        _bounce_u(s, min_u0)


@exact_kernel
def _bounce_u(s, u):
    s[S_B_N] += 1.0
    if u != u:
        s[S_B_UNAN] = 1.0
    elif u < s[S_B_UMIN]:
        s[S_B_UMIN] = u


@exact_kernel
def block(s, diag, nd, episodes, ne, bounces, nb, in_contact, ep_start, g, tau):
    """Take one drained block of the loop: ``nd`` diagnostics rows (``layout.DIAG_COLUMNS``),
    ``ne`` episode rows, ``nb`` closed bounce rows, and whether the loop is in contact at
    its end (``ev[IN_CONTACT]``) with that episode's start (``ev[EP_START]``)."""
    if s[S_S0] != s[S_S0]:
        if ne > 0:
            contact_start(s, episodes[0][L.EC_T_START])
        elif in_contact:
            contact_start(s, ep_start)
    k = 0
    for j in range(nd):
        row = diag[j]
        t = row[L.D_T]
        while k < ne and episodes[k][L.EC_T_END] <= t:
            episode(s, episodes[k][L.EC_T_START], episodes[k][L.EC_T_END], g, tau)
            k += 1
        sample(s, t, row[L.D_CM_VELOCITY], row[L.D_CM_HEIGHT], row[L.D_ENERGY_KINETIC],
               row[L.D_ENERGY_STRETCH], row[L.D_ENERGY_BEND], row[L.D_U_BOTTOM],
               row[L.D_FLOOR_FORCE], row[L.D_ENERGY_TOTAL])
    while k < ne:
        episode(s, episodes[k][L.EC_T_START], episodes[k][L.EC_T_END], g, tau)
        k += 1
    for j in range(nb):
        bounce(s, bounces[j][L.BC_T_IMPACT], bounces[j][L.BC_T_RELEASE], bounces[j][L.BC_MIN_U0])


@exact_kernel
def apex(g, w_i, z_i, w_r, z_r):
    """The apex restitution sqrt((z_apex_after − ½)/(z_apex_before − ½)) of an impact at
    (w_i, z_i) and a release at (w_r, z_r), the apexes those of the free-flight parabolas
    through them (z_apex = z + w²/(2|g|); ½ is the centre-of-mass height of the undeformed
    rod standing on the floor); at g = 0 the rigid-body kinetic-energy ratio; NaN for
    g > 0 or w_i >= 0."""
    if g > 0 or w_i >= 0:
        return np.nan
    a = -2.0 * g
    num = w_r * w_r + a * (z_r - 0.5)
    den = w_i * w_i + a * (z_i - 0.5)
    if not den > 0:
        return np.nan
    return math.sqrt(max(num, 0.0) / den)


@exact_kernel
def open_start(s, nb):
    """The start of the contact episode still running at the end: the first bounce row's
    impact if no episode finished and there are ``nb`` > 0 bounce rows (the pending one
    included), else the first sample inside the floor after the last finished episode,
    back to the linear root of u_0 between it and the sample before."""
    if s[S_NE] == 0.0 and nb > 0.0:
        return s[S_B0]
    if s[S_O_FOUND] != 0.0:
        t = s[S_O_T]
        if s[S_O_PREV] != 0.0 and s[S_O_PT] > s[S_AFTER]:
            t0 = s[S_O_PT]
            u0 = s[S_O_PU]
            t = t0 + (t - t0) * u0 / (u0 - s[S_O_U])
        return t
    after = s[S_AFTER]
    return after if math.isfinite(after) else 0.0


@exact_kernel
def _carry(s, r, g, t, out3):
    """(w, z, energy_vibration) at ``t`` along the free-flight parabola from the kept row
    at ``r`` into ``out3``."""
    d = t - s[r + T_T]
    w_s = s[r + T_W]
    z_s = s[r + T_Z]
    out3[0] = w_s + g * d
    out3[1] = z_s + w_s * d + 0.5 * g * d * d
    w = s[r + T_W]
    out3[2] = s[r + T_KE] - 0.5 * w * w + s[r + T_ES] + s[r + T_EB]


@exact_kernel
def finish(s, pending, p_t_impact, p_t_release, p_open, p_min_u0, g, tau, t_final,
           in_contact, out, st):
    """The first contact's values into ``out`` (``O_*``) and its code (LIFT_OFF,
    OPEN_AT_END, NO_IMPACT or UNDEFINED), at the end of the run at ``t_final``, in contact
    then if ``in_contact`` (u_0 < 0): ``pending`` says whether a bounce is still pending
    (``events.write_bounce``'s row: its t_impact, t_release, open flag and min u_0); ``st``
    is 3 floats of scratch.  It changes ``s``: a caller that reads the state on copies
    it first."""
    for j in range(OUT_SIZE):
        out[j] = np.nan
    if pending and s[S_NB] == 0.0:
        s[S_B0] = p_t_impact
    nb = s[S_NB] + (1.0 if pending else 0.0)
    if s[S_ND] < 2.0:
        return UNDEFINED
    out[O_E_END] = s[R_LAST + T_E]
    out[O_T_LAST] = s[R_LAST + T_T]
    ne = s[S_NE]
    if ne == 0.0 and not in_contact:
        return NO_IMPACT
    ostart = open_start(s, nb) if in_contact else np.nan
    is_open = False
    if s[S_DONE] == 0.0:
        if in_contact and ne > 0.0 and _flight(s, ostart, g, tau):
            s[S_DONE] = 1.0
            s[S_NEXT] = ostart
        elif in_contact:
            is_open = True
    t_imp = s[S_S0] if ne > 0.0 else ostart
    if s[S_HAS_PRE] != 0.0 and s[R_PRE + T_T] <= t_imp:
        _carry(s, R_PRE, g, t_imp, st)
        w_i = st[0]
        z_i = st[1]
        ev_i = st[2]
    else:       # the run starts in contact: the initial sample is the impact
        w_i = s[R_FIRST + T_W]
        z_i = s[R_FIRST + T_Z]
        w = s[R_FIRST + T_W]
        ev_i = (s[R_FIRST + T_KE] - 0.5 * w * w + s[R_FIRST + T_ES]
                + s[R_FIRST + T_EB])
    t_rel = np.nan if is_open else s[S_EB]
    w_r = np.nan
    z_r = np.nan
    if not is_open:
        if s[S_HAS_POST] != 0.0 and s[R_POST + T_T] < s[S_NEXT]:
            _carry(s, R_POST, g, t_rel, st)
        else:   # released at the very end of the run: the nearest sample
            st[0] = s[R_NEAR + T_W]
            st[1] = s[R_NEAR + T_Z]
        w_r = st[0]
        z_r = st[1]
    if is_open:
        _join_gap(s)
    # the pending bounce (open, or closed after the last drain)
    end = t_final if is_open else t_rel
    if pending and p_t_impact >= t_imp and (p_t_release <= end or (p_open and is_open)):
        _bounce_u(s, p_min_u0)
    rebound = 0.0
    if s[S_M_ANY] != 0.0:
        rebound = max(0.0, s[S_M_WMAX])
    if not is_open and w_r > rebound:
        rebound = w_r
    umin = s[S_M_UMIN]
    unan = s[S_M_UNAN] != 0.0 or s[S_B_UNAN] != 0.0
    if s[S_B_UMIN] < umin:
        umin = s[S_B_UMIN]
    if unan:
        umin = np.nan
    elif s[S_M_ANY] == 0.0 and s[S_B_N] == 0.0:
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
