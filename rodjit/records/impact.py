"""The first-impact columns of a run (``IMPACT_COLUMNS``: a sweep row, a run file's summary,
``Result.impact``), all from the one implementation of the first-impact observables,
``stepping.impact_stream``.

``ImpactStream`` runs it for one run: block by block as the run drains (a run writer, a
sweep point's sink: ``Sink.block``), or over a run's whole tables read back in blocks
(``run_impact``: a run file, a ``Result``).  ``impact_columns`` turns the values of many
runs into columns (a batch of the ensemble or the GPU engine, which stream them in
compiled code), ``impact_values`` those of one run into a dict, ``impact_line`` that into
one line of a report.
"""
from __future__ import annotations

import math

import numpy as np

from .._jit import numba_loaded, python_module
from ..stepping import impact_stream as S
from ..stepping import layout as L
from .physics import flight_time, lift_energy

__all__ = ["TRACK_COLUMNS", "IMPACT_COLUMNS", "NO_SAMPLES", "ImpactStream", "run_impact",
           "impact_columns", "impact_values", "impact_line"]

# the diagnostics columns the first-impact observables read: a few floats per sample,
# whatever N is
TRACK_COLUMNS = tuple(L.DIAG_COLUMNS[c] for c in S.TRACK_FROM_DIAG)
NO_SAMPLES = ("the macroscopic-contact observables need diagnostics samples "
              "(output.diagnostics_interval > 0)")

# the sweep summary columns of the first bounce: name -> (dtype, description)
IMPACT_COLUMNS: dict[str, tuple[str, str]] = {
    "restitution_first": ("float", "-w_release/w_impact of the first bounce (the first "
                                   "physical impact); 0 for no lift-off, NaN if open or no "
                                   "impact"),
    "impact_status": ("str", "first bounce: lift-off | no lift-off | open | no impact | "
                             "undefined"),
    "impact_reason": ("str", "why restitution_first is 0 or missing ('' for lift-off)"),
    "restitution_apex": ("float", "sqrt of rebound over drop apex height of the centre of "
                                  "mass above 1/2 for the first bounce (0 where it rises no "
                                  "higher than 1/2; not the restitution: restitution_first)"),
    "contact_time_first": ("float", "t_release - t_impact of the first bounce (inf: no "
                                    "lift-off)"),
    "w_impact": ("float", "centre-of-mass velocity at the first impact"),
    "rebound_speed": ("float", "largest centre-of-mass velocity from the first impact to "
                               "its release (to the end of the run without lift-off)"),
    "min_u0_impact": ("float", "deepest penetration min u_0 in the first bounce"),
    "vibration_ratio": ("float", "energy_vibration / (w_impact^2/2) at the first impact"),
}

_PYTHON = python_module(S)        # the stream's kernels run by the interpreter
_WIDTH = max(S.TRACK_FROM_DIAG) + 1     # the diagnostics columns up to the last one read


