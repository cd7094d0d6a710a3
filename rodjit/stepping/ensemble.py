"""The ensemble engine's compiled batch call: many points of one sweep in one call.

A *batch* is points whose six parameter tuples (scheme, control, system, rod law, floor
law, observer: ``driver.setup.parameters``) have the same classes and field types; only
their values differ.  Each point's tuples travel as one row of ``params`` (``packing.pack``), and
``packing.rebuild`` makes them again in compiled code, so the values stay run-time values
and one compile serves the whole grid (as the GPU engine does).

Per point, ``run_batch`` sets its arrays as ``Run.__init__`` leaves them (zeros; u, v and
the clock row from the caller; the flight time in ``ev``) and runs it with the one
per-point driver, ``trajectory.run_one`` (a GPU thread runs the same), whose results go to
the point's row of ``fout`` and ``iout`` and its bounce rows to the batch's ``bout``, after
the rows of the points before it.  When ``bout`` is full, the point stops where it is
(``trajectory``'s module docstring) and the call returns: the caller takes the rows out and
calls again from that point, which goes on with the arrays as it left them.  Nothing here
allocates.
"""
from . import layout as L
from . import trajectory as T
from .packing import family, pack, rebuild  # noqa: F401  (a batch's key and row)
from .._jit import kernel


@kernel
def run_batch(scheme0, ctrl0, system0, rod0, floor0, obs0, params, init, clock0, flight,
              first, arrays, imp, bout, fout, iout, max_steps):
    """Run the points (rows) of ``params`` from ``first`` on; ``init[i]`` holds a point's u
    and v rows, ``clock0[i]`` its clock, ``flight[i]`` its flight time τ.  ``arrays`` and
    ``imp`` are one point's (reused: a ``Run``'s ``arrays.RunArrays``, and its first-impact
    state of ``impact_stream.SIZE`` doubles), ``bout`` the batch's bounce rows
    (``trajectory.BOUT_SIZE`` columns), ``fout`` and ``iout`` the points' results
    (``trajectory.F_*``, ``I_*``; ``iout`` zero before a point's first call), a point's
    rows in ``bout`` from ``iout[i, I_BSTART]``.  Returns the point that stopped with
    ``bout`` full (``first`` of the next call, which goes on with it), or the number of
    points when all have ended."""
    protos = (scheme0, ctrl0, system0, rod0, floor0, obs0)
    nbo = 0
    for i in range(first, params.shape[0]):
        scheme, ctrl, system, rod, floor, obs = rebuild(protos, params[i])
        if iout[i, T.I_STOPPED] == 0:
            _set_up(init[i], clock0[i], flight[i], arrays)
        T.run_one(scheme, ctrl, system, rod, floor, obs, arrays, imp, bout[nbo:], fout[i],
                  iout[i], max_steps)
        iout[i, T.I_BSTART] = nbo
        nbo += iout[i, T.I_BOUNCES]
        if iout[i, T.I_STOPPED] != 0:
            return i
    return params.shape[0]


@kernel
def _set_up(init, clock0, tau, arrays):
    """A point's arrays as ``Run.__init__`` leaves them (the output buffers as they are:
    the loop writes a row before it reads it)."""
    state = arrays.state
    trial = arrays.trial
    work = arrays.work
    interp = arrays.interp
    sstats = arrays.sstats
    clock = arrays.clock
    count = arrays.count
    ev = arrays.ev
    fail = arrays.fail
    observed = arrays.observed
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
    for j in range(observed.size):
        observed[j] = 0.0
