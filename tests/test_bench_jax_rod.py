"""The JAX rod of benchmarks/jax_rod.py (the diffrax peer of bench_sweep.py and bench_gpu.py)
integrates the same system as rodjit.

Its right-hand side, with μ, κ_b and β passed per point, must equal rodjit's plain-NumPy
reference (rodjit.model.reference.rhs, MODEL.md §2) at admissible states on both sides of
the floor, one point at a time and vmapped over points with different parameters; a rod
it cannot represent (γ ≠ 0) is refused.  Skipped where jax is not installed.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

jax = pytest.importorskip("jax")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import jax_rod  # noqa: E402

from rodjit.model.reference import rhs as reference_rhs  # noqa: E402
from rodjit.model.system import build_system, check_admissible  # noqa: E402
from rodjit.presets import load_preset  # noqa: E402

POINTS = [{}, {"rod.mu": 0.0, "floor.beta": 0.03, "floor.kappa_b": 3000.0},
          {"rod.mu": 37.5, "floor.beta": 0.12}, {"rod.N": 9, "floor.beta": 0.08}]


def random_states(cfg, rng, count):
    """Admissible states: strains in (−0.6, 0.6), the bottom from −0.9β (in the floor) to
    above it, velocities O(5 m/s)."""
    n, beta = cfg.rod.N, cfg.floor.beta
    _, rod, floor = build_system(cfg)
    for k in range(count):
        eps = rng.uniform(-0.6, 0.6, n)
        u0 = -0.9 * beta * rng.uniform() if k % 2 == 0 else rng.uniform(0.0, 0.5)
        u = u0 + np.concatenate([[0.0], np.cumsum((1.0 + eps) / n)])
        check_admissible(u, rod, floor)
        yield np.concatenate([u, rng.normal(0.0, 5.0, n + 1)])


def _close(got, want):
    scale = np.abs(want).max()
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * scale)


def _args(cfg):
    return (cfg.rod.mu, cfg.floor.kappa_b, cfg.floor.beta)


@pytest.mark.parametrize("over", POINTS)
def test_jax_rhs_equals_reference(over):
    base = load_preset("paper-mu100")
    cfg = base.override(over)
    # N, κ, g come from the base; μ, κ_b, β only through the per-point arguments
    rhs = jax_rod.make_rhs(base.override({"rod.N": cfg.rod.N}))
    system, rod, floor = build_system(cfg)
    for y in random_states(cfg, np.random.default_rng(37), count=10):
        _close(np.asarray(rhs(0.0, y, _args(cfg))), reference_rhs(0.0, y, system, rod, floor))


def test_jax_rhs_vmapped_over_points():
    """One call over points whose μ, κ_b and β all differ: each row its own point's rhs."""
    base = load_preset("paper-mu100")
    cfgs = [base.override(o) for o in POINTS if "rod.N" not in o]
    rng = np.random.default_rng(6)
    ys = np.array([next(random_states(c, rng, count=1)) for c in cfgs])
    mu, kb, beta = jax_rod.point_arrays(cfgs)
    got = np.asarray(jax.vmap(jax_rod.make_rhs(base), in_axes=(None, 0, 0))(
        0.0, ys, (mu, kb, beta)))
    for row, y, c in zip(got, ys, cfgs):
        _close(row, reference_rhs(0.0, y, *build_system(c)))


def test_bending_is_refused():
    cfg = load_preset("paper-mu100").override({"rod.gamma": 0.02})
    assert "gamma" in jax_rod.unsupported(cfg)
    with pytest.raises(ValueError, match="gamma"):
        jax_rod.make_rhs(cfg)
    assert jax_rod.unsupported(load_preset("paper-mu100")) is None
