"""The discrete-gradient integrator (``time.integrator = "energy"``).

Checked against: the discrete energy identity at every step of the real loop (μ = 0 and
μ > 0, 100 bounces), the NumPy spec of the step equations, 50-digit energies, exact free
fall, second-order convergence in dt and agreement with verlet/semi-implicit, admissibility
and energy exactness at 100× the explicit stability limit, and bit-identical resume.
"""
import json
import math
import os
import subprocess
import sys

import mpmath as mp
import numba
import numpy as np
import pytest

import rodjit
from conftest import assert_resume_is_bit_identical
from rodjit.records.result import MemorySink
from rodjit.driver.run import Run
from rodjit.kernels.forces import INACCURATE, NO_CONVERGENCE, OK, energies
from rodjit.model import reference as ref
from rodjit.model.reference import rhs as ref_rhs
from rodjit.model.system import masses
from rodjit.stepping import control as CT
from rodjit.kernels import rates
from rodjit.stepping.integrators import energy as EN
from rodjit.stepping import layout as L
from rodjit.stepping.loop import advance

QUIET = {"output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0}


def energy_config(**over):
    return rodjit.Config().override({"time.integrator": "energy", **QUIET, **over})


# ---- the real loop, one step at a time ------------------------------------------------------
@numba.njit
def _record(scheme, ctrl, system, rod, floor, obs, arrays, out, max_bounces):
    """Call the compiled loop for one step at a time; per step record dt, E before/after,
    the loop's dissipation increment, μ dt Σ h (Δv̄/h)² recomputed from the two states, the
    rounding scale of E, u_0, the bounces so far and t.  Returns the number of steps."""
    state = arrays.state
    work = arrays.work
    clock = arrays.clock
    count = arrays.count
    n = system.n
    h = system.h
    v_old = np.empty(n + 1)
    k = 0
    while k < out.shape[0]:
        ke, st, be, fe, ge, emin, z, w = energies(state[0], state[1], work[1], system, rod,
                                                  floor)
        e0 = ke + st + be + fe + ge
        mag = ke + st + be + abs(fe) + abs(ge)
        t0 = clock[L.T]
        d0 = clock[L.DISSIPATED]
        v_old[:] = state[1]
        code = advance(scheme, ctrl, system, rod, floor, obs, arrays, 1)
        count[L.N_EP] = 0        # drain the event buffers (their rows are not needed)
        count[L.N_BOUNCE] = 0
        if code == L.FAILED:
            return -1
        ke, st, be, fe, ge, emin, z, w = energies(state[0], state[1], work[1], system, rod,
                                                  floor)
        dt = clock[L.T] - t0
        diss = 0.0
        for i in range(n):
            dv = 0.5 * ((v_old[i + 1] + state[1][i + 1]) - (v_old[i] + state[1][i]))
            diss += dv * dv
        out[k, 0] = dt
        out[k, 1] = e0
        out[k, 2] = ke + st + be + fe + ge
        out[k, 3] = clock[L.DISSIPATED] - d0
        out[k, 4] = dt * system.mu * diss / h
        out[k, 5] = max(mag, abs(e0))
        out[k, 6] = state[0][0]
        out[k, 7] = count[L.BOUNCES_TOTAL]
        out[k, 8] = clock[L.T]
        k += 1
        if code == L.DONE or count[L.BOUNCES_TOTAL] >= max_bounces:
            break
    return k


def record_steps(cfg, max_steps, max_bounces=10**9, u0=None, v0=None):
    run = Run(cfg, u0=u0, v0=v0)
    run.start(MemorySink())
    out = np.zeros((max_steps, 9))
    k = _record(*run._args(), run.arrays, out, max_bounces)
    assert k > 0, run.failure_message()
    return run, out[:k]


@pytest.mark.slow
@pytest.mark.parametrize("mu", [0.0, 0.005])
def test_energy_identity_holds_at_every_step_over_many_bounces(mu):
    """E^{n+1} − E^n = −μ dt Σ h ((v̄_{i+1} − v̄_i)/h)² at every accepted step of the real
    loop (crossing refinements, landings, rejections included), and the loop's dissipation
    grows by exactly that sum."""
    # rtol 1e-3: the error per unit step (control.per_unit_step) takes about the steps that
    # rtol 1e-4 took per step; the identity, not the accuracy, is under test
    cfg = energy_config(**{"rod.mu": mu, "time.rtol": 1e-3, "time.t_end": 1000.0})
    run, rec = record_steps(cfg, 2_000_000, max_bounces=100)
    dt, e0, e1, diss, diss_formula, scale, u0, nb, t = rec.T
    # 100 bounces at μ = 0; at μ = 0.005 the rod comes to rest on the floor after 47
    assert nb[-1] >= (100 if mu == 0 else 45)
    assert (u0 < 0).sum() > 1000                       # many steps in contact
    resid = np.abs(e1 - e0 + diss) / scale
    assert resid.max() < 1e-12, resid.max()
    # the loop's increments are the formula, up to the rounding of its running sum (and of
    # dt recovered here as t_{n+1} − t_n)
    total = np.cumsum(diss)
    tol = (1e-14 + 4e-16 * t / dt) * diss_formula + 4e-16 * total
    assert np.all(np.abs(diss - diss_formula) <= tol)
    if mu > 0:
        assert diss.sum() > 0.3 * abs(e0[0])           # a dissipative run, not a no-op
    else:
        assert diss.sum() == 0.0
    assert run.arrays.sstats[0] > 0                           # Newton iterations were counted


def test_energy_identity_with_bending_on_a_stiff_floor():
    """The same per-step identity with γ > 0 (pentadiagonal Newton), viscosity, a finer rod
    and a stiff floor, through 5 bounces."""
    cfg = energy_config(**{"rod.N": 40, "rod.gamma": 1e-3, "rod.mu": 0.02, "time.rtol": 1e-4,
                           "floor.kappa_b": 1e5, "floor.beta": 1e-3, "time.t_end": 100.0})
    run, rec = record_steps(cfg, 2_000_000, max_bounces=5)
    dt, e0, e1, diss, diss_formula, scale, u0, nb, t = rec.T
    assert nb[-1] >= 5 and (u0 < 0).sum() > 100
    resid = np.abs(e1 - e0 + diss) / scale
    assert resid.max() < 1e-12, resid.max()


def test_step_solves_the_discrete_gradient_equations_of_the_numpy_spec():
    """One step in contact, with bending and viscosity, checked against the independent
    NumPy statement of the scheme (rodjit.model.reference.discrete_gradient_residual) and its
    energy change against 50-digit arithmetic."""
    cfg = energy_config(**{"rod.N": 12, "rod.gamma": 0.02, "rod.mu": 0.5, "initial.height": 0.0,
                           "initial.velocity": -2.0, "time.t_end": 0.004, "time.dt": 2e-3})
    run = Run(cfg)
    run.start(MemorySink())
    run.advance(MemorySink(), max_steps=1)             # into the floor
    u, v, a = (x.copy() for x in run.arrays.state)
    assert u[0] < 0
    u2, v2, a2 = np.zeros_like(u), np.zeros_like(u), np.zeros_like(u)
    work = np.zeros_like(run.arrays.work)
    ss = np.zeros(2, np.int64)
    dt = 2e-3
    status, *_, dissipated = EN.step(run.scheme, run.system, run.rod, run.floor, u, v, a,
                                     u2, v2, a2, work, ss, dt)
    assert status in (OK, INACCURATE)                 # a valid state either way
    r_u, r_v = ref.discrete_gradient_residual(u, v, u2, v2, dt, run.system, run.rod, run.floor)
    m = masses(12)
    assert np.abs(r_u).max() < 1e-14
    assert np.abs(r_v).max() < 1e-9 * np.abs(m * (v2 - v)).max()
    # the new state's acceleration (assembled from the stresses of Newton's last
    # evaluation) is the full acceleration of the NumPy spec at (u2, v2), to rounding
    a_ref = ref.rhs(0.0, np.concatenate([u2, v2]), run.system, run.rod, run.floor)[13:]
    assert np.abs(a2 - a_ref).max() <= 1e-12 * np.abs(a_ref).max()
    # the energy balance in 50 digits
    mp.mp.dps = 50
    E = lambda uu, vv: _energy_mp(uu, vv, run)
    vb = [(mp.mpf(x) + mp.mpf(y)) / 2 for x, y in zip(v, v2)]
    n, h = 12, mp.mpf(1) / 12
    d_exact = dt * mp.mpf(0.5) * sum((vb[i + 1] - vb[i]) ** 2 for i in range(n)) / h
    assert abs(E(u2, v2) - E(u, v) + d_exact) < 1e-13 * abs(E(u, v))
    assert abs(dissipated - d_exact) < 1e-14 * d_exact


@pytest.mark.parametrize("gamma, mu, u_bottom, damping", [
    (0.0, 0.0, -0.01, 0.0), (0.0, 100.0, -0.004, 0.0), (0.02, 0.5, -0.01, 0.0),
    (0.0, 0.5, 0.2, 0.0), (0.0, 100.0, -0.004, 0.3), (0.0, 0.0, -0.01, 0.05)])
def test_jerk_is_the_time_derivative_of_the_acceleration(gamma, mu, u_bottom, damping):
    """ȧ (the predictor's and the error estimate's third derivative) against a central
    difference of the NumPy spec's acceleration along the motion, (a(u + δv, v + δa) −
    a(u − δv, v − δa))/2δ, in contact and in flight, with the floor's damping too; and the
    segment strains it leaves."""
    n = 8
    cfg = energy_config(**{"rod.N": n, "rod.gamma": gamma, "rod.mu": mu,
                           "floor.damping": damping})
    run = Run(cfg)
    rng = np.random.default_rng(3)
    x = np.arange(n + 1) / n
    u = u_bottom + x * (1.0 + 0.05 * rng.standard_normal()) + 1e-3 * rng.standard_normal(n + 1)
    v = rng.standard_normal(n + 1)
    acc = lambda uu, vv: ref.acceleration(uu, vv, run.system, run.rod, run.floor)
    a = acc(u, v)
    out, k, strains = np.zeros(n + 1), np.zeros(n + 1), np.zeros(n + 1)
    rates.jerk(run.system, run.rod, run.floor, u, v, a, out, k, strains)
    dl = 1e-6
    fd = (acc(u + dl * v, v + dl * a) - acc(u - dl * v, v - dl * a)) / (2 * dl)
    np.testing.assert_allclose(out, fd, rtol=0, atol=1e-6 * np.abs(fd).max())
    np.testing.assert_array_equal(strains[:n], (u[1:] - u[:-1]) * n - 1.0)


@pytest.mark.parametrize("gamma", [0.0, 0.02])
def test_chord_updates_reach_the_same_root(gamma):
    """Newton's later updates may reuse the first factor (``chord``): a contact step that
    needs several updates lands on the root of the discrete-gradient equations to rounding
    whether it never (chord = 0), by default, or always (chord = 1) reuses it."""
    cfg = energy_config(**{"rod.N": 12, "rod.gamma": gamma, "rod.mu": 100.0,
                           "initial.height": 0.0, "initial.velocity": -2.0,
                           "time.t_end": 0.004, "time.dt": 2e-3})
    run = Run(cfg)
    run.start(MemorySink())
    run.advance(MemorySink(), max_steps=1)             # into the floor
    u, v, a = (x.copy() for x in run.arrays.state)
    assert u[0] < 0
    dt = 1e-3
    ends = {}
    for chord in (0.0, EN.CHORD, 1.0):
        out = [np.zeros_like(u) for _ in range(3)]
        ss = np.zeros(2, np.int64)
        status = EN.step(run.scheme._replace(chord=chord), run.system, run.rod, run.floor,
                         u, v, a, *out, np.zeros_like(run.arrays.work), ss, dt)[0]
        assert status in (OK, INACCURATE) and ss[0] >= 2 and ss[1] == 0
        r_u, r_v = ref.discrete_gradient_residual(u, v, out[0], out[1], dt, run.system,
                                                  run.rod, run.floor)
        assert np.abs(r_u).max() < 1e-14
        assert np.abs(r_v).max() < 1e-9 * np.abs(masses(12) * (out[1] - v)).max()
        ends[chord] = out[0]
    assert run.scheme.chord == EN.CHORD
    for chord in (EN.CHORD, 1.0):
        np.testing.assert_allclose(ends[chord], ends[0.0], rtol=0, atol=1e-14)


def _energy_mp(u, v, run):
    """E_h of MODEL.md §2 in 50 digits, from the literal formulas."""
    n = len(u) - 1
    h = mp.mpf(1) / n
    m = [h / 2 if i in (0, n) else h for i in range(n + 1)]
    kap, kb, be = (mp.mpf(x) for x in (run.rod.kappa, run.floor.kappa_b, run.floor.beta))
    E = sum(mi * mp.mpf(vi) ** 2 / 2 for mi, vi in zip(m, v))
    U = [mp.mpf(x) for x in u]
    for i in range(n):
        e = (U[i + 1] - U[i]) / h - 1
        E += h * kap / 2 * (e**2 / 2 + e / 2 + 1 / (4 * (1 + e) ** 2) - mp.mpf(1) / 4)
    for i in range(1, n):
        k = (U[i + 1] - 2 * U[i] + U[i - 1]) / h**2
        E += mp.mpf(run.system.gamma) / 2 * h * k**2
    if U[0] <= 0:
        E -= kb * (-(be**3) / (2 * (U[0] + be) ** 2) - U[0] + be / 2)
    E -= mp.mpf(run.system.g) * sum(mi * ui for mi, ui in zip(m, U))
    return E


@pytest.mark.parametrize("mu, gamma", [(0.0, 0.0), (0.05, 1e-4)])
def test_free_flight_is_exact_and_takes_long_steps(mu, gamma):
    """No contact: w = w0 + g t and z = z0 + w0 t + g t²/2 (MODEL.md §4) to rounding, with
    internal vibration (the free-free mode 1, u_x = 1 − Aπ sin πx vanishes at the ends); and
    the accuracy-controlled steps grow far past the explicit stability limit 2/ω."""
    n = 1000
    x = np.arange(n + 1) / n
    u0 = 50.0 + x + 0.002 * np.cos(np.pi * x)
    v0 = np.full(n + 1, 1.5)
    cfg = energy_config(**{"rod.N": n, "rod.gamma": gamma, "rod.mu": mu, "time.t_end": 0.5,
                           "time.rtol": 1e-3, "output.diagnostics_interval": 0.1})
    res = rodjit.simulate(cfg, u0=u0, v0=v0)
    d = res.diagnostics
    m = masses(n)
    z0, w0, g = m @ u0, m @ v0, -9.81
    t = d["t"]
    np.testing.assert_allclose(d["cm_velocity"], w0 + g * t, rtol=0, atol=1e-13)
    np.testing.assert_allclose(d["cm_height"], z0 + w0 * t + 0.5 * g * t**2, rtol=0, atol=1e-12)
    _, rec = record_steps(cfg, 100_000, u0=u0, v0=v0)
    om2 = 4 * 1.25 * 100.0 * n**2 + 16 * gamma * n**4       # Gershgorin bound, as in accel
    limit = 2 / math.sqrt(om2)
    assert rec[:, 0].max() > 100 * limit and np.median(rec[:, 0]) > 15 * limit


def _fixed(integrator, dt, over):
    cfg = rodjit.Config().override({"time.integrator": integrator, "time.dt": dt, **QUIET,
                                    **over})
    res = rodjit.simulate(cfg)
    return np.concatenate([res.u_final, res.v_final])


SMOOTH = {"rod.N": 8, "rod.gamma": 0.001, "rod.mu": 0.3, "gravity.g": 0.0,
          "initial.height": 1.0, "initial.strain": 0.3, "initial.velocity": 0.0,
          "time.t_end": 0.4}
CONTACT = {"rod.N": 8, "initial.height": 0.02, "initial.velocity": -1.0, "rod.mu": 0.1,
           "floor.kappa_b": 100.0, "floor.beta": 0.2, "time.t_end": 0.25}


@pytest.mark.parametrize("case", [SMOOTH, CONTACT], ids=["smooth", "contact"])
def test_second_order_in_dt(case):
    """Fixed steps dt, dt/2, dt/4, dt/8 against dt/128: error ratios ≈ 4.  The contact
    case enters and leaves the floor inside steps (the kink of σ_b' at u_0 = 0): the order
    stays 2."""
    dts = [2e-3 / 2**k for k in range(4)] if case is SMOOTH else [1e-3 / 2**k for k in range(4)]
    ref_y = _fixed("energy", dts[0] / 128, case)
    errs = [np.abs(_fixed("energy", dt, case) - ref_y).max() for dt in dts]
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(orders - 2.0) < 0.15), orders


