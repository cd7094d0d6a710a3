"""rodjit.fit: one key to a target observable, its sensitivity and resolution shift, and
the errors for unreachable targets and non-monotone responses."""
from __future__ import annotations

import math

import pytest

import rodjit
from rodjit.analysis.evaluate import evaluate
from rodjit.analysis.fit import FitError, fit, scan_points

BASE = rodjit.load_preset("paper-mu100").override({"time.t_end": 2.0,
                                                   "output.snapshot_interval": 0.0})


def test_scan_points_are_geometric_over_decades():
    assert scan_points(0, 1000, 5) == pytest.approx([0.0, 1.0, 10.0, 100.0, 1000.0])
    assert scan_points(1, 2, 3) == pytest.approx([1, 1.5, 2])
    with pytest.raises(ValueError):
        scan_points(0, 1, 1)


def test_fit_mu_to_a_restitution_and_check_it_by_an_independent_run():
    res = fit("rod.mu", {"restitution_first": 0.8}, BASE, bracket=(0, 3), jobs=1, ftol=1e-5)
    assert res.achieved == pytest.approx(0.8, abs=1e-5)
    check = evaluate([BASE.override({"rod.mu": res.value})], jobs=1)[0]
    assert check["restitution_first"] == pytest.approx(0.8, abs=1e-5)
    # the sensitivity against a central difference of two more runs
    d = 1e-3
    up, dn = evaluate([BASE.override({"rod.mu": res.value + d}),
                       BASE.override({"rod.mu": res.value - d})], jobs=1)
    fd = (up["restitution_first"] - dn["restitution_first"]) / (2 * d)
    assert res.sensitivity < 0
    assert res.sensitivity == pytest.approx(fd, rel=0.05)
    # the answer at N/2 = 2 differs, by an estimate the fit reports
    assert math.isfinite(res.resolution_shift) and res.coarse == "rod.N = 2"
    assert res.evaluations < 20
    assert "rod.mu" in repr(res) and "0.8" in repr(res)


def test_a_target_outside_the_reach_of_the_bracket_names_the_reachable_range():
    with pytest.raises(FitError, match=r"outside the range 0\.6\d* \.\. 0\.91"):
        fit("rod.mu", {"restitution_first": 0.95}, BASE, bracket=(0, 1), jobs=1, points=4)


def test_a_target_crossed_twice_says_where():
    # 0.91 at μ = 0, 0.44 at 3, no lift-off at 10 and 30, then up to 0.81 at 3000
    with pytest.raises(FitError, match=r"not monotone in rod\.mu: it crosses 0\.5 in "
                                       r"\[0, 3\], \[94\.87, 300\]"):
        fit("rod.mu", {"restitution_first": 0.5}, BASE, bracket=(0, 3000), jobs=1)


def test_a_one_crossing_non_monotone_response_is_noted():
    res = fit("rod.mu", {"restitution_first": 0.7}, BASE, bracket=(3, 3000), jobs=1,
              ftol=1e-3)
    assert res.achieved == pytest.approx(0.7, abs=1e-3)
    assert 300 < res.value < 948.7
    assert res.notes and "not monotone" in res.notes[0]


@pytest.mark.slow
def test_fit_of_the_continuum_value_along_a_ladder():
    cfg = BASE.override({"rod.N": 10, "time.t_end": 1.0})
    res = fit("rod.mu", {"restitution_first": 0.7}, cfg, bracket=(0.3, 2), converged=True,
              ladder={"rod.N": [10, 20, 40]}, jobs=2, ftol=1e-4, points=4)
    assert res.converged and res.achieved == pytest.approx(0.7, abs=1e-4)
    assert res.coarse == "rod.N = 40" and math.isfinite(res.resolution_shift)


def test_bad_fit_input_is_a_clear_error():
    with pytest.raises(ValueError, match="unknown observable"):
        fit("rod.mu", {"nope": 1}, BASE)
    with pytest.raises(ValueError, match="bracket"):
        fit("rod.mu", {"restitution_first": 0.8}, BASE, bracket=(3, 1))
    with pytest.raises(ValueError, match="rod.mu"):
        fit("rod.mu", {"restitution_first": 0.8}, BASE, bracket=(-1, 1))
    with pytest.raises(ValueError, match="real-valued"):
        fit("rod.N", {"restitution_first": 0.8}, BASE, bracket=(5, 50))
