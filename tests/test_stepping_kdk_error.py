"""The kick–drift–kick schemes' local error estimate and tolerance control.

The estimate has a part for the heights, dt²/6·|a⁺ − a|, the leading term dt³/6·ȧ of the
verlet step's local error in u, and one for the velocities, dt/6·|a⁺ − a − dt·ȧ₀|, the
leading term dt³/12·ä of its local error in v (``kdk``'s docstring derives both): on a
smooth flight each is O(dt³) and matches the true local error (from a converged SciPy
solution of the NumPy right-hand side) with constant 1 as dt → 0, and the step's ratio is
the larger of the two in the one error norm.
"""
from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import rodjit
from rodjit.driver.run import Run
from rodjit.kernels.forces import INACCURATE, OK
from rodjit.kernels.rates import jerk
from rodjit.model import reference as ref
from rodjit.records.result import MemorySink
from rodjit.stepping import control
from rodjit.stepping.integrators import kdk


def _flight(integrator, mu=0.0, gamma=0.0):
    cfg = rodjit.Config().override({
        "rod.N": 8, "rod.mu": mu, "rod.gamma": gamma, "initial.height": 3.0,
        "initial.velocity": 0.5, "initial.strain": 0.05, "time.integrator": integrator,
        "time.t_end": 1.0})
    run = Run(cfg)
    n1 = cfg.rod.N + 1
    x = np.linspace(0.0, 1.0, n1)
    u = run.arrays.state[0]
    u += 0.02 * np.sin(np.pi * x)          # a non-uniform strain: internal motion
    run.arrays.state[1] += 0.3 * np.cos(2 * np.pi * x)
    run.start(MemorySink())
    return run


def _one_step(run, scheme, dt):
    u, v, a = (r.copy() for r in run.arrays.state)
    u2, v2, a2 = np.zeros_like(u), np.zeros_like(u), np.zeros_like(u)
    work = np.zeros_like(run.arrays.work)
    r = kdk.step(scheme, run.system, run.rod, run.floor, u, v, a, u2, v2, a2, work,
                 np.zeros(4, np.int64), dt)
    return r, u, v, a, u2, v2, a2


def _exact(run, dt):
    """(u, v) of the semi-discrete system after dt from the run's state."""
    n1 = run.arrays.state.shape[1]
    y0 = np.concatenate([run.arrays.state[0], run.arrays.state[1]])
    sol = solve_ivp(lambda t, y: ref.rhs(t, y, run.system, run.rod, run.floor), (0.0, dt),
                    y0, method="DOP853", rtol=1e-13, atol=1e-15)
    return sol.y[:n1, -1], sol.y[n1:, -1]


def _kick_jerk(run, scheme, u, v):
    """ȧ₀ of the kick acceleration at (u, v) (no viscous term; bending where the kicks
    have it)."""
    ad, k, strains = (np.zeros_like(u) for _ in range(3))
    jerk(run.system, run.rod, run.floor, u, v, np.zeros_like(u), ad, k, strains,
         kdk.stages(scheme).kick_bending, False)
    return ad


def _estimates(dt, a, a2, ad):
    """The NumPy reference of the two parts: heights dt²/6·|a⁺ − a|, velocities
    dt/6·|a⁺ − a − dt·ȧ₀|."""
    return dt * dt / 6.0 * np.abs(a2 - a), dt / 6.0 * np.abs(a2 - a - dt * ad)


