"""The streaming first-impact observables (``stepping.impact_stream``) against
``stepping.impact.first_contact`` on the whole track: real runs of every first-contact
outcome, fed in blocks as the loop drains them (of one sample, a few, random sizes, all
at once), give the same values to the bit.

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
from rodjit.presets import load_preset
from rodjit.records.observables import TRACK_COLUMNS, physics_of
from rodjit.stepping import impact as I
from rodjit.stepping import impact_stream as S
from rodjit.stepping import layout as L

# (preset, changes, the first contact's outcome)
RUNS = {
    "paper-mu0": ("paper-mu0", {"time.t_end": 1.5}, I.LIFT_OFF),
    "paper-mu100": ("paper-mu100", {"time.t_end": 1.5, "floor.beta": 0.12}, I.LIFT_OFF),
    # the rod stays on the floor: still in contact at the end, below the lift-off energy
    "no-lift-off": ("paper-mu100", {"time.t_end": 3.0, "floor.beta": 0.03}, I.OPEN_AT_END),
    "no-impact": ("paper-mu100", {"time.t_end": 0.3}, I.NO_IMPACT),
    # the first contact still running when the run stops: in its fifth episode (the start
    # of the open one from the samples), and in its first
    "open": ("paper-mu0", {"time.t_end": 0.527}, I.OPEN_AT_END),
    "open-first": ("paper-mu0", {"time.t_end": 0.453}, I.OPEN_AT_END),
    # a lift-off, then the run stops inside a later contact
    "later-open": ("paper-mu100", {"time.t_end": 0.91, "floor.beta": 0.12}, I.LIFT_OFF),
    # off the floor at the end, after three bounces
    "in-flight": ("paper-mu100", {"time.t_end": 1.2, "floor.beta": 0.12}, I.LIFT_OFF),
}

_CACHE: dict = {}


def _run(name):
    if name not in _CACHE:
        preset, changes, _ = RUNS[name]
        res = rodjit.simulate(load_preset(preset).override(changes))
        d = res.diagnostics
        diag = np.stack([np.asarray(d[c], float) for c in L.DIAG_COLUMNS], axis=1)
        track = np.stack([np.asarray(d[c], float) for c in TRACK_COLUMNS], axis=1)
        eps = np.stack([np.asarray(res.episodes["t_start"], float),
                        np.asarray(res.episodes["t_end"], float)], axis=1).reshape(-1, 2)
        b = res.bounces
        brows = np.stack([np.asarray(b[c], float) for c in L.BOUNCE_ROW_COLUMNS]
                         + [np.asarray(b["open"], float)], axis=1).reshape(-1, I.BROW_SIZE)
        _CACHE[name] = (res, physics_of(res), diag, track, eps, brows)
    return _CACHE[name]


def _reference(name):
    res, phys, diag, track, eps, brows = _run(name)
    out, st = np.zeros(I.OUT_SIZE), np.zeros(3)
    code = I.first_contact(track, len(track), eps, len(eps), brows, len(brows), phys.g,
                           phys.flight_time, phys.t_final, phys.in_contact, out, st)
    return code, out


def _streamed(name, cuts, last_pending):
    """``finish`` after the run's rows fed in the blocks ``cuts`` (sample indices); the
    last bounce row is the pending one if ``last_pending`` (always when open)."""
    res, phys, diag, track, eps, brows = _run(name)
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
    pending = nb > 0 and (bool(brows[-1, I.BR_OPEN]) or last_pending)
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
    S.reset(s)
    bcols = np.zeros((max(nb, 1), len(L.BOUNCE_ROW_COLUMNS)))
    for k, (a, b) in enumerate(blocks):
        e_rows = np.ascontiguousarray(eps[[e for e in range(ne) if ep_block[e] == k]])
        rows = [j for j in range(closed) if b_block[j] == k]
        bcols[:len(rows)] = brows[rows, :len(L.BOUNCE_ROW_COLUMNS)]
        t_end = t[b - 1]
        open_now = [x for x, y in zip(starts, ends) if x <= t_end < y]
        S.block(s, np.ascontiguousarray(diag[a:b]), b - a, e_rows.reshape(-1, 2),
                len(e_rows), bcols, len(rows), bool(open_now),
                open_now[0] if open_now else 0.0, phys.g, phys.flight_time)
    out, st = np.zeros(I.OUT_SIZE), np.zeros(3)
    p = brows[-1] if pending else np.zeros(I.BROW_SIZE)
    code = S.finish(s, bool(pending), p[L.BC_T_IMPACT], p[L.BC_T_RELEASE],
                    bool(p[I.BR_OPEN] != 0.0), p[L.BC_MIN_U0], phys.g, phys.flight_time,
                    phys.t_final, bool(phys.in_contact), out, st)
    return code, out


def _splits(nd, seed):
    rng = np.random.default_rng(seed)
    random = np.cumsum(rng.integers(1, 40, size=nd))
    return {"whole": [], "ones": list(range(1, nd)), "fives": list(range(5, nd, 5)),
            "random": [int(x) for x in random if x < nd]}


@pytest.mark.parametrize("name", list(RUNS))
def test_streamed_equals_first_contact_on_the_whole_track(name):
    code, out = _reference(name)
    assert code == RUNS[name][2]
    nd = len(_run(name)[2])
    for split, cuts in _splits(nd, 1).items():
        for last_pending in (False, True):
            got_code, got = _streamed(name, cuts, last_pending)
            assert got_code == code, (split, last_pending)
            same = (got == out) | (np.isnan(got) & np.isnan(out))
            assert same.all(), (split, last_pending, got[~same], out[~same])


def test_a_run_without_samples_is_undefined():
    s = np.zeros(S.SIZE)
    S.reset(s)
    out = np.zeros(I.OUT_SIZE)
    code = S.finish(s, False, 0.0, 0.0, False, 0.0, -9.81, 1e-3, 1.0, False, out,
                    np.zeros(3))
    assert code == I.UNDEFINED and np.isnan(out).all()