def test_agrees_with_verlet_and_semi_implicit_in_the_limit():
    """The three integrators approach the same semi-discrete solution: their differences at
    a common dt shrink at second order."""
    diffs = {"verlet": [], "semi-implicit": []}
    for dt in (1e-3, 5e-4, 2.5e-4):
        e = _fixed("energy", dt, SMOOTH)
        for other in diffs:
            diffs[other].append(np.abs(_fixed(other, dt, SMOOTH) - e).max())
    for other, d in diffs.items():
        d = np.array(d)
        assert d[-1] < 2e-4, (other, d)
        assert np.all(d[:-1] / d[1:] > 3.5), (other, d)


def test_stiff_floor_at_100x_the_explicit_limit():
    """Fine rod, stiff floor, fixed dt = 100 × the explicit limit 2/ω (ω² the stiffness
    bound of ``accel`` at first contact): the energy step stays admissible and conserves
    energy through the bounce; verlet and semi-implicit fail with their clear error."""
    n, kb, beta = 200, 1e5, 1e-3
    om2 = 4 * 1.25 * 100.0 * n**2 + 2 * 3 * kb / beta * n
    dt = 100 * 2 / math.sqrt(om2)
    over = {"rod.N": n, "floor.kappa_b": kb, "floor.beta": beta, "time.t_end": 0.75,
            "time.dt": dt}
    cfg = energy_config(**over, **{"output.diagnostics_interval": 10 * dt})
    res = rodjit.simulate(cfg)
    d = res.diagnostics
    assert res.stats["rejected_steps"] == 0            # fixed steps are never rejected
    assert d["u_bottom"].min() < -2e-6                 # it did hit the floor
    assert d["min_strain"].min() > -0.9 and d["u_bottom"].min() > -beta
    assert res.n_bounces == 1 and 0.5 < res.bounces["restitution"][0] < 1.0
    assert res.energy_error() < 1e-10
    assert res.stats["newton_iterations"] > res.stats["steps"]
    for explicit in ("verlet", "semi-implicit"):
        with pytest.raises(rodjit.SimulationError, match=r"fixed step time\.dt = .* failed"):
            rodjit.simulate(cfg.override({"time.integrator": explicit}))