@pytest.mark.parametrize("integrator", ["verlet", "semi-implicit"])
def test_estimate_is_the_leading_local_error_on_a_smooth_flight(integrator):
    run = _flight(integrator)
    scheme = run.scheme._replace(tolerance=True, rtol=0.0, atol=1.0)   # scales: 1
    est, true = {"u": [], "v": []}, {"u": [], "v": []}
    for dt in (2.5e-4, 1.25e-4, 6.25e-5, 3.125e-5):
        r, u, v, a, u2, v2, a2 = _one_step(run, scheme, dt)
        assert r.status in (OK, INACCURATE)
        ad = _kick_jerk(run, scheme, u, v)
        eu, ev = _estimates(dt, a, a2, ad)
        ratio = kdk._error_ratio(scheme, u, u2, v, v2, a, a2, ad, dt)
        assert ratio == pytest.approx(max(eu.max(), ev.max() / control.VELOCITY_SCALE),
                                      rel=1e-12)
        ue, ve = _exact(run, dt)
        est["u"].append(eu.max())
        est["v"].append(ev.max())
        true["u"].append(np.abs(u2 - ue).max())
        true["v"].append(np.abs(v2 - ve).max())
    for part in ("u", "v"):
        e, t = np.array(est[part]), np.array(true[part])
        assert np.all(np.abs(np.log2(e[:-1] / e[1:]) - 3.0) < 0.15), (part, e)
        assert np.all(np.abs(np.log2(t[:-1] / t[1:]) - 3.0) < 0.2), (part, t)
        assert abs(e[-1] / t[-1] - 1.0) < 0.05, (part, e / t)   # the expected constant


@pytest.mark.parametrize("integrator", ["verlet", "semi-implicit"])
def test_a_trial_within_tolerance_in_heights_is_rejected_on_its_velocities(integrator):
    """The compiled step measures both parts in the one norm: with the heights' part at
    half the tolerance and the velocities' above it, the trial is rejected and its ratio is
    the velocities' part, per unit step."""
    run = _flight(integrator)
    dt = 2.5e-4
    u, v, a, u2, v2, a2 = _one_step(run, run.scheme._replace(tolerance=True), dt)[1:]
    eu, ev = _estimates(dt, a, a2, _kick_jerk(run, run.scheme, u, v))
    unit = control.ERROR_TIME / dt                   # control.per_unit_step's factor
    atol = 2.0 * unit * eu.max()                     # the heights' part: 1/2
    velocities = unit * ev.max() / (atol * control.VELOCITY_SCALE)
    assert velocities > 2.0, velocities
    r = _one_step(run, run.scheme._replace(tolerance=True, rtol=0.0, atol=atol), dt)[0]
    assert r.status == INACCURATE
    assert r.value == pytest.approx(velocities, rel=1e-9)


def test_a_step_over_the_tolerance_is_rejected_with_a_shorter_suggestion():
    run = _flight("verlet")
    scheme = run.scheme._replace(tolerance=True, rtol=1e-10, atol=1e-12)
    r = _one_step(run, scheme, 1e-3)[0]
    assert r.status == INACCURATE and r.value > 1.0
    assert 0.0 < r.dt_suggest < 1e-3
    r2 = _one_step(run, scheme, r.dt_suggest)[0]
    assert r2.value < r.value


def test_cfl_control_is_the_plain_fraction_of_the_stability_limit():
    """time.control = "cfl" never rejects for accuracy and suggests cfl × the limit."""
    run = _flight("verlet")
    a = _one_step(run, run.scheme._replace(tolerance=False, cfl=0.05), 1e-3)[0]
    b = _one_step(run, run.scheme._replace(tolerance=False, cfl=0.1), 1e-3)[0]
    assert a.status == b.status == OK
    assert b.dt_suggest == pytest.approx(2.0 * a.dt_suggest)


