"""Sweep grids: value lists and ranges, types, the Cartesian order, names, bad input."""
import json

import numpy as np
import pytest

import rodjit
from rodjit.sweeps.grid import Grid, format_value, parse_grid_option


def test_lists_and_ranges_from_the_command_line():
    g = Grid.from_spec(parse_grid_option([
        "rod.mu=0,1,10,100", "floor.kappa_b=logspace(3,5,3)", "floor.beta=linspace(0.01, 0.05, 5)",
        "rod.N=5,20", "time.integrator=verlet,'semi-implicit'"]))
    assert g.keys == ("rod.mu", "floor.kappa_b", "floor.beta", "rod.N", "time.integrator")
    assert g.values[0] == (0.0, 1.0, 10.0, 100.0)
    assert g.values[1] == tuple(np.logspace(3, 5, 3)) == (1e3, 1e4, 1e5)
    assert g.values[2] == tuple(np.linspace(0.01, 0.05, 5))
    assert g.values[3] == (5, 20) and all(type(n) is int for n in g.values[3])
    assert g.values[4] == ("verlet", "semi-implicit")
    assert len(g) == 4 * 3 * 5 * 2 * 2 and g.shape == (4, 3, 5, 2, 2)


def test_python_specs_accept_sequences_arrays_and_text():
    g = Grid.from_spec({"rod.mu": np.array([0.0, 2.5]), "rod.N": [4.0, 8], "floor.beta": 0.02,
                        "rod.kappa": "linspace(50, 150, 3)"})
    assert g.values == ((0.0, 2.5), (4, 8), (0.02,), (50.0, 100.0, 150.0))
    assert Grid.from_json(g.to_json()) == g
    assert json.loads(g.to_json()) == {"rod.mu": [0.0, 2.5], "rod.N": [4, 8],
                                       "floor.beta": [0.02], "rod.kappa": [50.0, 100.0, 150.0]}


def test_points_are_the_cartesian_product_last_key_fastest():
    g = Grid.from_spec({"rod.mu": [0, 1], "floor.beta": [0.01, 0.02, 0.03]})
    pts = list(g.points())
    assert pts == [g.point(i) for i in range(len(g))]
    for i, idx in enumerate(np.ndindex(g.shape)):
        assert pts[i] == {"rod.mu": g.values[0][idx[0]], "floor.beta": g.values[1][idx[1]]}
    assert pts[1] == {"rod.mu": 0.0, "floor.beta": 0.02}
    assert g.config(rodjit.Config(), 4).rod.mu == 1.0
    assert g.config(rodjit.Config(), 4).floor.beta == 0.02
    with pytest.raises(IndexError):
        g.point(6)


def test_run_names_are_deterministic_unique_and_sort_in_grid_order():
    g = Grid.from_spec({"rod.mu": list(range(12)), "floor.beta": [0.01, 0.05]})
    names = [g.run_name(i) for i in range(len(g))]
    assert names[0] == "00_rod.mu=0_floor.beta=0.01.h5"
    assert names[23] == "23_rod.mu=11_floor.beta=0.05.h5"
    assert len(set(names)) == len(names) and sorted(names) == names
    again = Grid.from_spec({"rod.mu": list(range(12)), "floor.beta": [0.01, 0.05]})
    assert [again.run_name(i) for i in range(len(g))] == names
    assert format_value(1e-3) == "0.001" and format_value(100000.0) == "100000"
    assert format_value(5) == "5" and format_value(0.1 + 0.2) == "0.30000000000000004"


