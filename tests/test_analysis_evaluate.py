"""``analysis.evaluate``: the observables of many configurations, from a run file each or,
for the observables a sweep point's summary row holds, from the batch engine: the same
numbers either way."""
from __future__ import annotations

import math

import pytest

import rodjit
from rodjit.analysis.evaluate import SUMMARY_OF, evaluate

BASE = rodjit.load_preset("paper-mu100").override({"time.t_end": 1.0})
CONFIGS = [BASE,                                                     # lift-off
           BASE.override({"rod.mu": 10.0}),                          # no lift-off
           BASE.override({"rod.mu": 10.0, "time.t_end": 0.47}),      # open at the end
           BASE.override({"time.t_end": 0.2}),                       # no impact
           BASE.override({"rod.mu": 300.0, "initial.height": 0.01,
                          "initial.impact_speed": 7.0}),
           BASE.override({"time.dt_min": 0.05})]                     # fails: step too short


def _same(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))


@pytest.mark.parametrize("scheduler, jobs", [(None, 2), ("inline", 1)])
def test_the_batch_engine_gives_the_observables_of_the_run_files(scheduler, jobs):
    names = list(SUMMARY_OF)
    whole = evaluate(CONFIGS, jobs=2)                   # a run file each (two workers)
    batched = evaluate(CONFIGS, jobs=jobs, scheduler=scheduler, columns=names)
    assert [r["status"] for r in whole] == ["lift-off", "no lift-off", "open", "no impact",
                                            "lift-off", "failed"]
    for w, b in zip(whole, batched):
        assert b["status"] == w["status"]
        assert b["steps"] == w["steps"] and b["rejected_steps"] == w["rejected_steps"]
        for name in names:
            assert _same(b[name], w[name]), (name, b[name], w[name])
        if w["status"] == "failed":
            assert "dt_min" in b["reason"] and b["reason"] == b["message"]
        else:
            assert b["reason"] == w["reason"]
    assert set(batched[0]) == {*names, "status", "reason", "run_status", "message", "steps",
                               "rejected_steps"}


def test_what_the_summary_does_not_hold_takes_the_run_files():
    """An observable of the whole run (the second contact), an extra function or another
    merge time: a run each, all observables back."""
    out = evaluate(CONFIGS[:1], columns=["restitution_second"])
    assert "restitution_second" in out[0] and "vibration_share_first" in out[0]
    out = evaluate(CONFIGS[:1], columns=["restitution_first"], merge_time=0.01)
    assert "vibration_share_first" in out[0]
