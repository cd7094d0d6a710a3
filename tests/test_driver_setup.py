"""A point's set-up (``rodjit.driver.setup``: single runs, the CPU engine's batches and the
GPU engine), each piece kept by the values of what it reads, against every piece made anew
for every point (the cache emptied before each): the same parameter tuples (values and
field types), the same start arrays to the bit, the same warnings, and the same failure
for a point that cannot start."""
from __future__ import annotations

import warnings

import numpy as np

import rodjit
import custom_law  # noqa: F401  (registers the law "raise-test")
from rodjit.config import ModelWarning
from rodjit.driver import setup
from rodjit.sweeps.grid import Grid


def _bits(a) -> bytes:
    return np.ascontiguousarray(a, dtype=np.float64).tobytes()


def _same_tuple(a, b) -> bool:
    if type(a) is not type(b) or len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if type(x) is not type(y):
            return False
        if isinstance(x, float):
            if _bits(x) != _bits(y):
                return False
        elif x != y:
            return False
    return True


def _said(make):
    """``(what make() returned or raised, the ModelWarning texts it issued)``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ModelWarning)
        try:
            got = make()
        except Exception as exc:
            got = exc
    return got, {str(w.message) for w in caught if issubclass(w.category, ModelWarning)}


def _alone(config):
    """A point's start with every piece made anew (nothing kept from other points)."""
    setup.clear()
    return _said(lambda: setup.start(config))


def _check(*grids):
    """Compare for the points of the grids ``(base, spec)``, set up in one batch."""
    configs = []
    for base, spec in grids:
        grid = Grid.from_spec(spec)
        configs += [grid.config(base, i) for i in range(len(grid))]
    setup.clear()
    got, said = _said(lambda: setup.starts(configs))
    want_said: set = set()
    for c, g in zip(configs, got):
        want, w = _alone(c)
        want_said |= w
        if isinstance(want, Exception):
            assert isinstance(g, Exception), c
            assert (type(g), str(g)) == (type(want), str(want))
            continue
        assert not isinstance(g, Exception), (c, g)
        for a, b in zip(g.params(), want.params()):
            assert _same_tuple(a, b), (a, b)
        for name in ("state", "clock"):
            x, y = getattr(g, name), getattr(want, name)
            assert x.shape == y.shape and _bits(x) == _bits(y), name
        assert _bits(g.ev()) == _bits(want.ev())
        # the point's configuration, "auto" resolved (a named integrator: the same object)
        assert g.config is c if c.time.integrator != "auto" else g.config == c.resolve()
    assert said == want_said
    return got


def test_a_grid_of_many_sections_starts_as_each_point_alone():
    base = rodjit.Config().override({"time.t_end": 0.3})
    spec = {"rod.mu": [0.0, 25.0, 100.0], "floor.kappa_b": [1000.0, 3000.0],
            "initial.velocity": [0.0, -1.5], "time.integrator": ["energy", "dp54"],
            "rod.N": [5, 8], "output.diagnostics_interval": [1e-3, 0.0]}
    # a zero of either sign (equal, but a start of -0.0 is not one of 0.0)
    got = _check((base, spec),
                 (base.override({"initial.velocity": -0.0}), {"rod.mu": [0.0, 25.0]}))
    # what the points agree on is one object, made once
    assert got[0].scheme is got[1].scheme and got[0].ctrl is got[1].ctrl


def test_points_that_cannot_start_fail_as_they_would_alone():
    base = rodjit.Config().override({"time.t_end": 0.3, "rod.law": "raise-test"})
    got = _check((base, {"rod.kappa": [100.0, 13.0, 50.0], "rod.mu": [0.0, 5.0],
                         "initial.height": [0.5, 1e12]}))
    assert sum(isinstance(g, Exception) for g in got) == 8


def test_kept_initial_states_are_bounded_in_memory(monkeypatch):
    """A sweep of the initial state of a long rod keeps the latest states only, whatever
    the count kept of small pieces."""
    monkeypatch.setattr(setup, "ARRAY_FLOATS", 2 * 41 * 16)     # 16 states of N = 40
    setup.clear()
    base = rodjit.Config().override({"time.t_end": 0.3, "rod.N": 40})
    starts = setup.starts([base.override({"initial.height": 1.0 + k / 64})
                           for k in range(40)])
    assert not any(isinstance(s, Exception) for s in starts)
    assert len(setup._MADE["state"]) == 16 and len(setup._MADE["clock"]) == 1
    # the latest are kept, the others made again (equal, not the same object)
    assert setup.start(starts[-1].config).state is starts[-1].state
    again = setup.start(starts[0].config)
    assert again.state is not starts[0].state and _bits(again.state) == _bits(starts[0].state)