def test_adaptive_error_follows_the_tolerance_on_the_paper_mu100_run():
    """The paper's second setting (N = 5, μ = 100: impacts, release, settling on the floor),
    snapshots of the first second against SciPy's Radau on the NumPy right-hand side at
    1e-11 (the measure of benchmarks/bench_scipy.py): the error of the error-controlled
    step follows the tolerance (local error O(dt³) held per unit step, control.per_unit_step:
    ×100 in tol is ×100 in error; held per step it was ×21.5, tol^(2/3)) and is below 1e-4
    at tol = 1e-8; the snapshots land on their times."""
    from scipy.integrate import solve_ivp
    from rodjit.model.system import build_system, initial_state
    from rodjit.presets import load_preset
    cfg = load_preset("paper-mu100").override({"time.integrator": "energy", "time.t_end": 1.0,
                                               "output.diagnostics_interval": 0.0})
    system, rod, floor = build_system(cfg)
    u0, v0 = initial_state(cfg)
    t = cfg.output.snapshot_interval * np.arange(201)
    ref = solve_ivp(ref_rhs, (0.0, 1.0), np.concatenate([u0, v0]), method="Radau",
                    rtol=1e-11, atol=1e-11, t_eval=t, args=(system, rod, floor)).y
    vscale = math.sqrt(2 * 9.81 * cfg.initial.height)
    errs = []
    for tol in (1e-4, 1e-6, 1e-8):
        res = rodjit.simulate(cfg.override({"time.rtol": tol, "time.atol": tol}))
        np.testing.assert_allclose(res.t, t, rtol=0, atol=1e-12)
        errs.append(max(np.abs(res.u.T - ref[:6]).max(), np.abs(res.v.T - ref[6:]).max() / vscale))
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 50) & (ratios < 200)), errs
    assert errs[-1] < 1e-4, errs


