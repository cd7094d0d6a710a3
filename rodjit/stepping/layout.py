"""Index layout of the arrays that carry the loop's state between compiled calls.

Everything the stepper needs to continue lives in ``state`` (u, v, a), ``clock`` (float64),
``count`` (int64), ``ev`` (float64) and ``sstats`` (int64): saving these is a checkpoint,
restoring them resumes bit for bit.
"""
from typing import NamedTuple

# ---- clock: float64 ---------------------------------------------------------------------
T = 0            # current time
DT = 1           # proposed (unclipped) next step
T_END = 2
DISSIPATED = 3   # ∫ 2R dt so far
E0 = 4           # discrete energy at the start of the run
SNAP_DT = 5      # snapshot interval (0: none)
DIAG_DT = 6      # diagnostics interval (0: none)
T0 = 7           # origin of the output grids t0 + k·Δ
W = 8            # centre-of-mass velocity of the current state
TOL = 9          # two output times closer than this coincide
EMIN = 10        # smallest segment strain of the current state
CLOCK_SIZE = 11

# ---- count: int64 -----------------------------------------------------------------------
STEP = 0
REJECTED = 1
K_SNAP = 2       # index k of the next snapshot time t0 + k·Δs
K_DIAG = 3
N_SNAP = 4       # rows filled in the output buffers since the last drain
N_DIAG = 5
N_EP = 6
N_BOUNCE = 7
EPISODES_TOTAL = 8
BOUNCES_TOTAL = 9
STARTED = 10
COUNT_SIZE = 11

# ---- ev: float64, contact and bounce bookkeeping ------------------------------------------
IN_CONTACT = 0
EP_START = 1
B_NEP = 2          # episodes in the current bounce (0: no bounce open)
B_T_IMPACT = 3
B_W_IMPACT = 4
B_T_RELEASE = 5
B_W_RELEASE = 6
CUR_MIN_U0 = 7     # extremes since the current bounce's impact
CUR_MAX_FF = 8
CUR_MIN_EPS = 9
REL_MIN_U0 = 10    # the same, frozen at its latest release
REL_MAX_FF = 11
REL_MIN_EPS = 12
EV_SIZE = 13

# ---- fail: float64 -----------------------------------------------------------------------
F_CODE = 0
F_T = 1
F_VALUE = 2
F_INDEX = 3
F_DT = 4
FAIL_SIZE = 5

# ---- return codes of the compiled loop -------------------------------------------------
DONE = 0         # reached t_end
FULL = 1         # an output buffer is full: drain and call again
PAUSED = 2       # max_steps taken: Python housekeeping, then call again
FAILED = 3       # could not continue: see ``fail``

DIAG_COLUMNS = (
    "t", "dt",
    "energy_kinetic", "energy_stretch", "energy_bend", "energy_floor", "energy_gravity",
    "energy_total", "dissipated",
    "u_bottom", "floor_force", "min_strain", "cm_height", "cm_velocity",
)
EPISODE_COLUMNS = ("t_start", "t_end")
BOUNCE_COLUMNS = (
    "t_impact", "t_release", "n_episodes", "w_impact", "w_release", "restitution",
    "min_u0", "max_floor_force", "min_strain",
)


class Control(NamedTuple):
    """Step-size control: caps, fixed step (0: adaptive), growth and barrier-gap limits."""

    dt_max: float     # inf when unset
    dt_min: float
    dt_fixed: float   # > 0: fixed steps
    growth: float     # a proposal grows at most by this factor per step
    gap: float        # a step closes at most this fraction of the distance to a barrier
                      # (ε = −1, u_0 = −β); 0: off (schemes admissible by construction)
