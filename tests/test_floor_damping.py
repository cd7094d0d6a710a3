"""The floor's Hunt–Crossley damping, ``floor.damping`` (MODEL.md §1 "The floor's damping",
§2): the compiled right-hand side against the NumPy reference (its time derivative:
tests/test_stepping_energy.py, its Jacobian: tests/test_stepping_radau.py), the energy
balance and the dissipated energy on every integrator, the physics it was made for
(restitution falling with the impact speed), and its refusals."""
import warnings

import numpy as np
import pytest

import rodjit
from conftest import assert_resume_is_bit_identical, rodjit_cli
from rodjit.driver.run import Run
from rodjit.kernels import rates
from rodjit.kernels.forces import INACCURATE, OK
from rodjit.model import reference as ref
from rodjit.model.system import masses
from rodjit.records.result import MemorySink
from rodjit.stepping.integrators import energy as EN
from rodjit.stepping.registry import NAMES

ALPHA = 0.3          # s/m: restitution 0.91 → 0.76 on paper-mu0 at 4.43 m/s


def damped(preset="paper-mu100", **over):
    return rodjit.load_preset(preset).override({"floor.damping": ALPHA, **over})


def contact_state(n, u0, v0, seed=1):
    rng = np.random.default_rng(seed)
    x = np.arange(n + 1) / n
    u = u0 + x * (1.0 + 0.03 * rng.standard_normal()) + 1e-3 * rng.standard_normal(n + 1)
    u[0] = u0
    v = rng.standard_normal(n + 1)
    v[0] = v0
    return u, v


