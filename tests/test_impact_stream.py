"""The first-impact observables (``stepping.impact_stream``, the one implementation)
against the whole-table definitions (``records.contacts.first_impact``, the analysis API's
NumPy form, here the oracle): real runs of every first-contact outcome, fed in blocks as
the loop drains them (of one sample, a few, random sizes, all at once), compiled and as
Python (``_jit.python_module``), give the same values to the bit; and so do the readers
of a run's whole tables (``records.impact``: a Result, a run file).

A block here keeps the loop's order (``impact_stream`` module docstring): an episode's
row comes in the block of the first sample at or after its end, a bounce row with or after
its release's episode, and the block's end says whether a contact is open then, with its
start, as the loop's ``ev`` does.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import rodjit
from rodjit import _jit
from rodjit.presets import load_preset
from rodjit.records import impact as RI
from rodjit.records.observables import first_impact, physics_for, physics_of
from rodjit.stepping import impact_stream as S
from rodjit.stepping import layout as L

# (preset, changes, the first contact's outcome)
RUNS = {
    "paper-mu0": ("paper-mu0", {"time.t_end": 1.5}, S.LIFT_OFF),
    "paper-mu100": ("paper-mu100", {"time.t_end": 1.5, "floor.beta": 0.12}, S.LIFT_OFF),
    # the rod stays on the floor: still in contact at the end, below the lift-off energy
    "no-lift-off": ("paper-mu100", {"time.t_end": 3.0, "floor.beta": 0.03}, S.OPEN_AT_END),
    "no-impact": ("paper-mu100", {"time.t_end": 0.3}, S.NO_IMPACT),
    # the first contact still running when the run stops: in its fifth episode (the start
    # of the open one from the samples), and in its first
    "open": ("paper-mu0", {"time.t_end": 0.527}, S.OPEN_AT_END),
    "open-first": ("paper-mu0", {"time.t_end": 0.453}, S.OPEN_AT_END),
    # a lift-off, then the run stops inside a later contact
    "later-open": ("paper-mu100", {"time.t_end": 0.91, "floor.beta": 0.12}, S.LIFT_OFF),
    # off the floor at the end, after three bounces
    "in-flight": ("paper-mu100", {"time.t_end": 1.2, "floor.beta": 0.12}, S.LIFT_OFF),
}
OPEN = len(L.BOUNCE_ROW_COLUMNS)        # the ``open`` column of a bounce row here
PYTHON = _jit.python_module(S)

_CACHE: dict = {}


def _run(name):
    if name not in _CACHE:
        preset, changes, _ = RUNS[name]
        res = rodjit.simulate(load_preset(preset).override(changes))
        d = res.diagnostics
        diag = np.stack([np.asarray(d[c], float) for c in L.DIAG_COLUMNS], axis=1)
        eps = np.stack([np.asarray(res.episodes["t_start"], float),
                        np.asarray(res.episodes["t_end"], float)], axis=1).reshape(-1, 2)
        b = res.bounces
        brows = np.stack([np.asarray(b[c], float) for c in L.BOUNCE_ROW_COLUMNS]
                         + [np.asarray(b["open"], float)], axis=1).reshape(-1, OPEN + 1)
        _CACHE[name] = (res, physics_of(res), diag, eps, brows)
    return _CACHE[name]


def _oracle(res, phys):
    """``finish``'s code and values, from ``first_impact`` on the run's whole tables."""
    d = res.diagnostics
    out = np.full(S.OUT_SIZE, np.nan)
    if d["t"].size < 2:
        return S.UNDEFINED, out
    out[S.O_E_END], out[S.O_T_LAST] = d["energy_total"][-1], d["t"][-1]
    fi = first_impact(d, res.episodes, res.bounces, phys)
    if fi.status == "no impact":
        return S.NO_IMPACT, out
    out[S.O_T_IMPACT], out[S.O_W_IMPACT] = fi.t_impact, fi.w_impact
    out[S.O_REBOUND], out[S.O_MIN_U0] = fi.rebound_speed, fi.min_u0
    out[S.O_EV_IMPACT] = fi.energy_vibration_impact
    if fi.status != "lift-off":
        return S.OPEN_AT_END, out
    out[S.O_RESTITUTION], out[S.O_APEX] = fi.restitution, fi.restitution_apex
    out[S.O_CONTACT_TIME] = fi.contact_time
    return S.LIFT_OFF, out


def _same(got, out) -> bool:
    return bool(((got == out) | (np.isnan(got) & np.isnan(out))).all())


def _streamed(name, cuts, last_pending, kernels=S):
    """``finish`` after the run's rows fed in the blocks ``cuts`` (sample indices); the
    last bounce row is the pending one if ``last_pending`` (always when open)."""
    res, phys, diag, eps, brows = _run(name)
    nd, ne = len(diag), len(eps)
    t = diag[:, L.D_T]
    bounds = sorted(set([0, *cuts, nd]))
    blocks = list(zip(bounds[:-1], bounds[1:]))
    nblk = len(blocks)

    def block_of_time(x):
        """The block of the first sample at or after ``x`` (the last if none)."""
        j = int(np.searchsorted(t, x, side="left"))
        for k, (a, b) in enumerate(blocks):
            if j < b:
                return k
        return nblk - 1

    ep_block = [block_of_time(eps[k, 1]) for k in range(ne)]
    nb = len(brows)
    pending = nb > 0 and (bool(brows[-1, OPEN]) or last_pending)
    closed = nb - 1 if pending else nb
    b_block = []
    for j in range(closed):
        rel = brows[j, L.BC_T_RELEASE]
        k = max([ep_block[e] for e in range(ne) if eps[e, 1] == rel] or [0])
        b_block.append(max(k, block_of_time(rel + phys.flight_time)))
    # the episodes as the loop knows them at a block's end: open ones included
    starts = list(eps[:, 0])
    ends = list(eps[:, 1])
    if phys.in_contact:
        starts.append(brows[-1, L.BC_T_IMPACT] if ne == 0 else phys.contact_start)
        ends.append(math.inf)
    s = np.zeros(S.SIZE)
    kernels.reset(s)
    bcols = np.zeros((max(nb, 1), len(L.BOUNCE_ROW_COLUMNS)))
    for k, (a, b) in enumerate(blocks):
        e_rows = np.ascontiguousarray(eps[[e for e in range(ne) if ep_block[e] == k]])
        rows = [j for j in range(closed) if b_block[j] == k]
        bcols[:len(rows)] = brows[rows, :len(L.BOUNCE_ROW_COLUMNS)]
        t_end = t[b - 1]
        open_now = [x for x, y in zip(starts, ends) if x <= t_end < y]
        kernels.block(s, np.ascontiguousarray(diag[a:b]), b - a, e_rows.reshape(-1, 2),
                      len(e_rows), bcols, len(rows), bool(open_now),
                      open_now[0] if open_now else 0.0, phys.g, phys.flight_time)
    out, st = np.zeros(S.OUT_SIZE), np.zeros(3)
    p = brows[-1] if pending else np.zeros(OPEN + 1)
    code = kernels.finish(s, bool(pending), p[L.BC_T_IMPACT], p[L.BC_T_RELEASE],
                          bool(p[OPEN] != 0.0), p[L.BC_MIN_U0], phys.g, phys.flight_time,
                          phys.t_final, bool(phys.in_contact), out, st)
    return code, out


def _splits(nd, seed):
    rng = np.random.default_rng(seed)
    random = np.cumsum(rng.integers(1, 40, size=nd))
    return {"whole": [], "ones": list(range(1, nd)), "fives": list(range(5, nd, 5)),
            "random": [int(x) for x in random if x < nd]}


@pytest.mark.parametrize("name", list(RUNS))
def test_streamed_in_blocks_of_every_size_equals_the_whole_table_definitions(name):
    res, phys = _run(name)[:2]
    code, out = _oracle(res, phys)
    assert code == RUNS[name][2]
    nd = len(_run(name)[2])
    for split, cuts in _splits(nd, 1).items():
        for last_pending in (False, True):
            got_code, got = _streamed(name, cuts, last_pending)
            assert got_code == code, (split, last_pending)
            assert _same(got, out), (split, last_pending, got, out)
    # the interpreter running the same kernels (readers without Numba) gives the same bits
    for split in ("whole", "random"):
        got_code, got = _streamed(name, _splits(nd, 2)[split], False, PYTHON)
        assert got_code == code and _same(got, out), split


def test_a_run_without_samples_is_undefined():
    s = np.zeros(S.SIZE)
    S.reset(s)
    out = np.zeros(S.OUT_SIZE)
    code = S.finish(s, False, 0.0, 0.0, False, 0.0, -9.81, 1e-3, 1.0, False, out,
                    np.zeros(3))
    assert code == S.UNDEFINED and np.isnan(out).all()


@pytest.mark.parametrize("name", ["paper-mu100", "no-lift-off", "open", "open-first"])
def test_a_runs_whole_tables_give_the_streamed_columns_compiled_or_not(name, monkeypatch):
    """``records.impact.run_impact`` (a Result, a run file read back) reads the tables in
    blocks, the first contact's start given first; in small blocks, as Python, and
    switching to the compiled kernels partway, its columns are the same; and they are
    those of the oracle's values."""
    res, phys = _run(name)[:2]
    code, out = _oracle(res, phys)
    want = RI.impact_values(res.config, res.t_final, out, code)
    n = int(res.diagnostics["t"].size)

    def columns():
        return RI.run_impact(res.config, res.t_final, res.u_final, res.diagnostics, n,
                             res.episodes, res.bounces)

    def same(got):
        return all(got[k] == want[k] or (got[k] != got[k] and want[k] != want[k])
                   for k in want)

    assert same(columns()) and same(res.impact())
    monkeypatch.setattr(RI.ImpactStream, "BLOCK_ROWS", 97)
    assert same(columns())
    monkeypatch.setattr(RI, "numba_loaded", lambda: False)
    assert same(columns())                                # Python all through
    monkeypatch.setattr(RI.ImpactStream, "PYTHON_ROWS", 1000)
    assert same(columns())                                # compiled from the 11th block


def test_a_file_without_its_pending_bounce_row_finds_the_open_start_from_the_samples():
    """A run file read while it is written has no row for the bounce still open: with no
    finished episode either, the first contact's start comes from the samples (a first
    pass of the stream), as the whole-table definition takes it."""
    res = _run("open-first")[0]
    assert res.episodes["t_start"].size == 0 and res.bounces["open"][0]
    none = {name: col[:0] for name, col in res.bounces.items()}
    reference = physics_for(res.config, res.t_final, res.u_final, res.diagnostics,
                            res.episodes, none)
    assert reference.contact_start != res.bounces["t_impact"][0]
    fi = first_impact(res.diagnostics, res.episodes, none, reference)
    got = RI.run_impact(res.config, res.t_final, res.u_final, res.diagnostics,
                        int(res.diagnostics["t"].size), res.episodes, none)
    assert got["impact_status"] == fi.status == "open"
    assert (got["w_impact"], got["rebound_speed"], got["min_u0_impact"]) == (
        fi.w_impact, fi.rebound_speed, fi.min_u0)
