"""The first-impact observables of ``impact.first_contact``, computed as a run drains, in a
fixed-size state: what a GPU thread can keep, where the whole diagnostics track of
thousands of runs at once cannot be.

``first_contact`` reads the track for a handful of things only, each tied to a time that
the episode rows fix: the sample last at or before the first contact's start (the impact
state), the first sample at or after each release (the flight test of ``flight_groups``
and the release state), the sample nearest the release when none follows it, the extremes
of w and u_0 from the impact to the group's end, the first sample inside the floor after
the last finished episode (the start of an episode still open at the end), and the last
sample.  Each is kept here as it goes by, in the state ``s`` (``SIZE`` doubles, ``S_*``
below): a few scalars and five track rows.  Nothing needs look-back, because the loop
writes an episode's row in the step that ends it, together with that step's samples, so:

* a block's episode rows are merged with its samples by time (``block``): every sample at
  or after an episode's end is taken after that episode, every earlier one before it;
* the first contact's start is known at the drain of the block it begins in, from the
  loop's ``ev`` (an episode still open) or from its episode row, before that block's
  samples are taken; all samples of earlier blocks lie before it;
* the macroscopic contact grows one episode at a time: the samples after the latest
  release are kept apart (``S_G*``) until the next episode says whether that gap was a
  flight (the group ends there, they are dropped) or not (they join the group, ``S_M*``).

Every value is computed by the same operations, in the same order, as ``first_contact``
(compiled without fused multiply-adds, ``exact_kernel``), so it equals it to the bit
(tests/test_impact_stream.py feeds real runs in blocks of every size).  One assumption
about ties: the sample nearest a release at the very end of a run (no sample after it)
is taken to be the latest one, which holds whenever that sample lies in the second half of
[0, t_release] (then the distances are exact differences).
"""
import math

import numpy as np

from . import impact as I
from . import layout as L
from .._jit import exact_kernel

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
# track rows (impact.T_* columns)
R_PRE = 30                          # the last sample at or before the contact's start
R_FIRST = R_PRE + I.TRACK_SIZE      # the first sample
R_LAST = R_FIRST + I.TRACK_SIZE     # the last sample
R_NEAR = R_LAST + I.TRACK_SIZE      # the first sample of the latest time
R_POST = R_NEAR + I.TRACK_SIZE      # the first sample at or after S_EB
ST = R_POST + I.TRACK_SIZE          # 3 doubles of scratch for ``finish`` (its ``st``)
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
    s[r + I.T_T] = t
    s[r + I.T_W] = w
    s[r + I.T_Z] = z
    s[r + I.T_KE] = ke
    s[r + I.T_ES] = es
    s[r + I.T_EB] = eb
    s[r + I.T_U0] = u0
    s[r + I.T_FF] = ff
    s[r + I.T_E] = e


@exact_kernel
def contact_start(s, t):
    """The first contact begins at ``t`` (its episode row, or the loop's ``ev`` while it is
    open); the samples at or after ``t`` taken so far (at most the last one, at ``t``
    exactly) join it."""
    if s[S_S0] == s[S_S0]:
        return
    s[S_S0] = t
    if s[S_HAS_PRE] != 0.0 and s[R_PRE + I.T_T] >= t:
        _inside(s, S_M_ANY, s[R_PRE + I.T_W], s[R_PRE + I.T_U0])


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
    """Take one diagnostics sample (the track columns of ``impact``)."""
    nd = s[S_ND]
    if nd == 0.0:
        _keep(s, R_FIRST, t, w, z, ke, es, eb, u0, ff, e)
        _keep(s, R_NEAR, t, w, z, ke, es, eb, u0, ff, e)
    elif t > s[R_NEAR + I.T_T]:
        _keep(s, R_NEAR, t, w, z, ke, es, eb, u0, ff, e)
    _keep(s, R_LAST, t, w, z, ke, es, eb, u0, ff, e)
    # the start of an episode open at the end (impact._open_start)
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
    """``first_contact``'s flight test of the gap from S_EB to ``t_next``."""
    t_rel = s[S_EB]
    if t_next - t_rel >= tau:
        w_r = -1.0
        if s[S_HAS_POST] != 0.0 and s[R_POST + I.T_T] < t_next:
            d = t_rel - s[R_POST + I.T_T]
            w_r = s[R_POST + I.T_W] + g * d
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
            contact_start(s, episodes[0, L.EC_T_START])
        elif in_contact:
            contact_start(s, ep_start)
    k = 0
    for j in range(nd):
        row = diag[j]
        t = row[L.D_T]
        while k < ne and episodes[k, L.EC_T_END] <= t:
            episode(s, episodes[k, L.EC_T_START], episodes[k, L.EC_T_END], g, tau)
            k += 1
        sample(s, t, row[L.D_CM_VELOCITY], row[L.D_CM_HEIGHT], row[L.D_ENERGY_KINETIC],
               row[L.D_ENERGY_STRETCH], row[L.D_ENERGY_BEND], row[L.D_U_BOTTOM],
               row[L.D_FLOOR_FORCE], row[L.D_ENERGY_TOTAL])
    while k < ne:
        episode(s, episodes[k, L.EC_T_START], episodes[k, L.EC_T_END], g, tau)
        k += 1
    for j in range(nb):
        bounce(s, bounces[j, L.BC_T_IMPACT], bounces[j, L.BC_T_RELEASE], bounces[j, L.BC_MIN_U0])


