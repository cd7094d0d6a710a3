"""One sweep point's whole run, as one GPU thread runs it: the CPU's compiled loop, drained
in place into the point's summary.

``run_one`` is plain Python over arrays, like every rodjit kernel, and is compiled for the
GPU by ``retarget.Retarget`` together with what it calls (``stepping.loop.start`` and
``advance``, the scheme's step, the laws).  It does what ``driver.run.Run`` and a sweep
point's sink (``sweeps.point``) do between the loop's calls: call ``advance`` with the same
``max_steps`` (``driver.run.NODE_STEPS_PER_CALL``), refuse a call that took steps without
moving t (``NO_PROGRESS``) and a block with a non-finite diagnostic value, and drain the
output buffers: snapshots are dropped (they are taken so that the steps land on the same
output times as a run's), diagnostics rows are folded into the running extremes of
``records.extremes.Extremes``, bounce rows are copied out, and the bounce still open at the
end is written by ``stepping.events.write_bounce``, as ``Run.pending_bounce`` does.  The
first-impact observables are streamed from the same blocks (``stepping.impact_stream``,
a few dozen doubles a thread, as the CPU engine does).
"""
import math

from ..driver.run import NO_PROGRESS
from ..kernels.forces import OK
from ..stepping import layout as L
from ..stepping import impact_stream as S
from ..stepping.events import write_bounce
from ..stepping.loop import advance, start
from .._jit import kernel

# columns of the float results of a point (``fout``)
F_T = 0            # time reached
F_E0 = 1           # initial energy
F_BAL_MAX = 2      # largest and smallest E + dissipated over the diagnostics rows
F_BAL_MIN = 3
F_KIN_MAX = 4      # largest kinetic energy
F_STRAIN_MIN = 5   # smallest strain, bottom height; largest floor force (diagnostics rows)
F_U0_MIN = 6
F_FORCE_MAX = 7
F_FAIL = 8         # the loop's ``fail`` array (layout.FAIL_SIZE values) from here
F_IMPACT = F_FAIL + L.FAIL_SIZE    # impact_stream.finish's ``out`` (OUT_SIZE values)
F_SIZE = F_IMPACT + S.OUT_SIZE

# columns of the integer results (``iout``)
I_CODE = 0         # layout.DONE, layout.FAILED, or BAD_DIAGNOSTICS
I_STEPS = 1
I_REJECTED = 2
I_SAMPLES = 3      # diagnostics rows folded into the extremes
I_BOUNCES = 4      # closed bounce rows written to the point's bounce rows
I_DROPPED = 5      # closed bounce rows that did not fit there
I_PENDING = 6      # 0: no bounce pending at the end; 1: pending, closed episode; 2: open
I_IMPACT = 7       # impact_stream.finish's code (LIFT_OFF, ...)
I_SIZE = 8

BAD_DIAGNOSTICS = 101   # a block of diagnostics held a non-finite value (``Run.drain``)


@kernel
def _fold(diag, n, fout, iout):
    """Fold ``n`` diagnostics rows into the extremes (``Extremes.update``); False (nothing
    folded) if any value is not finite (the driver refuses such a block)."""
    ncol = diag.shape[1]
    for j in range(n):
        for c in range(ncol):
            if not math.isfinite(diag[j, c]):
                return False
    for j in range(n):
        row = diag[j]
        bal = row[L.D_ENERGY_TOTAL] + row[L.D_DISSIPATED]
        fout[F_BAL_MAX] = max(fout[F_BAL_MAX], bal)
        fout[F_BAL_MIN] = min(fout[F_BAL_MIN], bal)
        fout[F_KIN_MAX] = max(fout[F_KIN_MAX], row[L.D_ENERGY_KINETIC])
        fout[F_STRAIN_MIN] = min(fout[F_STRAIN_MIN], row[L.D_MIN_STRAIN])
        fout[F_U0_MIN] = min(fout[F_U0_MIN], row[L.D_U_BOTTOM])
        fout[F_FORCE_MAX] = max(fout[F_FORCE_MAX], row[L.D_FLOOR_FORCE])
    iout[I_SAMPLES] += n
    return True


