"""The fixed cost of a run cut without changing it: the values of a Config's rod, floor,
gravity and initial sections shared by the Configs ``override`` derives (``driver.prepared``),
and ``simulate``'s sink keeping its run's last block uncopied (``MemorySink(views=True)``);
a Config still refused and warned about at every run."""
import dataclasses
import warnings

import numpy as np
import pytest

import rodjit
from rodjit.config import ModelWarning
from rodjit.driver import prepared
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


def test_a_run_gets_its_own_state_not_the_kept_template():
    cfg = rodjit.Config().override({"time.t_end": 0.2})
    body = prepared.body(cfg)
    state = body.initial(cfg)
    run = Run(cfg)
    assert prepared.body(cfg) is body and not np.shares_memory(run.state, body._state)
    run.start(None)
    while run.advance(MemorySink()) != L.DONE:
        pass
    # the run moved its own state; the template is as it was
    np.testing.assert_array_equal(body.initial(cfg), state)
    assert run.t == pytest.approx(0.2)


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


def test_configs_that_differ_in_time_keys_share_their_body_and_run_unchanged():
    base = rodjit.load_preset("paper-mu0").override({"time.t_end": 0.3})
    a = base.override({"time.integrator": "dp54", "time.rtol": 1e-5, "time.atol": 1e-5})
    b = base.override({"time.integrator": "dop853", "time.rtol": 1e-6, "time.atol": 1e-6})
    assert prepared.body(a) is prepared.body(b)          # the rod's values derived once
    # the same runs as from configurations that share nothing with them
    for cfg in (a, b):
        fresh = rodjit.Config.from_dict(_flat(cfg))      # every section a new object
        assert fresh == cfg and fresh.rod is not cfg.rod
        assert prepared.body(fresh) is not prepared.body(a)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModelWarning)
            _same(rodjit.simulate(cfg), rodjit.simulate(fresh))
    # a changed rod section gets its own body
    assert prepared.body(a.override({"rod.mu": 1.0})) is not prepared.body(a)


def test_a_law_registered_again_gets_a_new_body(monkeypatch):
    """A law registered again under the same name (a notebook cell run twice: new
    functions) is not mistaken for the one a kept body was built with."""
    cfg = rodjit.Config().override({"time.t_end": 0.1})
    kept = prepared.body(cfg)
    get_law = prepared.get_law
    again = dataclasses.replace(get_law("floor", cfg.floor.law), description="again")
    monkeypatch.setattr(prepared, "get_law",
                        lambda kind, name: again if kind == "floor" else get_law(kind, name))
    assert prepared.body(cfg) is not kept
    monkeypatch.undo()
    assert prepared.body(cfg) is kept


def _flat(cfg):
    return {f"{section}.{k}": v for section in ("rod", "floor", "gravity", "initial", "time",
                                                "output")
            for k, v in dataclasses.asdict(getattr(cfg, section)).items()}