# v0: into the floor, out of it with the factor 1 − α v0 > 0, and out of it faster than
# 1/α (the factor held at 0: no force at all); u0 above the floor: no damping
@pytest.mark.parametrize("u0, v0", [(-0.01, -3.0), (-0.01, 1.5), (-0.01, 5.0), (0.2, -3.0)])
def test_full_acceleration_matches_the_reference(u0, v0):
    n = 7
    run = Run(damped(**{"rod.N": n}))
    u, v = contact_state(n, u0, v0)
    a = np.zeros(n + 1)
    s, k = np.zeros(n + 1), np.zeros(n + 1)
    status, *_ = rates.full_accel(run.system, run.rod, run.floor, u, v, a, s, k, False)
    assert status == OK
    want = ref.acceleration(u, v, run.system, run.rod, run.floor)
    np.testing.assert_allclose(a, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    sb = ref.floor_stress(u[0], run.floor)
    factor = max(0.0, 1.0 - ALPHA * v0)
    # the floor force is σ_b·max(0, 1 − α v0): the damping part alone, against α = 0
    a0 = np.zeros(n + 1)
    rates.full_accel(run.system._replace(alpha=0.0), run.rod, run.floor, u, v, a0, s, k, False)
    m0 = masses(n)[0]
    assert (a[0] - a0[0]) * m0 == pytest.approx(sb * (factor - 1.0), rel=1e-10, abs=1e-9)
    # its power is never negative
    rate = rates.floor_dissipation_rate(run.system, sb, v0)
    assert rate == pytest.approx(-sb * (factor - 1.0) * v0, rel=1e-12, abs=0)
    assert rate >= 0.0


def test_energy_step_solves_the_reference_equations_and_balances_exactly():
    """One ``energy`` step into the floor against the NumPy statement of the damped
    discrete-gradient step, and its energy change against the dissipation it reports."""
    cfg = damped(**{"rod.N": 12, "rod.mu": 0.5, "initial.height": 0.0,
                    "initial.velocity": -2.0, "time.t_end": 0.004, "time.dt": 2e-3,
                    "time.integrator": "energy"})
    run = Run(cfg)
    run.start(MemorySink())
    run.advance(MemorySink(), max_steps=1)
    u, v, a = (x.copy() for x in run.arrays.state)
    assert u[0] < 0
    u2, v2, a2 = np.zeros_like(u), np.zeros_like(u), np.zeros_like(u)
    work = np.zeros_like(run.arrays.work)
    dt = 2e-3
    res = EN.step(run.scheme, run.system, run.rod, run.floor, u, v, a, u2, v2, a2, work,
                  np.zeros(2, np.int64), dt)
    assert res.status in (OK, INACCURATE)
    r_u, r_v = ref.discrete_gradient_residual(u, v, u2, v2, dt, run.system, run.rod, run.floor)
    assert np.abs(r_u).max() < 1e-14
    assert np.abs(r_v).max() < 1e-9 * np.abs(masses(12) * (v2 - v)).max()
    e = lambda uu, vv: ref.energies(uu, vv, run.system, run.rod, run.floor)["energy_total"]
    floor_part = res.dissipated - dt * 0.5 * np.sum(np.diff((v + v2) / 2) ** 2) * 12
    assert floor_part > 0                       # the floor took energy in this step
    assert abs(e(u2, v2) - e(u, v) + res.dissipated) < 1e-12 * abs(e(u, v))
    np.testing.assert_allclose(a2, ref.acceleration(u2, v2, run.system, run.rod, run.floor),
                               rtol=0, atol=1e-11 * np.abs(a2).max())


def _balance(result):
    d = result.diagnostics
    e, diss = np.asarray(d["energy_total"]), np.asarray(d["dissipated"])
    return e, diss


@pytest.fixture(scope="module")
def mu100_runs():
    """paper-mu100 with the floor's damping for 2 s on every integrator that takes μ = 100
    under tolerance control (verlet refuses it: ``test_verlet_takes_the_damping``)."""
    return {name: rodjit.simulate(damped(**{"time.integrator": name, "time.t_end": 2.0}))
            for name in NAMES if name != "verlet"}


def _check_balance(name, r, tol):
    assert r.status == "completed", name
    e, diss = _balance(r)
    e0 = e[0]
    drift = np.abs(e + diss - e0).max() / abs(e0)
    assert drift < tol, (name, drift)
    # non-decreasing up to the rounding of a dense output's quadrature of a rate ~0
    assert np.diff(diss).min() >= -1e-15 * abs(e0), name
    return diss


def test_every_integrator_balances_its_energy(mu100_runs):
    """E + dissipated = E0 within 1e-6 of E0 over paper-mu100's first 2 s (to rounding for
    ``energy``), the dissipated energy never decreasing, and the floor's share of it
    there: more is dissipated than with α = 0."""
    undamped = rodjit.simulate(rodjit.load_preset("paper-mu100").override(
        {"time.integrator": "energy", "time.t_end": 0.6}))
    for name, r in mu100_runs.items():
        diss = _check_balance(name, r, 1e-11 if name == "energy" else 1e-6)
        t = np.asarray(r.diagnostics["t"])
        i = np.searchsorted(t, 0.6)
        d_ref = np.asarray(undamped.diagnostics["dissipated"])[-1]
        assert diss[i] > d_ref, name


def test_integrators_agree_on_the_first_bounce(mu100_runs):
    e1 = {name: r.bounces["restitution"][0] for name, r in mu100_runs.items()}
    ref_e = e1["radau5"]
    for name, value in e1.items():
        assert value == pytest.approx(ref_e, abs=2e-5), (name, e1)
    undamped = rodjit.simulate(rodjit.load_preset("paper-mu100").override({"time.t_end": 0.7}))
    assert ref_e < undamped.bounces["restitution"][0] - 5e-3


def test_verlet_takes_the_damping():
    """verlet (μ ≤ 1) on paper-mu0 with μ = 1: its floor sub-steps keep the balance to its
    own second-order error, as without the damping, and its first bounce is radau5's."""
    over = {"rod.mu": 1.0, "time.t_end": 1.0, "time.rtol": 1e-8, "time.atol": 1e-10}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        v = rodjit.simulate(damped("paper-mu0", **over, **{"time.integrator": "verlet"}))
        r = rodjit.simulate(damped("paper-mu0", **over, **{"time.integrator": "radau5"}))
        v0 = rodjit.simulate(rodjit.load_preset("paper-mu0").override(
            {**over, "time.integrator": "verlet"}))
    e_v0, d_v0 = _balance(v0)
    undamped_drift = np.abs(e_v0 + d_v0 - e_v0[0]).max() / abs(e_v0[0])
    _check_balance("verlet", v, max(3 * undamped_drift, 1e-7))
    assert v.bounces["restitution"][0] == pytest.approx(r.bounces["restitution"][0], abs=1e-4)


def test_dissipated_is_the_integral_of_its_rate():
    """``dissipated`` at the diagnostics rows against the trapezoid integral of the rate of
    MODEL.md §2 (viscous 2R and the floor's power σ_b min(1, α v0) v0, from the NumPy
    reference) over snapshots 20 µs apart through the first bounce (radau5, tight)."""
    dt_out = 2e-5
    cfg = damped(**{"time.t_end": 0.56, "time.rtol": 1e-10, "time.atol": 1e-12,
                    "time.integrator": "radau5", "output.snapshot_interval": dt_out,
                    "output.diagnostics_interval": dt_out})
    r = rodjit.simulate(cfg)
    run = Run(cfg)
    u, v = r.u, r.v
    rate = np.array([ref.energies(uu, vv, run.system, run.rod, run.floor)["dissipation_rate"]
                     for uu, vv in zip(u, v)])
    floor_rate = np.array([ref.floor_stress(uu[0], run.floor)
                           * min(1.0, ALPHA * vv[0]) * vv[0] for uu, vv in zip(u, v)])
    assert floor_rate.min() >= 0 and floor_rate.max() > 1.0
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * dt_out)])
    diss = np.asarray(r.diagnostics["dissipated"])
    assert diss.shape == integral.shape
    total = diss[-1]
    assert abs(integral[-1] - total) < 2e-4 * total
    assert np.abs(integral - diss).max() < 2e-4 * total


