"""The ensemble engine's compiled batch call: many points of one sweep in one call.

A *batch* is points whose five parameter tuples (scheme, control, system, rod law, floor
law: ``driver.run.parameters``) have the same classes and field types; only their values
differ.  Each point's tuples travel as one row of ``params`` (``packing.pack``), and
``packing.rebuild`` makes them again in compiled code, so the values stay run-time values
and one compile serves the whole grid (as the GPU engine does).

Per point, ``run_batch`` does what ``sweeps.point`` does with a ``Run``, with the loop's own
kernels (``loop.start``, ``loop.advance``), so every step is the same:

* its arrays start as ``Run.__init__`` leaves them (zeros; u, v and the clock row from the
  caller; the flight time in ``ev``), then ``start`` and ``advance`` until DONE, with the
  same ``max_steps`` and buffer sizes as a ``Run`` (so even the driver's check for a call
  that took steps without moving t sees the same calls);
* after each call the buffers are consumed here, as ``Run.drain`` hands them to a sink: a
  block holding a non-finite diagnostic value is refused (the point fails), snapshots are
  dropped (they were only taken so that steps land on the same output times), the
  diagnostics rows fold into the extremes (``records.extremes.Extremes``), the block
  goes to the first-impact state ``imp`` (``impact_stream.block``), bounce rows to the
  batch's ``bout``;
* at the end, the pending bounce (``events.write_bounce``), the extremes and the
  first-impact observables (``impact_stream.finish``).

A point whose bounce rows do not fit the batch's ``bout`` is marked ``R_OVERFLOW``: the
caller runs it again on the per-point path.  Nothing here allocates.
"""
import numpy as np

from . import impact_stream as S
from . import layout as L
from .events import write_bounce
from .loop import advance, start
from .packing import family, pack, rebuild  # noqa: F401  (a batch's key and row)
from .._jit import kernel

NO_PROGRESS = 100     # driver.run.NO_PROGRESS: steps were taken, t did not move

# per point, ``fout`` columns
F_MIN_U0 = 0
F_MAX_FF = 1
F_MIN_STRAIN = 2
F_ENERGY_ERROR = 3
F_T_FINAL = 4
F_E0 = 5
F_FAIL = 6                       # the loop's ``fail`` row (FAIL_SIZE values)
F_IMPACT = F_FAIL + L.FAIL_SIZE  # impact_stream.finish's ``out`` (OUT_SIZE values)
F_T_END = F_IMPACT + S.OUT_SIZE  # clock[T_END] (the failure message names it)
F_SIZE = F_T_END + 1

# per point, ``iout`` columns
I_RESULT = 0          # R_* below
I_STEPS = 1
I_REJECTED = 2
I_BOUNCES = 3         # rows in ``bout``, the pending bounce included
I_IMPACT = 4          # impact_stream.finish's code
I_BSTART = 5          # its first row in ``bout``
I_SIZE = 6

R_COMPLETED = 0
R_FAILED = 1          # ``fail`` says why
R_NONFINITE = 2       # a diagnostics block held a non-finite value
R_OVERFLOW = 3        # did not fit: run it on the per-point path

# a row of ``bout``: the loop's bounce row (``layout.BOUNCE_ROW_COLUMNS``), then ``open``
B_OPEN = len(L.BOUNCE_ROW_COLUMNS)
BOUT_SIZE = B_OPEN + 1


