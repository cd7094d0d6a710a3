"""Index layout of the arrays that carry the loop's state between compiled calls, and the
columns of the rows it writes.

Everything the stepper needs to continue lives in ``state`` (u, v, a), ``clock`` (float64),
``count`` (int64), ``ev`` (float64) and ``sstats`` (int64): saving these is a checkpoint,
restoring them resumes bit for bit.

The compiled code writes output rows through the column indices ``D_*`` (diagnostics),
``EC_*`` (episodes) and ``BC_*`` (bounces), each looked up by its column's name, so a
column list and the code that fills it cannot disagree (``check_columns`` and the tests
verify that every column has exactly one index).
"""

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
B_EV_IMPACT = 13   # vibration energy (energy_vibration) at the current bounce's impact
FLIGHT = 14        # 1 once the centre of mass turned over (w from + to −) after the release
FLIGHT_TIME = 15   # τ: a bounce ends once its release is followed by τ off the floor and a
                   # turn-over of the centre of mass (MODEL.md §3; set by the driver)
EV_SIZE = 16

# ---- fail: float64 -----------------------------------------------------------------------
F_CODE = 0
F_T = 1
F_VALUE = 2
F_INDEX = 3
F_DT = 4
FAIL_SIZE = 5
# the driver's own failure code (beside the kernels' ``kernels.forces`` codes): steps
# were taken, t did not move (``driver.run.Run.compute``, ``trajectory.run_one``)
NO_PROGRESS = 100

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
BOUNCE_ROW_COLUMNS = (
    "t_impact", "t_release", "n_episodes", "w_impact", "w_release", "restitution",
    "min_u0", "max_floor_force", "min_strain", "energy_vibration_impact",
    "restitution_energy", "ambiguous",
)


# ---- column indices of the output rows (compile-time constants of the kernels) -----------
D_T = DIAG_COLUMNS.index("t")
D_DT = DIAG_COLUMNS.index("dt")
D_ENERGY_KINETIC = DIAG_COLUMNS.index("energy_kinetic")
D_ENERGY_STRETCH = DIAG_COLUMNS.index("energy_stretch")
D_ENERGY_BEND = DIAG_COLUMNS.index("energy_bend")
D_ENERGY_FLOOR = DIAG_COLUMNS.index("energy_floor")
D_ENERGY_GRAVITY = DIAG_COLUMNS.index("energy_gravity")
D_ENERGY_TOTAL = DIAG_COLUMNS.index("energy_total")
D_DISSIPATED = DIAG_COLUMNS.index("dissipated")
D_U_BOTTOM = DIAG_COLUMNS.index("u_bottom")
D_FLOOR_FORCE = DIAG_COLUMNS.index("floor_force")
D_MIN_STRAIN = DIAG_COLUMNS.index("min_strain")
D_CM_HEIGHT = DIAG_COLUMNS.index("cm_height")
D_CM_VELOCITY = DIAG_COLUMNS.index("cm_velocity")

EC_T_START = EPISODE_COLUMNS.index("t_start")
EC_T_END = EPISODE_COLUMNS.index("t_end")

BC_T_IMPACT = BOUNCE_ROW_COLUMNS.index("t_impact")
BC_T_RELEASE = BOUNCE_ROW_COLUMNS.index("t_release")
BC_N_EPISODES = BOUNCE_ROW_COLUMNS.index("n_episodes")
BC_W_IMPACT = BOUNCE_ROW_COLUMNS.index("w_impact")
BC_W_RELEASE = BOUNCE_ROW_COLUMNS.index("w_release")
BC_RESTITUTION = BOUNCE_ROW_COLUMNS.index("restitution")
BC_MIN_U0 = BOUNCE_ROW_COLUMNS.index("min_u0")
BC_MAX_FLOOR_FORCE = BOUNCE_ROW_COLUMNS.index("max_floor_force")
BC_MIN_STRAIN = BOUNCE_ROW_COLUMNS.index("min_strain")
BC_ENERGY_VIBRATION_IMPACT = BOUNCE_ROW_COLUMNS.index("energy_vibration_impact")
BC_RESTITUTION_ENERGY = BOUNCE_ROW_COLUMNS.index("restitution_energy")
BC_AMBIGUOUS = BOUNCE_ROW_COLUMNS.index("ambiguous")

_PREFIXES = {"D_": DIAG_COLUMNS, "EC_": EPISODE_COLUMNS, "BC_": BOUNCE_ROW_COLUMNS}


def column_indices(prefix: str) -> dict[str, int]:
    """The column indices with ``prefix`` (``D_``, ``EC_``, ``BC_``), by column name."""
    return {k[len(prefix):].lower(): v for k, v in globals().items()
            if k.startswith(prefix) and k[len(prefix):].isupper() and isinstance(v, int)}


def check_columns() -> None:
    """Raise if a column list and its indices disagree: every column needs exactly one
    index, named after it, at its position."""
    for prefix, columns in _PREFIXES.items():
        idx = column_indices(prefix)
        expected = {c: i for i, c in enumerate(columns)}
        if idx != expected:
            raise AssertionError(f"{prefix}* indices {idx} do not match the columns "
                                 f"{columns}")


check_columns()
