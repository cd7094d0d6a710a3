"""The fixed cost of a run cut without changing it: the pieces of a point's set-up kept by
the values of what they read, shared by the Configs ``override`` derives and by equal ones
(``driver.setup``), and ``simulate``'s sink keeping its run's last block uncopied
(``MemorySink(views=True)``); a Config still refused and warned about at every run."""
import dataclasses
import warnings

import numpy as np
import pytest

import rodjit
from rodjit.config import ModelWarning
from rodjit.driver import setup
from rodjit.driver.run import Run
from rodjit.records.result import MemorySink
from rodjit.stepping import layout as L

FIELDS = ("t", "u", "v", "u_final", "v_final")


def _same(a, b):
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    for table in ("diagnostics", "episodes", "bounces"):
        ta, tb = getattr(a, table), getattr(b, table)
        assert list(ta) == list(tb)
        for k in ta:
            np.testing.assert_array_equal(ta[k], tb[k], err_msg=f"{table}.{k}")
    for k in ("steps", "rejected_steps"):
        assert a.stats[k] == b.stats[k]


def test_a_run_gets_its_own_state_and_clock_not_the_kept_ones():
    cfg = rodjit.Config().override({"time.t_end": 0.2})
    kept = setup.start(cfg)
    state, clock = kept.state.copy(), kept.clock.copy()
    run = Run(cfg)
    assert setup.start(cfg).state is kept.state
    assert not np.shares_memory(run.arrays.state, kept.state)
    assert not np.shares_memory(run.arrays.clock, kept.clock)
    # the run starts from the kept arrays to the bit, and shares the parameter tuples
    assert run.arrays.state[:2].tobytes() == state.tobytes() and not run.arrays.state[2].any()
    assert run.arrays.clock.tobytes() == clock.tobytes() and run.arrays.ev.tobytes() == kept.ev().tobytes()
    assert all(a is b for a, b in zip(run._args(), kept.params()))
    run.start(None)
    while run.advance(MemorySink()) != L.DONE:
        pass
    # the run moved its own state and clock; the kept ones are as they were
    np.testing.assert_array_equal(setup.start(cfg).state, state)
    np.testing.assert_array_equal(setup.start(cfg).clock, clock)
    assert run.t == pytest.approx(0.2)


def test_a_run_from_its_own_profiles_is_checked_under_their_name():
    cfg = rodjit.Config().override({"time.t_end": 0.2})
    u = np.linspace(0.5, 1.6, cfg.rod.N + 1)
    run = Run(cfg, u0=u, v0=np.zeros(cfg.rod.N + 1))
    assert run.u.tobytes() == u.tobytes()
    with pytest.raises(ValueError, match="u0 is not admissible"):
        Run(cfg, u0=u[::-1], v0=np.zeros(cfg.rod.N + 1))
    # a profile is not kept: the default start is still the config's
    assert setup.start(cfg).state[0].tobytes() != u.tobytes()


def test_a_refused_config_is_refused_at_every_run():
    cfg = rodjit.Config().override({"rod.mu": 100.0, "time.integrator": "verlet",
                                    "time.control": "tolerance"})
    for _ in range(2):
        with pytest.raises(ValueError, match="verlet"):
            rodjit.simulate(cfg)
    # and an initial state out of range, at every run too
    bad = rodjit.Config().override({"initial.height": 1e12})
    for _ in range(2):
        with pytest.raises(ValueError, match="initial.height"):
            rodjit.simulate(bad)


def test_the_model_warning_comes_with_every_run():
    cfg = rodjit.Config().override({"rod.mu": 0.0, "rod.gamma": 0.0, "time.t_end": 0.05})
    for _ in range(2):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            rodjit.simulate(cfg)
        assert any(issubclass(w.category, ModelWarning) for w in caught)


def _in_pieces(cfg, sink, settle):
    run = Run(cfg, snapshot_capacity=3, diag_capacity=5, event_capacity=1)
    run.start(None)
    while run.advance(sink, max_steps=7) != L.DONE:
        if settle:
            sink.settle()
    return sink.result(run)


def test_a_viewing_sink_settled_between_calls_equals_a_copying_one():
    cfg = rodjit.Config().override({"time.t_end": 1.5})
    copied = _in_pieces(cfg, MemorySink(), settle=False)
    viewed = _in_pieces(cfg, MemorySink(views=True), settle=True)
    assert copied.t.size > 3 and copied.n_bounces >= 1      # many blocks, bounces among them
    _same(copied, viewed)
    # what settle is for: without it the kept views are refilled by later calls
    unsettled = _in_pieces(cfg, MemorySink(views=True), settle=False)
    assert not np.array_equal(unsettled.t, copied.t)


def test_configs_that_differ_in_time_keys_share_their_rod_pieces_and_run_unchanged():
    base = rodjit.load_preset("paper-mu0").override({"time.t_end": 0.3})
    a = base.override({"time.integrator": "dp54", "time.rtol": 1e-5, "time.atol": 1e-5})
    b = base.override({"time.integrator": "dop853", "time.rtol": 1e-6, "time.atol": 1e-6})
    sa, sb = setup.start(a), setup.start(b)
    assert sa.rod is sb.rod and sa.system is sb.system    # the rod's values derived once
    assert sa.state is sb.state and sa.scheme is not sb.scheme
    # an equal Config that shares no object with it finds the same pieces, and runs the same
    for cfg in (a, b):
        fresh = rodjit.Config.from_dict(_flat(cfg))      # every section a new object
        assert fresh == cfg and fresh.rod is not cfg.rod
        assert all(x is y for x, y in zip(setup.start(fresh).params(),
                                          setup.start(cfg).params()))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModelWarning)
            _same(rodjit.simulate(cfg), rodjit.simulate(fresh))
    # a changed rod section gets its own pieces
    assert setup.start(a.override({"rod.mu": 1.0})).system is not sa.system


def test_a_law_registered_again_gets_new_pieces(monkeypatch):
    """A law registered again under the same name (a notebook cell run twice: new
    functions) is not mistaken for the one kept pieces were made with."""
    cfg = rodjit.Config().override({"time.t_end": 0.1})
    kept = setup.start(cfg)
    get_law = setup.get_law
    again = dataclasses.replace(get_law("floor", cfg.floor.law), description="again")
    monkeypatch.setattr(setup, "get_law",
                        lambda kind, name: again if kind == "floor" else get_law(kind, name))
    got = setup.start(cfg)
    assert got.floor is not kept.floor and got.rod is kept.rod
    monkeypatch.undo()
    assert setup.start(cfg).floor is kept.floor


def _flat(cfg):
    return {f"{section}.{k}": v for section in ("rod", "floor", "gravity", "initial", "time",
                                                "output")
            for k, v in dataclasses.asdict(getattr(cfg, section)).items()}