@kernel
def run_batch(scheme0, ctrl0, system0, rod0, floor0, params, init, clock0, flight,
              state, trial, work, interp, sstats, clock, count, ev, snap_t, snap_step,
              snap_u, snap_v, diag, episodes, bounces, fail, imp, bout, fout, iout,
              max_steps):
    """Run every point (row) of ``params``; ``init[i]`` holds its u and v rows,
    ``clock0[i]`` its clock, ``flight[i]`` its flight time τ.  The other arrays are one
    point's (reused: ``Run``'s arrays and buffers, ``imp`` its first-impact state of
    ``impact_stream.SIZE`` doubles), ``bout`` the batch's bounce rows (``BOUT_SIZE``
    columns), ``fout`` and ``iout`` its summary values (``F_*``, ``I_*``).  Returns the
    bounce rows written."""
    protos = (scheme0, ctrl0, system0, rod0, floor0)
    nbo = 0
    for i in range(params.shape[0]):
        scheme, ctrl, system, rod, floor = rebuild(protos, params[i])
        nbo = _run_point(scheme, ctrl, system, rod, floor, init[i], clock0[i], flight[i],
                         state, trial, work, interp, sstats, clock, count, ev, snap_t,
                         snap_step, snap_u, snap_v, diag, episodes, bounces, fail, imp,
                         bout, nbo, fout[i], iout[i], max_steps)
    return nbo


