"""One sweep point's whole run in compiled code, and the one layout of its results: the
CPU engine's batch kernel calls ``run_one`` for each of its points (``stepping.ensemble``),
a GPU thread calls it for its point (``gpu.kernel``, which compiles this same function for
CUDA, ``gpu.retarget``), and one host-side decoder reads what it leaves
(``sweeps.decode``).

``run_one`` does what ``driver.run.Run`` and a sweep point's sink (``sweeps.point``) do
between the loop's calls, with the loop's own kernels (``loop.start``, ``loop.advance``),
so every step is the same:

* from the arrays ``Run.__init__`` leaves (the caller sets them: zeros, u, v, the clock
  row, the flight time in ``ev``), ``start``, then ``advance`` until DONE with the
  caller's ``max_steps`` (the driver's ``NODE_STEPS_PER_CALL // (N + 1)``), refusing a call
  that took steps without moving t (``layout.NO_PROGRESS``, as ``Run.compute``);
* after each call the buffers are drained as ``Run.drain`` hands them to a sink: a block
  holding a non-finite diagnostic value is refused (``BAD_DIAGNOSTICS``; its episodes and
  bounces are not taken), snapshots are dropped (they are taken so that the steps land on
  the same output times as a run's), the diagnostics rows fold into the running extremes
  of ``records.extremes.Extremes`` (in ``fout``), the block goes to the first-impact state
  ``imp`` (``impact_stream.block``), its bounce rows to ``bout``;
* at the end, the bounce still pending (``events.write_bounce``, as ``Run.pending_bounce``
  and ``records.bounces.bounce_table`` make it: ambiguous, no restitution energy), the
  extremes with those of the bounce rows (``Extremes.with_bounces``), the energy error
  (``Extremes.energy_error``) and the first-impact observables (``impact_stream.finish``).

Bounce rows: a point writes its rows into ``bout`` (``BOUT_SIZE`` columns, the loop's
bounce row then ``open``), as many as it has rows.  When the next row does not fit, the
point *stops* where it is, ``iout[I_STOPPED]`` set, every array left as it was: its caller
takes the rows out and calls ``run_one`` again with the same arrays, and the point goes on
from the row it stopped at, so every bounce is kept whatever their number and the steps are
those of an uninterrupted run.  The CPU engine does so (its batch kernel returns at such a
point; the host empties ``bout`` and calls again from it).  A GPU thread's arrays live in
its local memory and are gone when the kernel ends, so the GPU engine runs its stopped
points again on the CPU engine, which then keeps them all.  (Why stop, not drop or count:
a sweep row's ``n_bounces`` and its means must be the point's own, as the per-point path
gives them; why not a bigger buffer: a point's bounce count is not known before it runs.)

Plain Python over arrays, as every rodjit kernel: nothing allocates, and ``math``'s
functions, which CUDA lowers, stand where the CPU code would call NumPy's.
"""
import math

from . import impact_stream as S
from . import layout as L
from .events import write_bounce
from .loop import advance, start
from .observers import state_size
from .._jit import kernel

# per point, ``fout`` columns
F_BAL_MAX = 0      # largest and smallest E + dissipated over the diagnostics rows
F_BAL_MIN = 1
F_KIN_MAX = 2      # largest kinetic energy
F_MIN_STRAIN = 3   # smallest strain, bottom height, largest floor force: of the
F_MIN_U0 = 4       # diagnostics and bounce rows (NaN at the end where none was finite)
F_MAX_FF = 5
F_ENERGY_ERROR = 6
F_T_FINAL = 7      # clock[T] at the end
F_T_END = 8        # clock[T_END] (a failure message names it)
F_FAIL = 9                         # the loop's ``fail`` row (FAIL_SIZE values)
F_IMPACT = F_FAIL + L.FAIL_SIZE    # impact_stream.finish's ``out`` (OUT_SIZE values)
F_SIZE = F_IMPACT + S.OUT_SIZE
F_OBSERVED = F_SIZE     # from here: the run's ``observed`` array (``fout_width``)

# per point, ``iout`` columns
I_CODE = 0         # the loop's last code (layout.DONE, FAILED, ...) or BAD_DIAGNOSTICS
I_STOPPED = 1      # 1: stopped with ``bout`` full, to be called again (module docstring)
I_STEPS = 2
I_REJECTED = 3
I_SAMPLES = 4      # diagnostics rows folded into the extremes
I_BOUNCES = 5      # rows written to ``bout`` by the last call (the pending bounce's too)
I_TAKEN = 6        # rows of the block in the loop's buffers already written to ``bout``
I_IMPACT = 7       # impact_stream.finish's code
I_BSTART = 8       # the point's first row in its caller's ``bout`` (the caller's own)
I_SIZE = 9