def test_adaptive_steps_shrink_in_contact_and_grow_in_flight():
    """Accuracy-controlled steps: far above the explicit limit in the first free fall,
    far below it in contact with a stiff floor."""
    n = 50
    cfg = energy_config(**{"rod.N": n, "floor.kappa_b": 1e5, "floor.beta": 1e-3,
                           "time.t_end": 0.6, "time.rtol": 1e-4})
    run, rec = record_steps(cfg, 500_000)
    dt, u0 = rec[:, 0], rec[:, 6]
    om2 = 4 * 1.25 * 100.0 * n**2
    assert dt[:20].max() > 20 * 2 / math.sqrt(om2)
    assert np.median(dt[u0 < 0]) < 0.01 * dt[:20].max()
    assert run.rejected > 0


def test_step_factor_is_the_clamped_inverse_cube_root():
    """The step-size factor SAFETY·err^(−1/3) in [FAC_MIN, FAC_MAX], without libm's cbrt:
    < 1e-7 relative over the unclamped range, the bounds outside it (0 included)."""
    errs = np.concatenate([[0.0, 1e-300, 1e-9, CT.ERR_FAC_MAX, CT.ERR_FAC_MIN, 1e300],
                           np.geomspace(CT.ERR_FAC_MAX / 10, CT.ERR_FAC_MIN * 10, 5001)])
    got = np.array([CT.step_factor(e) for e in errs])
    with np.errstate(divide="ignore"):
        want = np.clip(CT.SAFETY / np.cbrt(errs), CT.FAC_MIN, CT.FAC_MAX)
    assert np.abs(got / want - 1.0).max() < 1e-7
    assert got[0] == CT.FAC_MAX and got[-1] == want[-1]
    inner = (errs > CT.ERR_FAC_MAX) & (errs < CT.ERR_FAC_MIN)
    assert inner.sum() > 3000 and np.all(np.diff(got[6:]) <= 0)     # monotone in err


