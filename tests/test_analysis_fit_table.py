"""Least squares of several keys against a measurement table (synthetic measurements made
by the model itself at known parameters: the fit must recover them)."""
from __future__ import annotations

import pytest

import rodjit
from rodjit.analysis.evaluate import evaluate
from rodjit.analysis.fit_table import fit_table, read_measurements

BASE = rodjit.load_preset("paper-mu100").override({"time.t_end": 1.2, "rod.mu": 1.0, "rod.N": 20,
                                                   "output.snapshot_interval": 0.0})


def _table(tmp_path, truth, heights=(0.5, 1.0, 1.5)):
    cfgs = [BASE.override({**truth, "initial.height": h}) for h in heights]
    res = evaluate(cfgs, jobs=1)
    path = tmp_path / "drops.csv"
    lines = ["initial.height,restitution_first,contact_time_first"]
    lines += [f"{h},{r['restitution_first']!r},{r['contact_time_first']!r}"
              for h, r in zip(heights, res)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_recovers_mu_and_floor_stiffness_from_synthetic_drops(tmp_path):
    truth = {"rod.mu": 0.7, "floor.kappa_b": 1500.0}
    path = _table(tmp_path, truth)
    got = fit_table(["rod.mu", "floor.kappa_b"], path, BASE,
                    start={"rod.mu": 1.0, "floor.kappa_b": 1000.0}, jobs=1)
    assert got.values[0] == pytest.approx(0.7, rel=1e-3)
    assert got.values[1] == pytest.approx(1500.0, rel=1e-2)
    assert all(abs(r["residual"]) < 1e-4 for r in got.residuals)
    assert len(got.residuals) == 6 and got.converged
    assert "rod.mu" in repr(got) and "±" in repr(got)


def test_uncertainty_from_the_jacobian_scales_with_the_measurement_errors(tmp_path):
    truth = {"rod.mu": 0.7}
    path = _table(tmp_path, truth)
    text = path.read_text().splitlines()
    text[0] += ",sigma_restitution_first"
    text[1:] = [t + ",0.01" for t in text[1:]]
    path.write_text("\n".join(text) + "\n")
    got = fit_table(["rod.mu"], path, BASE, jobs=1)
    assert got.values[0] == pytest.approx(0.7, rel=1e-3)
    # σ_μ = (Σ_i (∂e_i/∂μ / σ_e)² + Σ_i (∂T_i/∂μ / 1)²)^(−1/2), the derivatives by central
    # differences of independent runs
    d = 1e-3
    conds = [BASE.override({"initial.height": h, "rod.mu": 0.7 + s}) for s in (d, -d)
             for h in (0.5, 1.0, 1.5)]
    r = evaluate(conds, jobs=1)
    info = sum(((r[i]["restitution_first"] - r[i + 3]["restitution_first"]) / (2 * d) / 0.01) ** 2
               + ((r[i]["contact_time_first"] - r[i + 3]["contact_time_first"]) / (2 * d)) ** 2
               for i in range(3))
    assert got.errors[0] == pytest.approx(info ** -0.5, rel=0.05)


def test_bad_tables_are_clear_errors(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("initial.height,restitution\n1,0.8\n")
    with pytest.raises(ValueError, match="unknown column 'restitution'"):
        read_measurements(p)
    p.write_text("initial.height,restitution_first\n1,abc\n")
    with pytest.raises(ValueError, match="line 2: restitution_first = 'abc'"):
        read_measurements(p)
    with pytest.raises(ValueError, match="does not exist"):
        read_measurements(tmp_path / "none.csv")
    p.write_text("initial.height,restitution_first\n1,0.8\n")
    with pytest.raises(ValueError, match=r"holds 1 measurement for 2 keys \(rod.mu, floor.kappa_b\): it needs at least 2"):
        fit_table(["rod.mu", "floor.kappa_b"], p, BASE)