BAD_DIAGNOSTICS = 101   # a block of diagnostics held a non-finite value (``Run.drain``)

# a row of ``bout``: the loop's bounce row (``layout.BOUNCE_ROW_COLUMNS``), then ``open``
B_OPEN = len(L.BOUNCE_ROW_COLUMNS)
BOUT_SIZE = B_OPEN + 1


def fout_width(obs) -> int:
    """Columns of ``fout`` for points with the observer parameters ``obs``: ``F_SIZE``,
    then the run's ``observed`` array (the observer's state, then its values)."""
    return F_SIZE + max(1, state_size(obs))


@kernel
def _fold(diag, n, fo, io):
    """Fold ``n`` diagnostics rows into the running extremes (``Extremes.update``); False
    (nothing folded) if a value is not finite: the driver refuses such a block."""
    total = 0.0
    for r in range(n):
        for c in range(diag.shape[1]):
            total += diag[r, c]
    if not math.isfinite(total):         # a non-finite value, or finite ones overflowing
        for r in range(n):
            for c in range(diag.shape[1]):
                if not math.isfinite(diag[r, c]):
                    return False
    bal_max = fo[F_BAL_MAX]
    bal_min = fo[F_BAL_MIN]
    kin_max = fo[F_KIN_MAX]
    strain_min = fo[F_MIN_STRAIN]
    u0_min = fo[F_MIN_U0]
    force_max = fo[F_MAX_FF]
    for r in range(n):
        row = diag[r]
        bal = row[L.D_ENERGY_TOTAL] + row[L.D_DISSIPATED]
        bal_max = max(bal_max, bal)
        bal_min = min(bal_min, bal)
        kin_max = max(kin_max, row[L.D_ENERGY_KINETIC])
        strain_min = min(strain_min, row[L.D_MIN_STRAIN])
        u0_min = min(u0_min, row[L.D_U_BOTTOM])
        force_max = max(force_max, row[L.D_FLOOR_FORCE])
    fo[F_BAL_MAX] = bal_max
    fo[F_BAL_MIN] = bal_min
    fo[F_KIN_MAX] = kin_max
    fo[F_MIN_STRAIN] = strain_min
    fo[F_MIN_U0] = u0_min
    fo[F_MAX_FF] = force_max
    io[I_SAMPLES] += n
    return True


@kernel
def _fold_bounce(row, fo):
    """Fold a bounce row's finite extremes in (``Extremes.with_bounces``)."""
    x = row[L.BC_MIN_STRAIN]
    if math.isfinite(x):
        fo[F_MIN_STRAIN] = min(fo[F_MIN_STRAIN], x)
    x = row[L.BC_MIN_U0]
    if math.isfinite(x):
        fo[F_MIN_U0] = min(fo[F_MIN_U0], x)
    x = row[L.BC_MAX_FLOOR_FORCE]
    if math.isfinite(x):
        fo[F_MAX_FF] = max(fo[F_MAX_FF], x)


@kernel
def _finite(x):
    return x if math.isfinite(x) else math.nan