def test_resume_is_bit_identical():
    cfg = energy_config(**{"rod.N": 10, "rod.mu": 0.2, "time.t_end": 0.9, "time.rtol": 1e-5})
    assert_resume_is_bit_identical(cfg, max_steps=777)


def test_newton_failure_is_reported_and_shrinks_the_step():
    """No convergence within max_newton returns NO_CONVERGENCE and counts a failure; the
    loop's message for it (and for an unmet error estimate) names the cause."""
    cfg = energy_config(**{"rod.N": 20, "initial.height": 0.0, "initial.velocity": -3.0,
                           "floor.kappa_b": 1e6, "floor.beta": 1e-3})
    run = Run(cfg)
    run.start(MemorySink())
    u, v, a = run.arrays.state
    out = [np.zeros_like(u) for _ in range(3)]
    ss = np.zeros(2, np.int64)
    status = EN.step(run.scheme._replace(max_newton=1), run.system, run.rod, run.floor,
                     u, v, a, *out, np.zeros_like(run.arrays.work), ss, 1e-2)[0]
    assert status == NO_CONVERGENCE and ss[1] == 1
    status = EN.step(run.scheme, run.system, run.rod, run.floor, u, v, a, *out,
                     np.zeros_like(run.arrays.work), ss, 1e-2)[0]
    assert status == INACCURATE                     # converged, but far too inaccurate
    assert out[0][0] > -1e-3 and np.all(np.diff(out[0]) > 0)
    run.arrays.fail[:] = [NO_CONVERGENCE, 0.1, 0.5, 0, 1e-3]
    assert "Newton iteration did not converge" in run.failure_message()
    run.arrays.fail[:] = [INACCURATE, 0.1, 7.0, 0, 1e-3]
    assert "error estimate is 7" in run.failure_message()


