"""The output rows of the compiled loop (``loop.advance``): the next output time, the
snapshot and diagnostics rows of a state, and, for a scheme with a dense output, the rows
of every output time inside a step (``loop``'s module docstring says when each is used).
"""
import numpy as np

from ..kernels.forces import energies
from ..model.laws import value
from . import control as C
from . import layout as L
from .schemes import dense, dense_dissipated, has_dense_type
from .._jit import overload, step_kernel

__all__ = ["next_target", "grid_time", "dense_target", "emit", "emit_dense"]


@step_kernel
def _grid_at(clock, times, dtidx, k):
    """Output time k of a grid: t0 + k·Δ for an interval Δ > 0; for Δ < 0 the listed time
    ``times[k]`` (``output.times``; inf past the list, −inf before it); inf for a grid
    that is off (Δ = 0)."""
    dt = clock[dtidx]
    if dt > 0.0:
        return clock[L.T0] + k * dt
    if dt < 0.0:
        if k < 0:
            return -np.inf
        if k < times.size:
            return times[k]
    return np.inf


@step_kernel
def next_target(clock, count, times):
    target = clock[L.T_END]
    target = min(target, _grid_at(clock, times, L.SNAP_DT, count[L.K_SNAP]))
    target = min(target, _grid_at(clock, times, L.DIAG_DT, count[L.K_DIAG]))
    return target


@step_kernel
def _skip_past(clock, count, times, kidx, dtidx, t):
    """Advance the output index to the first grid time after t (+ tolerance)."""
    while _grid_at(clock, times, dtidx, count[kidx]) <= t + clock[L.TOL]:
        count[kidx] += 1


@step_kernel
def grid_time(clock, count, times, kidx, dtidx, ahead):
    """The output time ``ahead`` places after the next one of a grid (inf: grid off)."""
    return _grid_at(clock, times, dtidx, count[kidx] + ahead)


@step_kernel
def _covered(clock, count, times, kidx, dtidx, t, limit):
    """How many output times of a grid a step ending at t covers (at most ``limit``)."""
    # a range, not a counter from a literal 0: ``grid_time`` compiles once (rodjit._jit)
    for n in range(limit):
        if grid_time(clock, count, times, kidx, dtidx, n) > t + clock[L.TOL]:
            return n
    return max(limit, 0)


@step_kernel
def _snapshot_row(u, v, t, step_no, count, snap_t, snap_step, snap_u, snap_v):
    j = count[L.N_SNAP]
    snap_t[j] = t
    snap_step[j] = step_no
    for i in range(u.size):   # element loops: a slice copy would allocate
        snap_u[j, i] = u[i]
        snap_v[j, i] = v[i]
    count[L.N_SNAP] += 1


@step_kernel
def _diag_row(u, v, work, system, rod, floor, count, t, dt_prop, dissipated, diag):
    j = count[L.N_DIAG]
    ke, st, be, fe, ge, emin, z, w = energies(u, v, work[1], system, rod, floor)
    row = diag[j]
    row[L.D_T] = t
    row[L.D_DT] = dt_prop
    row[L.D_ENERGY_KINETIC] = ke
    row[L.D_ENERGY_STRETCH] = st
    row[L.D_ENERGY_BEND] = be
    row[L.D_ENERGY_FLOOR] = fe
    row[L.D_ENERGY_GRAVITY] = ge
    row[L.D_ENERGY_TOTAL] = ke + st + be + fe + ge
    row[L.D_DISSIPATED] = dissipated
    row[L.D_U_BOTTOM] = u[0]
    row[L.D_FLOOR_FORCE] = value(u[0], floor)
    row[L.D_MIN_STRAIN] = emin
    row[L.D_CM_HEIGHT] = z
    row[L.D_CM_VELOCITY] = w
    count[L.N_DIAG] += 1


@step_kernel
def emit(cur, work, system, rod, floor, clock, count, times, t, dt_prop, step_no,
         snap_t, snap_step, snap_u, snap_v, diag, at_grid):
    """Write the snapshot and/or diagnostics row due at time t, from the state ``cur``;
    the rows' time is t, or with ``at_grid`` each grid's own output time (within the
    output tolerance of t)."""
    tol = clock[L.TOL]
    ts = _grid_at(clock, times, L.SNAP_DT, count[L.K_SNAP])
    if ts <= t + tol:
        _snapshot_row(cur[0], cur[1], ts if at_grid else t, step_no, count, snap_t,
                      snap_step, snap_u, snap_v)
        _skip_past(clock, count, times, L.K_SNAP, L.SNAP_DT, t)
    td = _grid_at(clock, times, L.DIAG_DT, count[L.K_DIAG])
    if td <= t + tol:
        _diag_row(cur[0], cur[1], work, system, rod, floor, count, td if at_grid else t,
                  dt_prop, clock[L.DISSIPATED], diag)
        _skip_past(clock, count, times, L.K_DIAG, L.DIAG_DT, t)