@kernel
def run_one(scheme, ctrl, system, rod, floor, obs, arrays, imp, bout, fo, io, max_steps):
    """Run one point from its ``arrays`` (``arrays.RunArrays``) as ``Run.__init__`` leaves
    them (``io`` zero) to t_end or its failure, or on from where it stopped
    (``io[I_STOPPED]``); its results in ``fo`` (the observer's ``obs`` array from
    ``F_OBSERVED``), ``io`` and the first ``io[I_BOUNCES]`` rows of ``bout`` (module
    docstring).  ``imp`` holds the first-impact state
    (``impact_stream.SIZE`` doubles)."""
    state = arrays.state
    clock = arrays.clock
    count = arrays.count
    ev = arrays.ev
    diag = arrays.diag
    episodes = arrays.episodes
    bounces = arrays.bounces
    fail = arrays.fail
    nb = 0
    again = io[I_STOPPED] != 0
    if not again:
        S.reset(imp)
        fo[F_BAL_MAX] = -math.inf
        fo[F_BAL_MIN] = math.inf
        fo[F_KIN_MAX] = 0.0
        fo[F_MIN_STRAIN] = math.inf
        fo[F_MIN_U0] = math.inf
        fo[F_MAX_FF] = -math.inf
        code = start(scheme, ctrl, system, rod, floor, obs, arrays)
        # the outputs at t0 stay in the buffers: the first drain takes them with the first
        # call's (``sweeps.point``: ``run.start(None)``)
        io[I_CODE] = L.FAILED if code == L.FAILED else L.PAUSED
    io[I_STOPPED] = 0
    while True:
        if not again:
            code = io[I_CODE]
            if code != L.PAUSED and code != L.FULL:
                break
            t = clock[L.T]
            steps = count[L.STEP]
            code = advance(scheme, ctrl, system, rod, floor, obs, arrays, max_steps)
            if ((code == L.PAUSED or code == L.FULL) and count[L.STEP] > steps
                    and clock[L.T] <= t):
                # every step of the call left t where it was (``Run.compute``)
                fail[L.F_CODE] = L.NO_PROGRESS
                fail[L.F_T] = t
                fail[L.F_DT] = clock[L.DT]
                fail[L.F_VALUE] = count[L.STEP] - steps
                code = L.FAILED
            if _fold(diag, count[L.N_DIAG], fo, io):
                S.block(imp, diag, count[L.N_DIAG], episodes, count[L.N_EP], bounces,
                        count[L.N_BOUNCE], ev[L.IN_CONTACT] != 0.0, ev[L.EP_START],
                        system.g, ev[L.FLIGHT_TIME])
            else:
                code = BAD_DIAGNOSTICS
                count[L.N_BOUNCE] = 0        # refused with the block
            io[I_CODE] = code
            io[I_TAKEN] = 0
        again = False
        k = io[I_TAKEN]
        while k < count[L.N_BOUNCE]:
            if nb == bout.shape[0]:
                io[I_TAKEN] = k
                io[I_STOPPED] = 1
                io[I_BOUNCES] = nb
                return
            for c in range(bounces.shape[1]):
                bout[nb, c] = bounces[k, c]
            bout[nb, B_OPEN] = 0.0
            _fold_bounce(bout[nb], fo)
            nb += 1
            k += 1
        count[L.N_SNAP] = 0
        count[L.N_DIAG] = 0
        count[L.N_EP] = 0
        count[L.N_BOUNCE] = 0
    pending = ev[L.B_NEP] > 0.0
    is_open = ev[L.IN_CONTACT] != 0.0
    p_impact = 0.0          # the pending bounce's row, if there is one
    p_release = 0.0
    p_min_u0 = 0.0
    if pending:             # Run.pending_bounce, bounce_table
        if nb == bout.shape[0]:
            io[I_TAKEN] = 0
            io[I_STOPPED] = 1
            io[I_BOUNCES] = nb
            return
        row = bout[nb]
        write_bounce(row, ev, is_open)
        row[L.BC_AMBIGUOUS] = 1.0
        row[L.BC_RESTITUTION_ENERGY] = math.nan
        row[B_OPEN] = 1.0 if is_open else 0.0
        _fold_bounce(row, fo)
        p_impact = row[L.BC_T_IMPACT]
        p_release = row[L.BC_T_RELEASE]
        p_min_u0 = row[L.BC_MIN_U0]
        nb += 1
    io[I_BOUNCES] = nb
    io[I_STEPS] = count[L.STEP]
    io[I_REJECTED] = count[L.REJECTED]
    e0 = clock[L.E0]
    if io[I_SAMPLES] == 0:
        fo[F_ENERGY_ERROR] = math.nan
    else:                   # Extremes.energy_error
        dev = max(0.0, fo[F_BAL_MAX] - e0, e0 - fo[F_BAL_MIN])
        fo[F_ENERGY_ERROR] = dev / max(abs(e0), fo[F_KIN_MAX], 1e-300)
    fo[F_MIN_STRAIN] = _finite(fo[F_MIN_STRAIN])
    fo[F_MIN_U0] = _finite(fo[F_MIN_U0])
    fo[F_MAX_FF] = _finite(fo[F_MAX_FF])
    fo[F_T_FINAL] = clock[L.T]
    fo[F_T_END] = clock[L.T_END]
    for j in range(L.FAIL_SIZE):
        fo[F_FAIL + j] = fail[j]
    observed = arrays.observed
    for j in range(observed.size):
        fo[F_OBSERVED + j] = observed[j]
    io[I_IMPACT] = S.finish(imp, pending, p_impact, p_release, pending and is_open,
                            p_min_u0, system.g, ev[L.FLIGHT_TIME], clock[L.T],
                            state[0, 0] < 0.0, fo[F_IMPACT:F_IMPACT + S.OUT_SIZE],
                            imp[S.ST:S.ST + 3])
