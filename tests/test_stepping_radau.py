"""The Radau IIA step (``time.integrator = "radau5"``).

Checked: the method's constants (collocation matrix, its transformation, the error
weights), the transformed linear solves against a dense (λI − J)⁻¹ from the NumPy
reference right-hand side, convergence order 5 in fixed steps in flight, in contact and
with stiff viscosity (μ dt λ_max = 2.5 … 10: no order reduction on this autonomous
system), agreement with ``dop853`` and ``energy`` on the paper's μ = 100 run, the energy
balance E + dissipated = E₀, admissibility through a hard impact, the full acceleration
left for the next step, resume bit for bit, and the configuration and command line.
"""
import numpy as np
import pytest
from numpy.polynomial import polynomial as Pl

import rodjit
from conftest import assert_resume_is_bit_identical, trial_step
from rodjit.cli import main
from rodjit.driver.run import Run, SimulationError
from rodjit.kernels.forces import BAD_FLOOR, BAD_STRAIN, NON_FINITE, NO_CONVERGENCE, OK
from rodjit.model import reference
from rodjit.records.result import MemorySink
from rodjit.kernels.rates import full_accel
from rodjit.stepping import registry
from rodjit.stepping.integrators import radau

QUIET = {"output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0}
TIGHT = {"time.rtol": 1e-13, "time.atol": 1e-15}   # Newton to rounding under fixed steps
FLIGHT = {"rod.N": 5, "initial.height": 3.0, "initial.strain": 0.1, "initial.velocity": 0.0,
          "time.t_end": 0.5}
CONTACT = {"rod.N": 8, "initial.height": -0.05, "initial.velocity": -1.0, "rod.mu": 0.1,
           "floor.kappa_b": 10.0, "floor.beta": 1.0, "time.t_end": 0.1}
# stiff viscosity: the largest viscous rate 4μ/h² = 1e4 /s, so μ dt λ_max = 10 … 2.5
STIFF = {"rod.N": 5, "rod.mu": 100.0, "initial.height": 3.0, "initial.strain": 0.1,
         "initial.velocity": 0.0, "time.t_end": 8e-3}
DTS = {"flight": (2e-3, FLIGHT), "contact": (1e-2, CONTACT), "stiff": (1e-3, STIFF)}


def _cfg(integrator, over):
    return rodjit.Config().override({"time.integrator": integrator, **QUIET, **over})


def _fixed(integrator, dt, over):
    res = rodjit.simulate(_cfg(integrator, {**TIGHT, "time.dt": dt, **over}))
    return np.concatenate([res.u_final, res.v_final])


def _radau_matrix():
    """a_ij = ∫_0^{c_i} l_j(s) ds, l_j the Lagrange polynomials on the nodes c."""
    c = radau.C
    a = np.zeros((3, 3))
    for j in range(3):
        others = [c[k] for k in range(3) if k != j]
        lj = Pl.polyfromroots(others) / np.prod([c[j] - o for o in others])
        ij = Pl.polyint(lj)
        a[:, j] = Pl.polyval(c, ij)
    return a


def test_registry_line():
    entry = registry.get("radau5")
    assert registry.load(entry)[1] is radau.Radau5
    assert entry.work_rows == radau.WORK_ROWS
    assert entry.counters == ("newton_iterations", "newton_failures")
    assert entry.gap_control is False
    s = registry.make_scheme(rodjit.Config().override(
        {"time.integrator": "radau5", "time.rtol": 1e-7, "time.atol": 1e-11}).time)
    assert s == radau.Radau5(1e-7, 1e-11)
    # the sstats layout (stored in checkpoints) is the one the energy step made
    assert registry.SCHEME_STATS == ("newton_iterations", "newton_failures")


def test_constants_are_the_radau_iia_method():
    a = _radau_matrix()
    c = radau.C
    np.testing.assert_allclose(a.sum(axis=1), c, atol=1e-15)
    np.testing.assert_allclose(a[2], radau.B, atol=1e-15)
    for k in range(5):      # order 5: Σ b c^k = 1/(k+1) for k ≤ 4
        assert abs(radau.B @ c**k - 1.0 / (k + 1)) < 1e-14
    # T⁻¹a⁻¹T = diag(μ_r, [[α, β], [−β, α]]): the complex pair solved as one system with
    # α − iβ (radau module docstring)
    lam = np.array([[radau.MU_REAL, 0, 0], [0, radau.ALPHA, radau.BETA],
                    [0, -radau.BETA, radau.ALPHA]])
    np.testing.assert_allclose(radau.T @ radau.TI, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(radau.T @ lam @ radau.TI, np.linalg.inv(a), atol=1e-12)
    # the error estimate f₀ + Σ e_i Z_i/dt vanishes for y' = 1, t, t² (Z_i = c_i^{k+1}/(k+1))
    assert abs(1.0 + radau.E @ c) < 1e-14
    assert abs(radau.E @ c**2) < 1e-13 and abs(radau.E @ c**3) < 1e-13


def _dense_jacobian(u, v, system, rod, floor):
    y = np.concatenate([u, v])
    n = y.size
    J = np.zeros((n, n))
    for k in range(n):
        d = 1e-7 * max(1.0, abs(y[k]))
        yp, ym = y.copy(), y.copy()
        yp[k] += d
        ym[k] -= d
        J[:, k] = (reference.rhs(0, yp, system, rod, floor)
                   - reference.rhs(0, ym, system, rod, floor)) / (2 * d)
    return J


@pytest.mark.parametrize("gamma, damping", [(0.0, 0.0), (1e-3, 0.0), (0.0, 0.3)])
def test_transformed_solves_invert_lambda_minus_the_jacobian(gamma, damping):
    """The banded real and complex solves give (λI − J)⁻¹r for J from central differences
    of the NumPy reference right-hand side (in contact, viscous, with and without bending,
    with the floor's damping: its derivatives in u₀ and v₀)."""
    cfg = _cfg("radau5", {"rod.N": 7, "rod.mu": 0.7, "rod.gamma": gamma,
                          "floor.damping": damping,
                          "initial.height": -0.01, "initial.velocity": -0.5,
                          "initial.strain": 0.05})
    run = Run(cfg)
    run.start(MemorySink())
    scheme, _, system, rod, floor, _ = run._args()
    u, v = run.arrays.state[0].copy(), run.arrays.state[1].copy()
    u[3] += 0.01
    J = _dense_jacobian(u, v, system, rod, floor)
    n1 = u.size
    work = np.zeros((radau.WORK_ROWS, n1))
    dt = 3e-3
    qb = radau.hessian_diagonal(system, rod, floor, u, v, work[radau.FP])
    rng = np.random.default_rng(1)
    lr = radau.MU_REAL / dt
    radau.real_matrix(system, work, lr, qb)
    r = rng.standard_normal(2 * n1)
    ru, rv = r[:n1].copy(), r[n1:].copy()
    radau.solve_real(system, work, lr, ru, rv, True)
    want = np.linalg.solve(lr * np.eye(2 * n1) - J, r)
    np.testing.assert_allclose(np.concatenate([ru, rv]), want, rtol=1e-6, atol=1e-9)
    ru, rv = r[:n1].copy(), r[n1:].copy()   # again from the stored factor
    radau.solve_real(system, work, lr, ru, rv, False)
    np.testing.assert_allclose(np.concatenate([ru, rv]), want, rtol=1e-6, atol=1e-9)
    cr, ci = radau.ALPHA / dt, -radau.BETA / dt
    radau.complex_matrix(system, work, cr, ci, qb)
    rc = r + 1j * rng.standard_normal(2 * n1)
    rur, rui = rc[:n1].real.copy(), rc[:n1].imag.copy()
    rvr, rvi = rc[n1:].real.copy(), rc[n1:].imag.copy()
    radau.solve_complex(system, work, cr, ci, rur, rui, rvr, rvi)
    want = np.linalg.solve((cr + 1j * ci) * np.eye(2 * n1) - J, rc)
    got = np.concatenate([rur + 1j * rui, rvr + 1j * rvi])
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("case", sorted(DTS))
def test_fifth_order_in_dt(case):
    """Order 5 ± 0.2 in flight, in contact and with stiff viscosity (μ dt·4/h² = 10, 5,
    2.5: the stiff modes are damped L-stably and the autonomous system shows no order
    reduction to the stage order 3).  Reference: dop853 (non-stiff) or radau5 at dt/64."""
    dt0, over = DTS[case]
    dts = [dt0 / 2**k for k in range(3)]
    if case == "stiff":
        ref = _fixed("radau5", dts[-1] / 64, over)
    else:
        ref = _fixed("dop853", dts[-1] / 8, over)
    errs = np.array([np.abs(_fixed("radau5", dt, over) - ref).max() for dt in dts])
    orders = np.log2(errs[:-1] / errs[1:])
    assert errs[-1] > 3e-12, errs
    assert np.all(np.abs(orders - 5.0) <= 0.2), (orders, errs)


def _paper(integrator, tol, **over):
    cfg = rodjit.presets.load_preset("paper-mu100").override(
        {"time.integrator": integrator, "time.rtol": tol, "time.atol": tol,
         "time.t_end": 1.0, "output.snapshot_interval": 0.01,
         "output.diagnostics_interval": 0.01, **over})
    return rodjit.simulate(cfg)


def _final(res):
    """The snapshots along the run (the rod is at rest on the floor by t = 1)."""
    return np.concatenate([res.u, res.v], axis=1)


def test_agrees_with_dop853_and_energy_on_the_paper_mu100_run():
    """The paper's μ = 100 rod over its first second (impact, contact, settling), at every
    snapshot: radau5 at tolerance 1e-10 agrees with dop853 at 1e-12 far below energy's own
    error at 1e-9, and the error follows the tolerance."""
    # the reference lands on every snapshot: at μ = 100 dop853 is stability-bound, and its
    # dense output amplifies the stiff components between a step's ends (up to ~15×)
    ref = _paper("dop853", 1e-12, **{"output.interpolate": False})
    assert len(ref.bounces) >= 1
    errs = {tol: np.abs(_final(_paper("radau5", tol)) - _final(ref)).max()
            for tol in (1e-6, 1e-10)}
    assert errs[1e-10] < 1e-8 and errs[1e-10] < errs[1e-6] / 100, errs
    e_energy = np.abs(_final(_paper("energy", 1e-9)) - _final(ref)).max()
    assert e_energy < 1e-4 and errs[1e-10] < e_energy / 1000, (errs, e_energy)
    r = _paper("radau5", 1e-10)
    assert abs(r.bounces["t_impact"][0] - ref.bounces["t_impact"][0]) < 1e-8
    assert r.stats["newton_iterations"] > r.stats["steps"]


def test_energy_balance_follows_the_tolerance():
    """E + dissipated = E₀ along the μ = 100 run (impact included), to a level that
    falls with the tolerance."""
    bal = []
    for tol in (1e-5, 1e-9):
        d = _paper("radau5", tol).diagnostics
        b = d["energy_total"] + d["dissipated"]
        assert d["dissipated"][-1] > 1.0
        bal.append(np.abs(b - b[0]).max() / abs(b[0]))
    assert bal[0] < 1e-3 and bal[1] < 1e-7 and bal[1] < bal[0] / 1000, bal


def test_a_stage_outside_the_admissible_set_is_rejected_and_the_run_stays_admissible():
    cfg = _cfg("radau5", {"initial.height": 0.001, "initial.velocity": -5.0})
    _, _, r = trial_step(cfg, radau.step, 0.05)
    assert r.status in (BAD_FLOOR, BAD_STRAIN, NON_FINITE, NO_CONVERGENCE)
    res = rodjit.simulate(_cfg("radau5", {"initial.height": 0.001, "initial.velocity": -5.0,
                                          "time.t_end": 0.3, "time.rtol": 1e-4,
                                          "time.atol": 1e-4,
                                          "output.diagnostics_interval": 1e-3}))
    d = res.diagnostics
    assert np.all(np.isfinite(d["energy_total"]))
    assert d["u_bottom"].min() > -cfg.floor.beta and d["min_strain"].min() > -1.0
    assert res.stats["rejected_steps"] > 0
    with pytest.raises(SimulationError, match="time.dt"):
        rodjit.simulate(_cfg("radau5", {"initial.height": 0.001, "initial.velocity": -5.0,
                                        "time.dt": 0.05, "time.t_end": 0.3}))


def test_step_leaves_the_full_acceleration_of_the_new_state():
    cfg = _cfg("radau5", {"rod.mu": 0.3, "rod.gamma": 1e-3})
    run, trial, r = trial_step(cfg, radau.step, 1e-4)
    assert r.status == OK
    _, _, system, rod, floor, _ = run._args()
    a = np.zeros_like(trial[2])
    full_accel(system, rod, floor, trial[0], trial[1], a, run.arrays.work[0], run.arrays.work[1],
                      False)
    np.testing.assert_array_equal(a, trial[2])
    assert run.arrays.sstats[registry.counter_index("newton_iterations")] >= 2


def test_resume_is_bit_identical():
    cfg = rodjit.presets.load_preset("paper-mu100").override(
        {"time.integrator": "radau5", "time.t_end": 0.9, "time.rtol": 1e-7,
         "time.atol": 1e-7, **QUIET})
    assert_resume_is_bit_identical(cfg, max_steps=333)


def test_config_and_command_line(tmp_path):
    from click.testing import CliRunner
    cfg = rodjit.Config().override({"time.integrator": "radau5"})
    assert cfg.time.integrator == "radau5"
    out = tmp_path / "r.h5"
    r = CliRunner().invoke(main, ["run", "paper-mu100", "--t-end", "0.3", "--set",
                                  "time.integrator=radau5", "-o", str(out), "-q"],
                           catch_exceptions=False)
    assert r.exit_code == 0, r.output
    res = rodjit.load_file(out)
    assert res.config.time.integrator == "radau5" and res.status == "completed"
    assert res.stats["newton_iterations"] > 0
