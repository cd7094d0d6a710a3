"""The fixed cost of a run cut without changing it: a Config's run-independent values kept
per Config object (``driver.prepared``), and ``simulate``'s sink keeping its run's last
block uncopied (``MemorySink(views=True)``)."""
import gc
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


def test_a_config_is_prepared_once_and_its_runs_are_unchanged():
    cfg = rodjit.Config().override({"time.t_end": 0.5, "rod.mu": 3.0})
    first = rodjit.simulate(cfg)
    p = prepared.prepare(cfg)
    assert prepared.prepare(cfg) is p            # kept: the second run derives nothing
    again = rodjit.simulate(cfg)
    assert prepared.prepare(cfg) is p
    # a new, equal Config object is prepared anew, and runs the same to the bit
    twin = rodjit.Config().override({"time.t_end": 0.5, "rod.mu": 3.0})
    assert prepared.prepare(twin) is not p
    _same(first, again)
    _same(first, rodjit.simulate(twin))


def test_a_run_gets_its_own_arrays_not_the_kept_templates():
    cfg = rodjit.Config().override({"time.t_end": 0.2})
    p = prepared.prepare(cfg)
    clock, ev, state = p.clock.copy(), p.ev.copy(), p.initial()
    run = Run(cfg)
    assert not np.shares_memory(run.clock, p.clock)
    assert not np.shares_memory(run.ev, p.ev)
    run.start(None)
    while run.advance(MemorySink()) != L.DONE:
        pass
    # the run moved its own clock, state and events; the templates are as they were
    np.testing.assert_array_equal(p.clock, clock)
    np.testing.assert_array_equal(p.ev, ev)
    np.testing.assert_array_equal(p.initial(), state)
    assert run.t == pytest.approx(0.2)


def test_a_dead_configs_id_is_not_mistaken_for_it():
    cfg = rodjit.Config().override({"time.t_end": 0.3})
    prepared.prepare(cfg)
    key = id(cfg)
    del cfg
    gc.collect()
    other = rodjit.Config().override({"time.t_end": 0.4})
    # whether or not the id is reused, the entry of the dead object is never returned
    assert prepared.prepare(other).clock[L.T_END] == 0.4
    assert key not in prepared._CACHE or prepared._CACHE[key][0]() is other
    # nor kept: a dead Config's values are dropped with it
    assert all(ref() is not None for ref, _ in prepared._CACHE.values())


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


def test_a_changed_registry_or_output_cap_prepares_the_config_anew(monkeypatch):
    from rodjit.stepping import control, registry

    cfg = rodjit.Config().override({"time.integrator": "dp54", "time.t_end": 0.1})
    p = prepared.prepare(cfg)
    assert p.args[1].dense_snapshots == control.DENSE_OUTPUTS_MAX
    monkeypatch.setattr(control, "DENSE_OUTPUTS_MAX", 2)
    q = prepared.prepare(cfg)
    assert q is not p and q.args[1].dense_snapshots == 2
    monkeypatch.setattr(registry, "SCHEMES",      # another registry (as a registration makes)
                        (*registry.SCHEMES[1:], registry.SCHEMES[0]))
    assert prepared.prepare(cfg) is not q
    monkeypatch.undo()
    assert prepared.prepare(cfg).args[1].dense_snapshots == control.DENSE_OUTPUTS_MAX


def test_configs_that_differ_in_time_keys_share_their_body_and_run_unchanged():
    base = rodjit.load_preset("paper-mu0").override({"time.t_end": 0.3})
    a = base.override({"time.integrator": "dp54", "time.rtol": 1e-5, "time.atol": 1e-5})
    b = base.override({"time.integrator": "dop853", "time.rtol": 1e-6, "time.atol": 1e-6})
    pa, pb = prepared.prepare(a), prepared.prepare(b)
    assert pa is not pb and pa.body is pb.body          # the rod's values derived once
    assert pa.args[0] is not pb.args[0]                  # each its own scheme
    # the same runs as from configurations that share nothing with them
    for cfg in (a, b):
        fresh = rodjit.Config.from_dict(_flat(cfg))      # every section a new object
        assert fresh == cfg and fresh.rod is not cfg.rod
        assert prepared.prepare(fresh).body is not pa.body
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModelWarning)
            _same(rodjit.simulate(cfg), rodjit.simulate(fresh))
    # a changed rod section gets its own body
    c = a.override({"rod.mu": 1.0})
    assert prepared.prepare(c).body is not pa.body


def _flat(cfg):
    import dataclasses
    return {f"{section}.{k}": v for section in ("rod", "floor", "gravity", "initial", "time",
                                                "output")
            for k, v in dataclasses.asdict(getattr(cfg, section)).items()}