@pytest.mark.parametrize("items, message", [
    (["rod.muu=1,2"], "unknown configuration key 'rod.muu'; did you mean 'rod.mu'?"),
    (["mu=1,2"], "did you mean 'rod.mu'"),
    (["rod.mu=1,-2"], r"rod.mu = -2.0 is out of range \(float >= 0\)"),
    (["rod.N=5,2.5"], r"rod.N = 2.5 is not an integer \(int in \[1, 10000000\]\)"),
    (["rod.mu=1,1"], "grid rod.mu lists the value 1.0 twice"),
    (["rod.mu="], "grid rod.mu: no values given"),
    (["rod.mu=linspace(0,1)"], r"linspace\(a, b, n\) takes two numbers and a whole number n >= 1"),
    (["rod.mu=logspace(0,1,2.5)"], "a whole number n >= 1"),
    (["rod.mu=linspace(0,x,3)"], "takes two numbers"),
    (["time.integrator=verlet,rk4"], "time.integrator = 'rk4' is not allowed"),
    (["rod.mu"], "a grid item is KEY=VALUES"),
    (["rod.mu=1", "rod.mu=2"], "grid key rod.mu is given twice"),
    ([], "a sweep needs at least one KEY=VALUES grid item"),
])
def test_bad_grids_name_the_key_and_the_range(items, message):
    with pytest.raises(ValueError, match=message):
        Grid.from_spec(parse_grid_option(items))


def test_validation_names_the_failing_point():
    g = Grid.from_spec({"floor.beta": [0.5, 0.01], "initial.height": [0.0, -0.02]})
    with pytest.raises(ValueError, match=r"grid point 3 \(floor.beta=0.01 initial.height=-0.02\): "
                                         r"initial.height = -0.02 is out of range"):
        g.validate(rodjit.Config())
    with pytest.raises(ValueError, match="at least one configuration key"):
        Grid.from_spec({})


@pytest.mark.parametrize("spec", [{"rod.mu": "linspace(0, 1, 10000000)"},
                                  {"rod.mu": "linspace(0, 1, 10000)",
                                   "rod.kappa": "logspace(1, 3, 1000)"},
                                  {"rod.mu": range(10**7)}])
def test_a_grid_is_sized_before_it_is_made(spec):
    """10^7 points are refused by counting (no value is made: a range of 10^7 would take
    seconds to build); the limit can be raised."""
    with pytest.raises(ValueError, match=r"the grid has 10,000,000 points .* more than the "
                                         r"limit of 1,000,000 points \(raise it with "
                                         r"max_points="):
        Grid.from_spec(spec)
    with pytest.raises(ValueError, match="limit of 100 points"):
        Grid.from_spec({"rod.mu": "linspace(0, 1, 101)"}, max_points=100)
    assert len(Grid.from_spec({"rod.mu": "linspace(0, 1, 101)"}, max_points=101)) == 101


def test_validation_runs_over_values_not_points(monkeypatch):
    """A key that no other key constrains is checked once per value; related keys
    (initial.height with floor.beta) over their own combinations only."""
    from rodjit import config

    calls = []

    def counted(keys, check):
        def run(*values):
            calls.append(keys)
            check(*values)
        return keys, run
    checks = tuple(counted(keys, fn) for keys, fn in config.CROSS_CHECKS)
    monkeypatch.setattr("rodjit.sweeps.grid.CROSS_CHECKS", checks)
    g = Grid.from_spec({"rod.mu": "linspace(0, 1, 1000)", "floor.beta": [0.01, 0.02],
                        "initial.height": [0.5, 1.0, 2.0]})
    assert len(g) == 6000
    g.validate(rodjit.Config())
    # (height, beta): their 6 combinations; the impact speed's check reads the height:
    # its 3 values
    speed = ("initial.impact_speed", "initial.velocity", "initial.height", "gravity.g")
    assert calls.count(("initial.height", "floor.beta")) == 6 and calls.count(speed) == 3
    assert len(calls) == 9
    combos = list(g.combinations(("initial.height", "floor.beta")))
    assert len(combos) == 6 and g.multiplicity(("initial.height", "floor.beta")) == 1000
    for index, over in combos:
        assert {k: g.point(index)[k] for k in over} == over


def test_a_large_allowed_grid_is_made_and_validated():
    g = Grid.from_spec({"rod.mu": "linspace(0, 1, 200000)", "rod.N": [4, 8]})
    g.validate(rodjit.Config())
    assert len(g) == 400000 and g.values[0][-1] == 1.0
