"""The pure helpers of benchmarks/work_precision.py, on synthetic work–precision data:
the cost at a target (bench_peers' front and interpolation), the fastest integrator and
its runner-up, the default's ratio, the budget's estimate of the next rung, the regime
table and the settings grid."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import work_precision as wp  # noqa: E402

# cost ∝ error^(-1/2) and ∝ error^(-1): straight lines in log-log
SLOW = sorted((10.0 ** -k, 10.0 ** (k / 2)) for k in range(2, 8))   # a front: errors up
STEEP = sorted((10.0 ** -k, 10.0 ** (k - 3)) for k in range(2, 6))   # reaches 1e-5 only


def test_cost_at_interpolates_along_the_front():
    # halfway between rungs in log error lies halfway in log cost
    assert wp.cost_at(SLOW, 10 ** -3.5) == pytest.approx(10 ** 1.75)
    assert wp.cost_at(STEEP, 1e-6) is None
    # a front keeps only the points that buy accuracy with time
    pts = [{"error": e, "best": c, "times": [c]} for e, c in STEEP]
    pts.append({"error": 1e-3, "best": 50.0, "times": [50.0]})         # dominated
    pts.append({"error": math.inf, "best": None, "times": []})         # failed
    assert wp.front(pts) == sorted(STEEP)


def test_ratios_at_names_the_fastest_and_the_runner_up():
    e = 1e-4
    costs = {name: wp.cost_at(fr, e) for name, fr in
             {"slow": SLOW, "steep": STEEP, "never": []}.items()}
    r = wp.ratios_at(costs)
    assert r["fastest"] == "steep" and r["seconds"] == pytest.approx(10.0)
    assert r["runner_up"] == "slow"
    assert r["runner_up_ratio"] == pytest.approx(100.0 / 10.0)
    assert r["ratios"]["never"] is None and r["ratios"]["steep"] == 1.0
    assert wp.ratios_at({"a": None}) is None
    alone = wp.ratios_at({"a": 2.0, "b": None})
    assert alone["runner_up"] is None and alone["runner_up_ratio"] is None


def test_default_ratio_against_the_cheapest_front_at_its_error():
    fronts = {"slow": SLOW, "steep": STEEP}
    d = wp.default_ratio(fronts, 1e-3, 30.0)
    # at 1e-3: slow 10**1.5, steep 1: steep is the cheapest
    assert d["cheapest"] == "steep" and d["ratio"] == pytest.approx(30.0)
    # more accurate than any front reaches, or cheaper than all: the default is the best
    d = wp.default_ratio(fronts, 1e-9, 5.0)
    assert d["cheapest"] == "default" and d["ratio"] == 1.0
    d = wp.default_ratio(fronts, 1e-3, 0.5)
    assert d["cheapest"] == "default" and d["ratio"] == 1.0


def test_next_estimate_grows_by_order_or_by_what_was_measured():
    # one rung: an order-5 method's steps grow 10^(1/5) a decade of tolerance
    assert wp.next_estimate([1.0], [1e-3], "tol", 5, 1e-4) == pytest.approx(10 ** 0.2)
    # cfl: steps ∝ 1/cfl
    assert wp.next_estimate([2.0], [0.5], "cfl", 2, 0.16) == pytest.approx(2.0 * 0.5 / 0.16)
    # a measured growth larger than the order's (a stiff or capped regime) wins
    assert wp.next_estimate([1.0, 4.0], [1e-3, 1e-4], "tol", 5, 1e-5) == pytest.approx(16.0)
    assert wp.next_estimate([1.0, 1.0], [1e-3, 1e-4], "tol", 2, 1e-5) == pytest.approx(
        10 ** 0.5)


def _setting(targets, at, default):
    return {"targets": targets, "at": at, "default": default}


def test_regime_rows_assembles_the_table():
    at = {"1e-03": wp.ratios_at({"dop853": 1.0, "dp54": 1.5}),
          "1e-04": wp.ratios_at({"dop853": None, "radau5": 3.0})}
    settings = {
        "mu0-N5-kb1e3": _setting([1e-3, 1e-4], at, wp.default_ratio({"x": SLOW}, 1e-3, 100.0)),
    }
    rows = wp.regime_rows(settings)
    assert rows == [["mu0-N5-kb1e3", "dop853 (dp54 1.5×)", "radau5 (alone)",
                     "below reference", "1.0e-03", f"{100 / 10 ** 1.5:.2g}× (x)"]]
    # a target the reference allows but no integrator reaches
    settings["mu0-N5-kb1e3"]["targets"] = [1e-3, 1e-4, 1e-6]
    assert wp.regime_rows(settings)[0][3] == "none"
    md = wp.markdown(rows, ["setting", "a", "b", "c", "d", "e"])
    assert md.splitlines()[1] == "|---|---|---|---|---|---|"


def test_settings_grid_and_ladders():
    full, quick = wp.setting_names(), wp.setting_names(quick=True)
    assert len(full) == len(wp.MUS) * len(wp.NS) * len(wp.FLOORS) == len(set(full))
    assert set(quick) <= set(full) and len(quick) == len(wp.MUS) * 2
    assert all(wp.parse_setting(n)["floor.kappa_b"] == 1e3 for n in quick)
    assert wp.parse_setting("mu100-N320-kb1e7") == {
        "rod.mu": 100.0, "rod.N": 320, "floor.kappa_b": 1e7, "floor.beta": 0.01}
    for bad in ("mu1-N5", "mu1-N5-kb1e5", "x1-N5-kb1e3", "mu1-Nx-kb1e3"):
        with pytest.raises(ValueError, match="--settings"):
            wp.parse_setting(bad)
    assert wp.ladder("verlet") == ("cfl", wp.CFLS)
    assert wp.ladder("radau5", quick=True) == ("tol", (1e-3, 1e-6))
    assert wp.overrides("semi-implicit", "cfl", 0.05) == {
        "time.integrator": "semi-implicit", "time.control": "cfl", "time.cfl": 0.05}


def test_run_error_takes_the_restitution_where_the_reference_has_one():
    assert wp.run_error(1e-6, 0.5 + 1e-4, 0.5) == (pytest.approx(1e-4), pytest.approx(1e-4))
    assert wp.run_error(1e-3, 0.5 + 1e-4, 0.5)[0] == 1e-3
    # the run lost the bounce the reference has
    assert wp.run_error(1e-6, math.nan, 0.5) == (math.inf, math.inf)
    # the reference's first bounce is still open: the state alone
    assert wp.run_error(1e-6, math.nan, math.nan) == (1e-6, None)
    assert wp.run_error(1e-6, 0.3, math.nan) == (1e-6, None)