@exact_kernel
def _carry(s, r, g, t, out3):
    """``impact._carried`` from the kept row at ``r``."""
    d = t - s[r + I.T_T]
    w_s = s[r + I.T_W]
    z_s = s[r + I.T_Z]
    out3[0] = w_s + g * d
    out3[1] = z_s + w_s * d + 0.5 * g * d * d
    w = s[r + I.T_W]
    out3[2] = s[r + I.T_KE] - 0.5 * w * w + s[r + I.T_ES] + s[r + I.T_EB]


@exact_kernel
def finish(s, pending, p_t_impact, p_t_release, p_open, p_min_u0, g, tau, t_final,
           in_contact, out, st):
    """``first_contact``'s values into ``out`` (``impact.O_*``) and its code, at the end of
    the run: ``pending`` says whether a bounce is still pending (``events.write_bounce``'s
    row: its t_impact, t_release, open flag and min u_0); ``st`` is 3 floats of scratch."""
    for j in range(I.OUT_SIZE):
        out[j] = np.nan
    if pending and s[S_NB] == 0.0:
        s[S_B0] = p_t_impact
    nb = s[S_NB] + (1.0 if pending else 0.0)
    if s[S_ND] < 2.0:
        return I.UNDEFINED
    out[I.O_E_END] = s[R_LAST + I.T_E]
    out[I.O_T_LAST] = s[R_LAST + I.T_T]
    ne = s[S_NE]
    if ne == 0.0 and not in_contact:
        return I.NO_IMPACT
    ostart = np.nan
    if in_contact:
        if ne == 0.0 and nb > 0.0:
            ostart = s[S_B0]
        elif s[S_O_FOUND] != 0.0:
            ostart = s[S_O_T]
            if s[S_O_PREV] != 0.0 and s[S_O_PT] > s[S_AFTER]:
                t0 = s[S_O_PT]
                u0 = s[S_O_PU]
                ostart = t0 + (ostart - t0) * u0 / (u0 - s[S_O_U])
        else:
            after = s[S_AFTER]
            ostart = after if math.isfinite(after) else 0.0
    is_open = False
    if s[S_DONE] == 0.0:
        if in_contact and ne > 0.0 and _flight(s, ostart, g, tau):
            s[S_DONE] = 1.0
            s[S_NEXT] = ostart
        elif in_contact:
            is_open = True
    t_imp = s[S_S0] if ne > 0.0 else ostart
    if s[S_HAS_PRE] != 0.0 and s[R_PRE + I.T_T] <= t_imp:
        _carry(s, R_PRE, g, t_imp, st)
        w_i = st[0]
        z_i = st[1]
        ev_i = st[2]
    else:       # the run starts in contact: the initial sample is the impact
        w_i = s[R_FIRST + I.T_W]
        z_i = s[R_FIRST + I.T_Z]
        w = s[R_FIRST + I.T_W]
        ev_i = (s[R_FIRST + I.T_KE] - 0.5 * w * w + s[R_FIRST + I.T_ES]
                + s[R_FIRST + I.T_EB])
    t_rel = np.nan if is_open else s[S_EB]
    w_r = np.nan
    z_r = np.nan
    if not is_open:
        if s[S_HAS_POST] != 0.0 and s[R_POST + I.T_T] < s[S_NEXT]:
            _carry(s, R_POST, g, t_rel, st)
        else:   # released at the very end of the run: the nearest sample
            st[0] = s[R_NEAR + I.T_W]
            st[1] = s[R_NEAR + I.T_Z]
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
    out[I.O_T_IMPACT] = t_imp
    out[I.O_W_IMPACT] = w_i
    out[I.O_REBOUND] = rebound
    out[I.O_MIN_U0] = umin
    out[I.O_EV_IMPACT] = ev_i
    if is_open:
        return I.OPEN_AT_END
    out[I.O_RESTITUTION] = -w_r / w_i if w_i < 0 else np.nan
    out[I.O_APEX] = I.apex(g, w_i, z_i, w_r, z_r)
    out[I.O_CONTACT_TIME] = t_rel - t_imp
    return I.LIFT_OFF