class ImpactStream:
    """The first-impact state of one run (``stepping.impact_stream``, ``SIZE`` doubles,
    whatever the run's length) and what it needs of the configuration (g, τ).

    The kernels run compiled where the process has loaded Numba (a run on the JIT, a sweep
    worker), else as Python (``_jit.python_module``, the same bits): reading a run file
    or a run on the loop compiled ahead of time never imports Numba, whose import and the
    kernels' load from the disk cache take 0.53 s, where the Python form reads the 5001
    samples of a ``paper-mu100`` run file in 7 ms (1.4 µs a sample; compiled: 0.25 ms).
    So a stream switches to the compiled kernels once it has taken ``PYTHON_ROWS``
    samples, about what that import costs."""

    PYTHON_ROWS = 1 << 18
    BLOCK_ROWS = 1 << 16     # rows read at a time from a run's tables (``read``)

    def __init__(self, config):
        self.config = config
        self.g = float(config.gravity.g)
        self.tau = flight_time(config)
        self.state = np.empty(S.SIZE)
        self.rows = 0                    # samples taken
        _PYTHON.reset(self.state)

    def _compiled(self, rows: int) -> bool:
        return numba_loaded() or self.rows + rows > self.PYTHON_ROWS

    def block(self, diagnostics, episodes, bounces, in_contact, contact_start) -> None:
        """Take one drained block (``Sink.block``): its diagnostics, episode and closed
        bounce rows, and whether the bottom is on the floor at its end, since
        ``contact_start``."""
        n, ne, nb = len(diagnostics), len(episodes), len(bounces)
        args = (bool(in_contact), float(contact_start), self.g, self.tau)
        if self._compiled(n):
            S.block(self.state, diagnostics, n, episodes, ne, bounces, nb, *args)
        else:
            s = self.state.tolist()
            _PYTHON.block(s, diagnostics[:, :_WIDTH].tolist(), n, episodes.tolist(), ne,
                          bounces.tolist(), nb, *args)
            self.state[:] = s
        self.rows += n

    def read(self, diagnostics, n: int, episodes, bounces, nb: int, start: float) -> None:
        """Take a run's first ``n`` diagnostics rows (columns by name: a Result's dict, a
        run file's group, read ``BLOCK_ROWS`` at a time), its ``episodes`` and the first
        ``nb`` rows of its bounce table, closed bounces (columns by name), its first
        contact beginning at ``start`` (NaN: not begun by then)."""
        if start == start:
            _PYTHON.contact_start(self.state, float(start))
        t_end = np.asarray(episodes["t_end"], float)
        eps = np.stack([np.asarray(episodes["t_start"], float), t_end], axis=1)
        brows = _bounce_rows(bounces, nb)
        k = 0
        for a in range(0, max(n, 1), self.BLOCK_ROWS):
            b = min(n, a + self.BLOCK_ROWS)
            rows = np.zeros((b - a, _WIDTH))
            for name, c in zip(TRACK_COLUMNS, S.TRACK_FROM_DIAG):
                rows[:, c] = diagnostics[name][a:b]
            last = b == n
            # an episode comes with the block of the first sample at or after its end
            k_next = len(eps) if last else int(np.searchsorted(t_end, rows[-1, L.D_T],
                                                                side="right"))
            self.block(rows, eps[k:k_next], brows if last else brows[:0], False, 0.0)
            k = k_next

    def open_start(self) -> float:
        """The start of a contact open at the end that no bounce row records, from the
        samples taken (``impact_stream.open_start``)."""
        return float(_PYTHON.open_start(self.state.tolist(), 0.0))

    def values(self, t_final: float, u_final, pending=None) -> dict:
        """The IMPACT_COLUMNS of the run ended at ``t_final`` in the state ``u_final``;
        ``pending``: its bounce still pending then, ``(row, open)`` as
        ``Run.pending_bounce`` gives it, or None.  The state stays as it was."""
        u = np.asarray(u_final)
        in_contact = bool(u.size and u[0] < 0)
        p: tuple = (False, 0.0, 0.0, False, 0.0)
        if pending is not None:
            row, is_open = pending
            p = (True, float(row[L.BC_T_IMPACT]), float(row[L.BC_T_RELEASE]), bool(is_open),
                 float(row[L.BC_MIN_U0]))
        args = (*p, self.g, self.tau, float(t_final), in_contact)
        if self._compiled(0):
            s = self.state.copy()
            out = np.zeros(S.OUT_SIZE)
            code = S.finish(s, *args, out, s[S.ST:S.ST + 3])
        else:
            values = [0.0] * S.OUT_SIZE
            code = _PYTHON.finish(self.state.tolist(), *args, values, [0.0] * 3)
            out = np.asarray(values)
        return impact_values(self.config, t_final, out, code)


def run_impact(config, t_final: float, u_final, diagnostics, n: int, episodes,
               bounces) -> dict:
    """The IMPACT_COLUMNS of a whole run from its tables (``ImpactStream.read``): the run
    ended at ``t_final`` in the state ``u_final``, with ``n`` diagnostics rows; an open last
    row of its bounce table is the pending bounce."""
    nb = len(bounces["t_impact"])
    is_open = bool(nb and bounces["open"][nb - 1])
    closed = nb - 1 if is_open else nb
    u = np.asarray(u_final)
    in_contact = bool(u.size and u[0] < 0)
    start = math.nan             # the first contact's start, given to the stream first
    if len(episodes["t_start"]):
        start = float(episodes["t_start"][0])
    elif in_contact and nb:
        start = float(bounces["t_impact"][0])
    elif in_contact:             # a file still being written, before its pending bounce
        first = ImpactStream(config)
        first.read(diagnostics, n, episodes, bounces, 0, math.nan)
        start = first.open_start()
    stream = ImpactStream(config)
    stream.read(diagnostics, n, episodes, bounces, closed, start)
    return stream.values(t_final, u_final,
                         (_bounce_rows(bounces, nb)[-1], True) if is_open else None)


def _bounce_rows(bounces, n: int) -> np.ndarray:
    """The first ``n`` rows of a bounce table (columns by name) as the loop's bounce rows,
    with the columns the stream reads."""
    rows = np.zeros((n, len(L.BOUNCE_ROW_COLUMNS)))
    for c in (L.BC_T_IMPACT, L.BC_T_RELEASE, L.BC_MIN_U0):
        rows[:, c] = np.asarray(bounces[L.BOUNCE_ROW_COLUMNS[c]], float)[:n]
    return rows


