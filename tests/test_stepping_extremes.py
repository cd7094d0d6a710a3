"""A bounce's extremes (min_u0, max_floor_force, min_strain) come from inside the steps
(``stepping.extremes``): the dense output of a scheme that has one, the cubic Hermite of
the step's ends for the others."""
from __future__ import annotations

import numpy as np
import pytest

import rodjit

COLUMNS = ("min_u0", "max_floor_force", "min_strain")
BASE = {"time.t_end": 0.9, "output.snapshot_interval": 0.05,
        "output.diagnostics_interval": 0.05, "time.control": "tolerance"}


def _first(integrator, rtol, **over):
    cfg = rodjit.load_preset("paper-mu0").override(
        {**BASE, "time.integrator": integrator, "time.rtol": rtol, "time.atol": rtol * 1e-3,
         **over})
    r = rodjit.simulate(cfg)
    return r, np.array([float(np.asarray(r.bounces[c])[0]) for c in COLUMNS])


@pytest.fixture(scope="module")
def reference():
    """dop853 at rtol 1e-10: its extremes from its dense output (the sampling error of its
    step points, ~1e-4 relative at the deepest point, is gone)."""
    return _first("dop853", 1e-10)[1]


@pytest.mark.parametrize("integrator, rtol, bound", [
    # step points only, these were off by 1.4e-3 (dp54) and 2.9e-4 (radau5) at rtol 1e-6
    ("dp54", 1e-6, 1e-5),
    ("radau5", 1e-6, 1e-5),
])
def test_dense_output_extremes_converge_with_the_tolerance(reference, integrator, rtol, bound):
    _, got = _first(integrator, rtol)
    err = np.abs(got / reference - 1.0)
    assert np.all(err < bound), dict(zip(COLUMNS, err))


def test_extremes_are_at_least_as_extreme_as_every_dense_output_row():
    """dp54 with its diagnostics interpolated inside the steps every 0.1 ms: no row of the
    first bounce lies deeper, or pushes harder, than the bounce's extremes say."""
    r, got = _first("dp54", 1e-4, **{"output.diagnostics_interval": 1e-4,
                                     "output.interpolate": True})
    b = r.bounces
    t0, t1 = float(np.asarray(b["t_impact"])[0]), float(np.asarray(b["t_release"])[0])
    d = r.diagnostics
    t = np.asarray(d["t"])
    inside = (t >= t0) & (t <= t1)
    assert inside.sum() > 10
    # (to 1e-12 relative: the search's bracket ends within 5e-4 of a sample interval)
    u_rows = np.asarray(d["u_bottom"])[inside].min()
    f_rows = np.asarray(d["floor_force"])[inside].max()
    e_rows = np.asarray(d["min_strain"])[inside].min()
    assert got[0] <= u_rows + 1e-12 * abs(u_rows)
    assert got[1] >= f_rows - 1e-12 * abs(f_rows)
    assert got[2] <= e_rows + 1e-12 * abs(e_rows)


def test_hermite_extremes_of_the_second_order_schemes(reference):
    """energy (no dense output) at rtol 1e-4: the cubic Hermite of the step's ends gives the
    deepest point and the largest force to 7e-5 and 1e-4 (its step points alone: 2.1e-4 and
    3.0e-4)."""
    _, got = _first("energy", 1e-4)
    err = np.abs(got / reference - 1.0)
    assert err[0] < 1.5e-4 and err[1] < 1.5e-4, dict(zip(COLUMNS, err))