@kernel
def _run_point(scheme, ctrl, system, rod, floor, init, clock0, tau, state, trial, work,
               interp, sstats, clock, count, ev, snap_t, snap_step, snap_u, snap_v, diag,
               episodes, bounces, fail, imp, bout, nbo, fo, io, max_steps):
    """One point of ``run_batch``; returns the bounce rows of the batch after it."""
    n1 = state.shape[1]
    for r in range(state.shape[0]):
        for j in range(n1):
            state[r, j] = init[r, j] if r < 2 else 0.0
            trial[r, j] = 0.0
    for r in range(work.shape[0]):
        for j in range(n1):
            work[r, j] = 0.0
    for r in range(interp.shape[0]):
        for j in range(n1):
            interp[r, j] = 0.0
    for j in range(sstats.size):
        sstats[j] = 0
    for j in range(clock.size):
        clock[j] = clock0[j]
    for j in range(count.size):
        count[j] = 0
    for j in range(ev.size):
        ev[j] = 0.0
    ev[L.FLIGHT_TIME] = tau
    for j in range(fail.size):
        fail[j] = 0.0
    S.reset(imp)
    # the extremes (records.extremes.Extremes)
    samples = 0
    bal_max = -np.inf
    bal_min = np.inf
    kin_max = 0.0
    strain_min = np.inf
    u0_min = np.inf
    force_max = -np.inf
    bstart = nbo
    outcome = R_COMPLETED
    code = start(scheme, ctrl, system, rod, floor, state, work, clock, count, ev, snap_t,
                 snap_step, snap_u, snap_v, diag, fail)
    if code == L.FAILED:
        outcome = R_FAILED
    while outcome == R_COMPLETED:
        t_before = clock[L.T]
        steps_before = count[L.STEP]
        code = advance(scheme, ctrl, system, rod, floor, state, trial, work, interp, sstats,
                       clock, count, ev, snap_t, snap_step, snap_u, snap_v, diag, episodes,
                       bounces, fail, max_steps)
        if ((code == L.PAUSED or code == L.FULL) and count[L.STEP] > steps_before
                and clock[L.T] <= t_before):
            fail[L.F_CODE] = NO_PROGRESS
            fail[L.F_T] = t_before
            fail[L.F_DT] = clock[L.DT]
            fail[L.F_VALUE] = count[L.STEP] - steps_before
            code = L.FAILED
        # the block, as Run.drain hands it to a sink
        m = count[L.N_DIAG]
        total = 0.0
        for r in range(m):
            for c in range(diag.shape[1]):
                total += diag[r, c]
        finite = np.isfinite(total)
        if not finite:
            for r in range(m):
                for c in range(diag.shape[1]):
                    if not np.isfinite(diag[r, c]):
                        outcome = R_NONFINITE
        if outcome == R_NONFINITE:
            break
        for r in range(m):
            row = diag[r]
            samples += 1
            bal = row[L.D_ENERGY_TOTAL] + row[L.D_DISSIPATED]
            bal_max = max(bal_max, bal)
            bal_min = min(bal_min, bal)
            kin_max = max(kin_max, row[L.D_ENERGY_KINETIC])
            strain_min = min(strain_min, row[L.D_MIN_STRAIN])
            u0_min = min(u0_min, row[L.D_U_BOTTOM])
            force_max = max(force_max, row[L.D_FLOOR_FORCE])
        S.block(imp, diag, m, episodes, count[L.N_EP], bounces, count[L.N_BOUNCE],
                ev[L.IN_CONTACT] != 0.0, ev[L.EP_START], system.g, tau)
        for r in range(count[L.N_BOUNCE]):
            if nbo < bout.shape[0]:
                for c in range(bounces.shape[1]):
                    bout[nbo, c] = bounces[r, c]
                bout[nbo, B_OPEN] = 0.0
            nbo += 1
        count[L.N_SNAP] = 0
        count[L.N_DIAG] = 0
        count[L.N_EP] = 0
        count[L.N_BOUNCE] = 0
        if code == L.FAILED:
            outcome = R_FAILED
        if code == L.DONE:
            break
    pending = ev[L.B_NEP] > 0
    is_open = ev[L.IN_CONTACT] != 0.0
    if pending:     # the pending bounce (Run.pending_bounce, bounce_table)
        if nbo < bout.shape[0]:
            write_bounce(bout[nbo], ev, is_open)
            bout[nbo, L.BC_AMBIGUOUS] = 1.0
            bout[nbo, L.BC_RESTITUTION_ENERGY] = np.nan
            bout[nbo, B_OPEN] = 1.0 if is_open else 0.0
        nbo += 1
    io[I_STEPS] = count[L.STEP]
    io[I_REJECTED] = count[L.REJECTED]
    io[I_BSTART] = bstart
    io[I_BOUNCES] = nbo - bstart
    if nbo > bout.shape[0]:
        io[I_RESULT] = R_OVERFLOW
        return bstart           # its rows are dropped: the point runs again alone
    io[I_RESULT] = outcome
    # Extremes.with_bounces: the finite extremes of the bounce rows too
    for r in range(bstart, nbo):
        x = bout[r, L.BC_MIN_STRAIN]
        if np.isfinite(x):
            strain_min = min(strain_min, x)
        x = bout[r, L.BC_MIN_U0]
        if np.isfinite(x):
            u0_min = min(u0_min, x)
        x = bout[r, L.BC_MAX_FLOOR_FORCE]
        if np.isfinite(x):
            force_max = max(force_max, x)
    e0 = clock[L.E0]
    fo[F_MIN_U0] = u0_min if np.isfinite(u0_min) else np.nan
    fo[F_MAX_FF] = force_max if np.isfinite(force_max) else np.nan
    fo[F_MIN_STRAIN] = strain_min if np.isfinite(strain_min) else np.nan
    if samples == 0:
        fo[F_ENERGY_ERROR] = np.nan
    else:
        dev = max(0.0, bal_max - e0, e0 - bal_min)
        fo[F_ENERGY_ERROR] = dev / max(abs(e0), kin_max, 1e-300)
    fo[F_T_FINAL] = clock[L.T]
    fo[F_E0] = e0
    fo[F_T_END] = clock[L.T_END]
    for j in range(L.FAIL_SIZE):
        fo[F_FAIL + j] = fail[j]
    p_impact = 0.0          # the pending bounce's row, if there is one
    p_release = 0.0
    p_min_u0 = 0.0
    if pending:
        p_impact = bout[nbo - 1, L.BC_T_IMPACT]
        p_release = bout[nbo - 1, L.BC_T_RELEASE]
        p_min_u0 = bout[nbo - 1, L.BC_MIN_U0]
    io[I_IMPACT] = S.finish(imp, pending, p_impact, p_release, pending and is_open, p_min_u0,
                            system.g, tau, clock[L.T], state[0, 0] < 0.0,
                            fo[F_IMPACT:F_IMPACT + S.OUT_SIZE], imp[S.ST:S.ST + 3])
    return nbo