def test_unknown_integrator_still_rejected():
    from rodjit.stepping.schemes import make_scheme
    with pytest.raises(ValueError, match="not available"):
        make_scheme(type("T", (), {"integrator": "nope"})())


_NOJIT = """
import json, sys, rodjit
cfg = rodjit.Config().override(json.loads(sys.argv[1]))
r = rodjit.simulate(cfg)
print(json.dumps({"u": r.u_final.tolist(), "v": r.v_final.tolist(), "steps": r.stats["steps"],
                  "newton": r.stats["newton_iterations"]}))
"""


def test_pure_python_path_matches_compiled():
    """The same small run with NUMBA_DISABLE_JIT=1 (the kernels as plain Python)."""
    over = {"time.integrator": "energy", "rod.N": 3, "rod.gamma": 0.01, "rod.mu": 0.5,
            "initial.height": 0.005, "initial.velocity": -1.0, "time.t_end": 0.02,
            "time.rtol": 1e-4, **QUIET}
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    proc = subprocess.run([sys.executable, "-c", _NOJIT, json.dumps(over)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    plain = json.loads(proc.stdout)
    res = rodjit.simulate(rodjit.Config().override(over))
    assert plain["steps"] == res.stats["steps"] and plain["newton"] > 0
    np.testing.assert_allclose(plain["u"], res.u_final, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(plain["v"], res.v_final, rtol=1e-10, atol=1e-12)