def impact_columns(values, pos, out, code, lift_energy_of) -> None:
    """The IMPACT_COLUMNS of the runs at rows ``pos`` of ``values`` (their ``t_final``
    already there) from the values ``out`` (``impact_stream.O_*`` columns) and codes of
    ``impact_stream.finish``; ``lift_energy_of(j)`` is the lift-off energy of the j-th,
    asked only for a first contact still running at the end."""
    lift = code == S.LIFT_OFF
    opened = code == S.OPEN_AT_END
    w = out[:, S.O_W_IMPACT]
    some = lift | opened
    for name, col in (("w_impact", S.O_W_IMPACT), ("rebound_speed", S.O_REBOUND),
                      ("min_u0_impact", S.O_MIN_U0)):
        values[name][pos] = np.where(some, out[:, col], math.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = out[:, S.O_EV_IMPACT] / (0.5 * w * w)
    values["vibration_ratio"][pos] = np.where(some & (w != 0), ratio, math.nan)
    for name, col in (("restitution_first", S.O_RESTITUTION),
                      ("restitution_apex", S.O_APEX),
                      ("contact_time_first", S.O_CONTACT_TIME)):
        values[name][pos] = np.where(lift, out[:, col], math.nan)
    status = values["impact_status"]
    reason = values["impact_reason"]
    status[pos[lift]] = "lift-off"
    reason[pos[lift]] = ""
    for j in np.flatnonzero(~lift):
        k = pos[j]
        t_final = float(values["t_final"][k])
        if code[j] == S.UNDEFINED:
            status[k], reason[k] = "undefined", NO_SAMPLES
        elif code[j] == S.NO_IMPACT:
            status[k] = "no impact"
            reason[k] = f"the bottom never touched the floor before t = {t_final:g}"
        else:
            e_end, lift_e = float(out[j, S.O_E_END]), lift_energy_of(j)
            if e_end < lift_e:
                wi, reb = float(w[j]), float(out[j, S.O_REBOUND])
                r = reb / abs(wi) if wi else math.nan
                status[k] = "no lift-off"
                reason[k] = (f"the rod never leaves the floor: its energy {e_end:.6g} at "
                             f"t = {float(out[j, S.O_T_LAST]):g} is below the {lift_e:.6g} "
                             f"a lift-off needs; the centre of mass rebounds at "
                             f"{reb:.3g} ({r:.3g} of the impact speed)")
                values["restitution_first"][k] = 0.0
                values["restitution_apex"][k] = 0.0
                values["contact_time_first"][k] = math.inf
            else:
                status[k] = "open"
                reason[k] = (f"the first contact is still running at t = {t_final:g} "
                             f"with energy {e_end:.6g} above the {lift_e:.6g} a lift-off "
                             f"needs: run longer (time.t_end)")


def impact_values(config, t_final: float, out, code: int) -> dict:
    """The IMPACT_COLUMNS of one run of ``config`` ended at ``t_final``, from the values
    ``out`` and the code of ``impact_stream.finish`` (``impact_columns``)."""
    values: dict = {name: np.full(1, math.nan) for name, (kind, _) in IMPACT_COLUMNS.items()
                    if kind == "float"}
    values.update(impact_status=np.array([""], object), impact_reason=np.array([""], object),
                  t_final=np.array([float(t_final)]))
    impact_columns(values, np.zeros(1, np.int64), np.asarray(out, float).reshape(1, -1),
                   np.array([code]), lambda j: lift_energy(config))
    return {name: str(values[name][0]) if kind == "str" else _number(values[name][0])
            for name, (kind, _) in IMPACT_COLUMNS.items()}


def _number(x) -> float:
    """A float, every NaN the one ``math.nan``: dicts of the same values compare equal."""
    x = float(x)
    return x if x == x else math.nan


def impact_line(values: dict) -> str:
    """One line for a report: 'first impact: e = 0.126 (lift-off), contact 0.0121 s, ...'
    or 'first impact: no lift-off (rebound speed 0.17 of impact)'."""
    st = values["impact_status"]
    if st == "lift-off":
        apex = values["restitution_apex"]
        # the apex ratio is no restitution of its own where the centre of mass does not
        # rise above its height at rest after the impact: it is 0 there by definition
        said = (f"{apex:.4g}" if apex > 0 else
                "0 (the centre of mass rises no higher than half the rod's length)")
        return (f"e = {values['restitution_first']:.4g} (lift-off), contact "
                f"{values['contact_time_first']:.4g} s, penetration "
                f"{-values['min_u0_impact']:.4g}; centre-of-mass apex restitution {said}")
    if st == "no lift-off":
        ratio = values["rebound_speed"] / abs(values["w_impact"])
        return (f"e = 0 (no lift-off: rebound speed of the centre of mass {ratio:.3g} of "
                f"impact), penetration {-values['min_u0_impact']:.4g}")
    return f"{st}: {values['impact_reason']}"