def test_restitution_falls_as_the_impact_speed_grows():
    """The floor's damping grows with the impact speed: on the elastic paper-mu0 rod the
    first restitution falls from 2 to 4 to 8 m/s, and every one is below the undamped
    floor's."""
    cfg = damped("paper-mu0", **{"time.t_end": 1.0, "rod.N": 5})
    table = rodjit.restitution_curve(cfg, speeds=[2.0, 4.0, 8.0],
                                     compare={"floor.damping": [0.0, ALPHA]},
                                     scheduler="inline", progress=False)
    df = table.to_pandas()
    damped_e = df[df["floor.damping"] == ALPHA].sort_values("initial.impact_speed")
    elastic_e = df[df["floor.damping"] == 0.0].sort_values("initial.impact_speed")
    e = damped_e["restitution_first"].to_numpy()
    assert np.all(np.diff(e) < -0.01), e
    assert np.all(e < elastic_e["restitution_first"].to_numpy() - 0.01)


def test_damping_vanishes_continuously():
    """A floor whose α tends to 0 gives the elastic floor's bounce: the change in the first
    restitution is linear in α (radau5, tight, so that the step errors are far below it)."""
    base = rodjit.load_preset("paper-mu100").override(
        {"time.t_end": 0.7, "time.integrator": "radau5", "time.rtol": 1e-10,
         "time.atol": 1e-12})
    e0 = rodjit.simulate(base).bounces["restitution"][0]
    d = [e0 - rodjit.simulate(base.override({"floor.damping": a})).bounces["restitution"][0]
         for a in (1e-3, 2e-3)]
    assert d[0] > 0
    assert d[1] / d[0] == pytest.approx(2.0, rel=0.01)


@pytest.mark.parametrize("integrator, steps", [("dop853", 1010), ("radau5", 60),
                                               ("energy", 700), ("semi-implicit", 3000)])
def test_a_resumed_run_is_the_uninterrupted_one(integrator, steps):
    """Paused in the first contact and resumed from its checkpoint, a damped run ends bit
    for bit where the uninterrupted one does (no state of the damping is carried between
    steps)."""
    cfg = damped(**{"time.integrator": integrator, "time.t_end": 0.7})
    assert_resume_is_bit_identical(cfg, max_steps=steps)


def test_a_negative_damping_is_refused(tmp_path):
    out = tmp_path / "x.h5"
    p = rodjit_cli("run", "paper-mu0", "--set", "floor.damping=-0.1", "-o", out)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "floor.damping" in lines[0] and ">= 0" in lines[0], p.stderr
    assert not out.exists()