@kernel
def _drain(count, diag, episodes, bounces, bounce_out, ev, imp, g, fout, iout):
    """Empty the output buffers as ``Run.take`` and ``Run.drain`` do, streaming the block
    into the first-impact state ``imp``; False if the diagnostics were refused (then, as
    there, the episodes and bounces are not drained)."""
    ok = _fold(diag, count[L.N_DIAG], fout, iout)
    if ok:
        S.block(imp, diag, count[L.N_DIAG], episodes, count[L.N_EP], bounces,
                count[L.N_BOUNCE], ev[L.IN_CONTACT] != 0.0, ev[L.EP_START], g,
                ev[L.FLIGHT_TIME])
        cap = bounce_out.shape[0] - 1       # the last row is kept for the pending bounce
        for j in range(count[L.N_BOUNCE]):
            k = iout[I_BOUNCES]
            if k < cap:
                for c in range(bounces.shape[1]):
                    bounce_out[k, c] = bounces[j, c]
                iout[I_BOUNCES] = k + 1
            else:
                iout[I_DROPPED] += 1
    count[L.N_SNAP] = 0
    count[L.N_DIAG] = 0
    count[L.N_EP] = 0
    count[L.N_BOUNCE] = 0
    return ok


def run_one(scheme, ctrl, system, rod, floor, state, trial, work, interp, sstats, clock,
            count, ev, snap_t, snap_step, snap_u, snap_v, diag, episodes, bounces, fail,
            imp, bounce_out, fout, iout, max_steps):
    """Run one point from its started arrays (``Run.__init__``'s) to t_end or its failure;
    results in ``fout``, ``iout`` and ``bounce_out`` (module docstring); ``imp`` holds the
    first-impact state (``impact_stream.SIZE`` doubles)."""
    S.reset(imp)
    fout[F_BAL_MAX] = -math.inf
    fout[F_BAL_MIN] = math.inf
    fout[F_KIN_MAX] = 0.0
    fout[F_STRAIN_MIN] = math.inf
    fout[F_U0_MIN] = math.inf
    fout[F_FORCE_MAX] = -math.inf
    for k in range(I_SIZE):
        iout[k] = 0
    code = start(scheme, ctrl, system, rod, floor, state, work, clock, count, ev, snap_t,
                 snap_step, snap_u, snap_v, diag, fail)
    # the outputs at t0 stay in the buffers: the first drain takes them with the first
    # call's (``sweeps.point``: ``run.start(None)``)
    code = L.PAUSED if code == OK else L.FAILED
    while code == L.PAUSED or code == L.FULL:
        t = clock[L.T]
        steps = count[L.STEP]
        code = advance(scheme, ctrl, system, rod, floor, state, trial, work, interp, sstats,
                       clock, count, ev, snap_t, snap_step, snap_u, snap_v, diag, episodes,
                       bounces, fail, max_steps)
        if (code == L.PAUSED or code == L.FULL) and count[L.STEP] > steps and clock[L.T] <= t:
            # every step of the call left t where it was (``Run.compute``)
            fail[L.F_CODE] = NO_PROGRESS
            fail[L.F_T] = t
            fail[L.F_DT] = clock[L.DT]
            fail[L.F_VALUE] = count[L.STEP] - steps
            code = L.FAILED
        if not _drain(count, diag, episodes, bounces, bounce_out, ev, imp, system.g, fout,
                      iout):
            code = BAD_DIAGNOSTICS
    iout[I_CODE] = code
    iout[I_STEPS] = count[L.STEP]
    iout[I_REJECTED] = count[L.REJECTED]
    fout[F_T] = clock[L.T]
    fout[F_E0] = clock[L.E0]
    for k in range(L.FAIL_SIZE):
        fout[F_FAIL + k] = fail[k]
    pending = ev[L.B_NEP] > 0.0
    is_open = ev[L.IN_CONTACT] != 0.0
    row = bounce_out[iout[I_BOUNCES]]
    if pending:
        write_bounce(row, ev, is_open)
        iout[I_PENDING] = 2 if is_open else 1
    iout[I_IMPACT] = S.finish(imp, pending, row[L.BC_T_IMPACT], row[L.BC_T_RELEASE],
                              pending and is_open, row[L.BC_MIN_U0], system.g,
                              ev[L.FLIGHT_TIME], clock[L.T], state[0, 0] < 0.0,
                              fout[F_IMPACT:F_IMPACT + S.OUT_SIZE], imp[S.ST:S.ST + 3])
