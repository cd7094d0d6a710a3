"""Output rows are written through column indices named after the columns."""
import numpy as np
import pytest

import rodjit
from rodjit.stepping import layout as L


@pytest.mark.parametrize("prefix, columns", [("D_", L.DIAG_COLUMNS),
                                             ("EC_", L.EPISODE_COLUMNS),
                                             ("BC_", L.BOUNCE_ROW_COLUMNS)])
def test_every_column_has_one_index_at_its_position(prefix, columns):
    idx = L.column_indices(prefix)
    assert sorted(idx.values()) == list(range(len(columns)))
    for name, i in idx.items():
        assert columns[i] == name
    L.check_columns()


def test_a_misplaced_index_is_caught(monkeypatch):
    monkeypatch.setattr(L, "D_ENERGY_BEND", L.D_ENERGY_STRETCH)
    with pytest.raises(AssertionError, match="D_"):
        L.check_columns()
    monkeypatch.undo()
    monkeypatch.setattr(L, "BC_SPARE", 9, raising=False)   # an index without a column
    with pytest.raises(AssertionError, match="BC_"):
        L.check_columns()


def test_the_columns_hold_what_their_names_say():
    """A bouncing run: each diagnostics column against an independent computation from
    the snapshots, each bounce column against its definition."""
    cfg = rodjit.Config().override({
        "rod.N": 6, "rod.mu": 1.0, "time.t_end": 0.6, "initial.height": 0.05,
        "initial.velocity": -1.0, "output.snapshot_interval": 0.01,
        "output.diagnostics_interval": 0.01})
    res = rodjit.simulate(cfg)
    d = res.diagnostics
    np.testing.assert_array_equal(d["t"], res.t)
    from rodjit.model.system import masses
    m = masses(6)
    np.testing.assert_allclose(d["u_bottom"], res.u[:, 0], rtol=0, atol=0)
    np.testing.assert_allclose(d["cm_height"], res.u @ m, rtol=1e-13)
    np.testing.assert_allclose(d["cm_velocity"], res.v @ m, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(d["energy_kinetic"], 0.5 * (res.v ** 2) @ m, rtol=1e-12)
    np.testing.assert_allclose(d["energy_gravity"], -cfg.gravity.g * (res.u @ m), rtol=1e-13)
    parts = sum(d[k] for k in ("energy_kinetic", "energy_stretch", "energy_bend",
                                "energy_floor", "energy_gravity"))
    np.testing.assert_allclose(d["energy_total"], parts, rtol=1e-14)
    assert np.all(np.diff(d["dissipated"]) >= 0) and d["dissipated"][-1] > 0
    assert np.all(d["dt"] > 0)
    strains = np.diff(res.u, axis=1) * 6 - 1.0
    np.testing.assert_allclose(d["min_strain"], strains.min(axis=1), rtol=1e-12, atol=1e-14)
    assert np.all((d["floor_force"] > 0) == (d["u_bottom"] < 0))
    b = res.bounces
    assert len(b["t_impact"]) >= 1
    done = np.isfinite(b["t_release"])
    assert np.all(b["t_release"][done] > b["t_impact"][done])
    np.testing.assert_allclose(b["restitution"][done],
                               -b["w_release"][done] / b["w_impact"][done], rtol=1e-15)
    assert np.all(b["w_impact"] < 0) and np.all(b["min_u0"] < 0)
    assert np.all(b["max_floor_force"] > 0) and np.all(b["n_episodes"] >= 1)
    e = res.episodes
    assert np.all(e["t_end"] > e["t_start"])