def test_the_first_bounce_converges_in_n():
    """paper-mu100 with the floor's damping: the first restitution on N = 10, 20, 40, 80
    converges at the observed order 2 (docs/damping.md gives the values)."""
    e = [rodjit.simulate(damped(**{"rod.N": n, "time.t_end": 0.7,
                                   "time.integrator": "radau5"})).bounces["restitution"][0]
         for n in (10, 20, 40, 80)]
    d = np.diff(e)
    orders = np.log2(np.abs(d[:-1] / d[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.1), (e, orders)


@pytest.mark.slow
def test_the_gpu_engine_gives_the_cpu_columns():
    from conftest import simulated_sweeps

    got = simulated_sweeps(
        "cfg = rodjit.load_preset('paper-mu100').override({'time.t_end': 0.6})",
        {"floor.damping": [0.1, 0.3]}, ("restitution_first", "contact_time_first", "steps"))
    for name, (gpu, cpu) in got.items():
        assert gpu == cpu, name


# ---- calibration: the floor's damping told apart from the rod's viscosity ----------------
CAL_BASE = rodjit.load_preset("paper-mu100").override({"time.t_end": 1.0,
                                                       "initial.height": 0.01})
CAL_SPEEDS = (2.0, 3.0, 4.0, 5.0, 6.0, 8.0)
CAL_SIGMA = {"restitution_first": 2e-3, "contact_time_first": 1e-4}
CAL_TRUTH = {"rod.mu": 150.0, "floor.damping": 0.2}
CAL_START = {"rod.mu": 120.0, "floor.damping": 0.1}
CANDIDATES = {"kelvin-voigt": (CAL_BASE, ["rod.mu"], {"rod.mu": 120.0}),
              "kelvin-voigt + hunt-crossley": (CAL_BASE, list(CAL_TRUTH), CAL_START)}


def _table(truth, rng):
    """A synthetic table (named so: made by rodjit) of drops at CAL_SPEEDS with Gaussian
    errors of a drop test."""
    from rodjit.analysis.evaluate import evaluate
    from test_calibration import _noisy

    exact = evaluate([CAL_BASE.override({**truth, "initial.impact_speed": v})
                      for v in CAL_SPEEDS], scheduler="inline", columns=list(CAL_SIGMA))
    return _noisy(exact, rng, CAL_SPEEDS, CAL_SIGMA)


def test_the_law_comparison_names_the_law_that_made_the_table():
    """A table made with the floor's damping is the damped floor's (ΔAIC > 100, α and μ
    recovered within their 95 % intervals); one made without it is the rod's viscosity's
    (the damped candidate's α is 0 within its error and it loses on its extra parameter)."""
    from rodjit.analysis import compare_laws

    rng = np.random.default_rng(7)
    damped_table = compare_laws(_table(CAL_TRUTH, rng), CANDIDATES, scheduler="inline")
    assert damped_table.best == "kelvin-voigt + hunt-crossley", damped_table
    assert damped_table.aic("kelvin-voigt") - damped_table.aic(damped_table.best) > 100
    for key, (lo, hi) in damped_table.fits[damped_table.best].intervals(0.95).items():
        assert lo <= CAL_TRUTH[key] <= hi, (key, lo, hi)
    viscous_table = compare_laws(_table({"rod.mu": 150.0}, rng), CANDIDATES,
                                 scheduler="inline")
    assert viscous_table.best == "kelvin-voigt", viscous_table
    both = viscous_table.fits["kelvin-voigt + hunt-crossley"]
    alpha, err = both.values[1], both.errors[1]
    assert abs(alpha) < 3 * err


@pytest.mark.slow
def test_the_damping_intervals_cover_the_truth():
    """Over 200 noisy tables the 95 % intervals of (μ, α) contain the truth at a rate inside
    the binomial acceptance band around 95 %."""
    from rodjit.analysis import fit_table
    from test_calibration import _binomial_band

    rng = np.random.default_rng(2026)
    draws = 200
    hits = {k: 0 for k in CAL_TRUTH}
    for _ in range(draws):
        f = fit_table(list(CAL_TRUTH), _table(CAL_TRUTH, rng), CAL_BASE, start=CAL_START,
                      scheduler="inline")
        assert f.converged
        for key, (lo, hi) in f.intervals(0.95).items():
            hits[key] += lo <= CAL_TRUTH[key] <= hi
    lo, hi = _binomial_band(draws)
    for key, k in hits.items():
        assert lo <= k <= hi, (key, k, (lo, hi))