@pytest.mark.parametrize("integrator", ["verlet", "semi-implicit"])
def test_tighter_tolerance_gives_a_smaller_first_bounce_error(integrator):
    base = rodjit.load_preset("paper-mu100").override({
        "rod.mu": 1.0, "time.integrator": integrator, "time.t_end": 1.2,
        "output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0})
    fine = rodjit.simulate(base.override({"time.rtol": 1e-9, "time.atol": 1e-12}))
    errs, steps = [], []
    for rtol in (1e-4, 1e-6):
        res = rodjit.simulate(base.override({"time.rtol": rtol, "time.atol": rtol * 1e-3}))
        errs.append(abs(res.bounces["restitution"][0] - fine.bounces["restitution"][0]))
        steps.append(res.stats["steps"])
    assert errs[1] < 0.5 * errs[0] and steps[1] > steps[0], (errs, steps)


def test_config_refuses_an_unknown_control():
    with pytest.raises(ValueError, match="time.control"):
        rodjit.Config().override({"time.control": "fast"})


def test_fixed_steps_leave_the_error_estimate_off():
    """Under fixed steps (time.dt) the tolerances choose nothing: the parameters the loop
    takes have the estimate off whatever time.control says, and adaptive steps keep it."""
    from rodjit.stepping import registry
    for integrator in ("verlet", "semi-implicit"):
        tc = rodjit.Config().override({"time.integrator": integrator,
                                       "time.control": "tolerance"}).time
        assert registry.make_scheme(tc).tolerance
        assert not registry.make_scheme(dataclasses.replace(tc, dt=1e-4)).tolerance


_COUNT_ESTIMATES = """
import json, sys, rodjit
from rodjit.stepping import control
from rodjit.stepping.integrators import kdk
calls = [0]
estimate = kdk._error_ratio
def counted(*args):
    calls[0] += 1
    return estimate(*args)
kdk._error_ratio = counted
r = rodjit.simulate(rodjit.Config().override(json.loads(sys.argv[1])))
print(json.dumps({"calls": calls[0], "steps": r.stats["steps"], "u": r.u_final.tolist()}))
"""


def _plain_python_run(over):
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    proc = subprocess.run([sys.executable, "-c", _COUNT_ESTIMATES, json.dumps(over)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


@pytest.mark.parametrize("integrator", ["verlet", "semi-implicit"])
def test_a_fixed_step_run_never_evaluates_the_error_estimate(integrator):
    """The kernels as plain Python (NUMBA_DISABLE_JIT=1), the estimate counted: a fixed-step
    run under time.control = "tolerance" takes its steps without it (the same steps and bits
    as under "cfl"), an adaptive one evaluates it on every trial."""
    over = {"time.integrator": integrator, "rod.N": 4, "rod.mu": 0.5, "initial.height": 0.02,
            "initial.velocity": -1.0, "time.t_end": 0.03, "time.control": "tolerance",
            "output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0}
    fixed = _plain_python_run({**over, "time.dt": 1e-3})
    assert fixed["steps"] == 30 and fixed["calls"] == 0
    adaptive = _plain_python_run(over)
    assert adaptive["calls"] >= adaptive["steps"] > 0
    cfl = rodjit.simulate(rodjit.Config().override({**over, "time.dt": 1e-3,
                                                    "time.control": "cfl"}))
    np.testing.assert_allclose(fixed["u"], cfl.u_final, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("integrator", ["verlet", "semi-implicit"])
def test_fixed_steps_take_the_same_bits_under_either_control(integrator):
    """Compiled: a fixed-step run is the same under time.control = "tolerance" and "cfl",
    bit for bit (snapshots, diagnostics, contact episodes)."""
    over = {"time.integrator": integrator, "rod.N": 12, "rod.mu": 1.0, "time.dt": 2e-4,
            "time.t_end": 0.6, "output.snapshot_interval": 0.05}
    a = rodjit.simulate(rodjit.Config().override({**over, "time.control": "tolerance"}))
    b = rodjit.simulate(rodjit.Config().override({**over, "time.control": "cfl"}))
    assert a.stats["steps"] == b.stats["steps"] == 3000
    assert a.episodes["t_start"].size > 0
    for x, y in [(a.u, b.u), (a.v, b.v), (a.episodes["t_end"], b.episodes["t_end"]),
                 *((a.diagnostics[k], b.diagnostics[k]) for k in a.diagnostics)]:
        assert np.array_equal(x, y, equal_nan=True)