@step_kernel
def emit_final(cur, work, system, rod, floor, clock, count, times, t, dt_prop, step_no,
               snap_t, snap_step, snap_u, snap_v, diag):
    """The snapshot and diagnostics rows of a run that ends before t_end
    (``events.stop_due``), at its end time t, unless its grid has a row at t already
    (the last step landed on one); the caller leaves room for one row of each."""
    # the grid's last output time (inf with the grid off): a row at t already if within tol
    tol = clock[L.TOL]
    if grid_time(clock, count, times, L.K_SNAP, L.SNAP_DT, int(-1)) < t - tol:
        _snapshot_row(cur[0], cur[1], t, step_no, count, snap_t, snap_step, snap_u, snap_v)
    if grid_time(clock, count, times, L.K_DIAG, L.DIAG_DT, int(-1)) < t - tol:
        _diag_row(cur[0], cur[1], work, system, rod, floor, count, t, dt_prop,
                  clock[L.DISSIPATED], diag)


@step_kernel
def dense_target(ctrl, fixed, clock, count, times, t, dtp):
    """A dense-output step from t: ``(target, dt, land, snapshots, diagnostics)``, the step
    toward t_end, shortened to end on the last output time it may cover
    (``ctrl.dense_snapshots``, ``ctrl.dense_diagnostics``) if it would cover more, and at
    most how many output times of each grid it covers."""
    t_end = clock[L.T_END]
    m_s = ctrl.dense_snapshots
    m_d = ctrl.dense_diagnostics
    dt, land = C.step_to(ctrl, fixed, t_end - t, dtp)
    t_new = t_end if land else t + dt
    n_s = _covered(clock, count, times, L.K_SNAP, L.SNAP_DT, t_new, m_s + 1)
    n_d = _covered(clock, count, times, L.K_DIAG, L.DIAG_DT, t_new, m_d + 1)
    target = t_end
    if n_s > m_s:
        target = min(target, grid_time(clock, count, times, L.K_SNAP, L.SNAP_DT, m_s - 1))
    if n_d > m_d:
        target = min(target, grid_time(clock, count, times, L.K_DIAG, L.DIAG_DT, m_d - 1))
    if target < t_end:
        dt, land = C.step_to(ctrl, fixed, target - t, dtp)
        n_s = min(n_s, m_s)
        n_d = min(n_d, m_d)
    return target, dt, land, n_s, n_d


@step_kernel
def _emit_dense_rows(scheme, old, new, work, interp, system, rod, floor, tfloor, clock, count,
                     times, t, dt, t_new, diss_old, dt_prop, step_no, snap_t, snap_step,
                     snap_u, snap_v, diag):
    """The rows of every output time in (t, t_new − tol) of the step of length dt from the
    state ``old`` to ``new``, by the scheme's dense output into ``interp`` (module
    docstring); ``dense_setup`` has run for the step, which took the floor law
    ``tfloor``."""
    tol = clock[L.TOL]
    while True:
        ts = grid_time(clock, count, times, L.K_SNAP, L.SNAP_DT, int(0))
        td = grid_time(clock, count, times, L.K_DIAG, L.DIAG_DT, int(0))
        tau = min(ts, td)
        if not tau < t_new - tol:
            break
        theta = (tau - t) / dt
        dense(scheme, old[0], old[1], old[2], new[0], new[1], new[2], work, dt, theta,
              interp[0], interp[1])
        if ts == tau:
            _snapshot_row(interp[0], interp[1], tau, step_no, count, snap_t, snap_step,
                          snap_u, snap_v)
            count[L.K_SNAP] += 1
        if td == tau:
            diss = diss_old + dense_dissipated(scheme, system, tfloor, old[0], old[1], new[0],
                                               new[1], work, dt, theta)
            _diag_row(interp[0], interp[1], work, system, rod, floor, count, tau, dt_prop,
                      diss, diag)
            count[L.K_DIAG] += 1


def emit_dense(scheme, old, new, work, interp, system, rod, floor, tfloor, clock, count,
               times, t, dt, t_new, diss_old, dt_prop, step_no, snap_t, snap_step, snap_u,
               snap_v, diag):
    """``_emit_dense_rows`` for a scheme with a dense output; compiled for one without, a
    no-op, so its loop does not compile the interpolation it never runs."""
    _emit_dense_rows(scheme, old, new, work, interp, system, rod, floor, tfloor, clock, count,
                     times, t, dt, t_new, diss_old, dt_prop, step_no, snap_t, snap_step,
                     snap_u, snap_v, diag)


@overload(emit_dense)
def _emit_dense_ov(scheme, old, new, work, interp, system, rod, floor, tfloor, clock, count,
                   times, t, dt, t_new, diss_old, dt_prop, step_no, snap_t, snap_step,
                   snap_u, snap_v, diag):
    if not has_dense_type(scheme):
        return (lambda scheme, old, new, work, interp, system, rod, floor, tfloor, clock,
                count, times, t, dt, t_new, diss_old, dt_prop, step_no, snap_t, snap_step,
                snap_u, snap_v, diag: None)
    return emit_dense
