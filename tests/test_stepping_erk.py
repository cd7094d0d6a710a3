"""The embedded Runge–Kutta pairs (``time.integrator = "dp54"`` and ``"dop853"``).

Checked: convergence order in fixed steps dt (5 and 8, within ±0.2) in flight and in
contact, the energy drift at μ = 0 following the tolerance, agreement with ``energy`` and
between the pairs through bounces (the loop's landing on the floor crossings), the stage
admissibility checks, exact free-fall momentum, dissipation bookkeeping, and resume bit
for bit.
"""
import numpy as np
import pytest

import rodjit
from conftest import assert_resume_is_bit_identical, trial_step
from rodjit.driver.run import Run, SimulationError
from rodjit.kernels.forces import BAD_FLOOR, BAD_STRAIN, NON_FINITE, OK
from rodjit.records.result import MemorySink
from rodjit.stepping import control, layout as L, registry
from rodjit.kernels.rates import full_accel
from rodjit.stepping.integrators import erk

QUIET = {"output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0}
PAIRS = {"dp54": 5, "dop853": 8}

# flight: the paper's rod high above the floor, pre-strained, vibrating as it falls
FLIGHT = {"rod.N": 5, "initial.height": 3.0, "initial.strain": 0.1, "initial.velocity": 0.0,
          "time.t_end": 0.5}
# contact: pressed into a soft floor for the whole interval (u_0 < 0 throughout, so the
# force is smooth: the kink at u_0 = 0 is handled by the adaptive loop, not by fixed steps)
CONTACT = {"rod.N": 8, "initial.height": -0.05, "initial.velocity": -1.0, "rod.mu": 0.1,
           "floor.kappa_b": 10.0, "floor.beta": 1.0, "time.t_end": 0.1}
# the largest of three halving steps: errors between ~1e-5 and ~1e-11, in the asymptotic
# range and above the rounding floor (1e-13 … 1e-12 for these runs)
DTS = {("dp54", "flight"): 1.25e-3, ("dp54", "contact"): 1e-3,
       ("dop853", "flight"): 1e-2, ("dop853", "contact"): 1.6e-2}


def _cfg(integrator, over):
    return rodjit.Config().override({"time.integrator": integrator, **QUIET, **over})


def _fixed(integrator, dt, over):
    res = rodjit.simulate(_cfg(integrator, {"time.dt": dt, **over}))
    return np.concatenate([res.u_final, res.v_final])


def test_registry_lines():
    for name, params in (("dp54", erk.DP54), ("dop853", erk.DOP853)):
        entry = registry.get(name)
        assert registry.load(entry)[1] is params
        assert entry.work_rows == erk.work_rows(params)
        assert entry.gap_control is False and entry.counters == ()
        s = registry.make_scheme(rodjit.Config().override(
            {"time.integrator": name, "time.rtol": 1e-7, "time.atol": 1e-11}).time)
        assert s == params(1e-7, 1e-11)


def test_tableaus_have_their_design_order_conditions():
    """Row sums c_i = Σ_j a_ij; Σ b = 1, Σ b c = 1/2, Σ b c² = 1/3, Σ b c³ = 1/4 (and up to
    c⁷ for dop853); the error weights sum to 0 (both solutions are consistent)."""
    for params, order in ((erk.DP54, 5), (erk.DOP853, 8)):
        t = erk.TABLEAUS[params]
        c = t.a.sum(axis=1)
        for k in range(order):
            assert abs(t.b @ c**k - 1.0 / (k + 1)) < 1e-13, (params, k)
        assert abs(t.e.sum()) < 1e-13 and abs(t.e3.sum()) < 1e-13


@pytest.mark.parametrize("case", ["flight", "contact"])
@pytest.mark.parametrize("integrator", sorted(PAIRS))
def test_order_in_dt(integrator, case):
    over = FLIGHT if case == "flight" else CONTACT
    dts = [DTS[integrator, case] / 2**k for k in range(3)]
    ref = _fixed("dop853", dts[-1] / 8, over)
    errs = np.array([np.abs(_fixed(integrator, dt, over) - ref).max() for dt in dts])
    orders = np.log2(errs[:-1] / errs[1:])
    assert errs[-1] > 3e-12, errs                        # above rounding
    assert np.all(np.abs(orders - PAIRS[integrator]) <= 0.2), (orders, errs)


def test_contact_case_stays_in_contact():
    res = rodjit.simulate(_cfg("dp54", {**CONTACT, "time.dt": 1e-4,
                                        "output.diagnostics_interval": 1e-3}))
    assert res.diagnostics["u_bottom"].max() < 0.0


def _paper(integrator, **over):
    return _cfg(integrator, {"time.t_end": 1.5, **over})


def _final(integrator, rtol, atol):
    res = rodjit.simulate(_paper(integrator, **{"time.rtol": rtol, "time.atol": atol}))
    return np.concatenate([res.u_final, res.v_final]), res


def test_accuracy_through_bounces_follows_the_tolerance():
    """The paper's run (μ = 0, N = 5) over 1.5 s, through its first bounce and the chatter
    of the bottom node: each adaptive step that crosses u_0 = 0 is redone to end on the
    crossing, so no step integrates across the kink of σ_b and the error keeps falling with
    the tolerance (a pair stepping across the kink stalls near 1e-4).  Reference: dop853 at
    rtol 1e-13; ``energy`` at its own tight tolerance agrees."""
    ref, rref = _final("dop853", 1e-13, 1e-15)
    assert len(rref.bounces) >= 1
    errs = {}
    for integrator in PAIRS:
        for rtol in (1e-8, 1e-10):
            y, res = _final(integrator, rtol, rtol * 1e-2)
            errs[integrator, rtol] = np.abs(y - ref).max()
            assert abs(res.bounces["t_impact"][0] - rref.bounces["t_impact"][0]) < 1e3 * rtol
    assert errs["dp54", 1e-10] < 1e-5 and errs["dop853", 1e-10] < 1e-7, errs
    for integrator in PAIRS:
        assert errs[integrator, 1e-10] < errs[integrator, 1e-8] / 20, errs
    ye, _ = _final("energy", 1e-9, 1e-12)
    assert np.abs(ye - ref).max() < 5e-4    # energy's own error (second order): 1.3e-4


@pytest.mark.parametrize("integrator", sorted(PAIRS))
def test_energy_drift_follows_the_tolerance(integrator):
    """μ = 0: the energy is not an invariant of the pairs, but its drift over a bouncing run
    shrinks with the tolerance (by ≥ 100× for 1000× tighter) and stays below it × E."""
    drift = []
    for rtol in (1e-5, 1e-8):
        res = rodjit.simulate(_paper(integrator, **{"time.t_end": 2.0, "time.rtol": rtol,
                                                    "time.atol": rtol * 1e-2,
                                                    "output.diagnostics_interval": 0.01}))
        e = res.diagnostics["energy_total"]
        drift.append(np.abs(e - e[0]).max() / abs(e[0]))
        assert drift[-1] < 100 * rtol
    assert drift[1] < drift[0] / 100, drift


@pytest.mark.parametrize("integrator", sorted(PAIRS))
def test_free_fall_momentum_and_dissipation(integrator):
    """No contact: w = w0 + g t to rounding (every stage adds g to each node's
    acceleration; internal forces cancel); with μ > 0, E + dissipated = E0 to the
    tolerance."""
    res = rodjit.simulate(_cfg(integrator, {**FLIGHT, "rod.mu": 0.05, "rod.gamma": 1e-3,
                                            "time.rtol": 1e-9, "time.atol": 1e-12,
                                            "output.diagnostics_interval": 0.05}))
    d = res.diagnostics
    np.testing.assert_allclose(d["cm_velocity"], -9.81 * d["t"], rtol=0, atol=1e-12)
    bal = d["energy_total"] + d["dissipated"]
    assert d["dissipated"][-1] > 1e-4
    assert np.abs(bal - bal[0]).max() < 1e-7 * abs(bal[0])


@pytest.mark.parametrize("integrator", sorted(PAIRS))
def test_a_stage_outside_the_admissible_set_is_rejected(integrator):
    """A step far too long for a hard impact: a stage (or the new point) leaves ε > −1 or
    u_0 > −β; the step reports which, and leaves its inputs untouched."""
    cfg = _cfg(integrator, {"initial.height": 0.001, "initial.velocity": -5.0})
    _, _, r = trial_step(cfg, erk.step, 0.05)
    assert r.status in (BAD_FLOOR, BAD_STRAIN, NON_FINITE)
    # the loop retries shorter and the run stays admissible through the impact
    res = rodjit.simulate(_cfg(integrator, {"initial.height": 0.001, "initial.velocity": -5.0,
                                            "time.t_end": 0.3, "time.rtol": 1e-4,
                                            "output.diagnostics_interval": 1e-3}))
    assert res.diagnostics["u_bottom"].min() > -cfg.floor.beta and res.stats["rejected_steps"] > 0
    assert res.diagnostics["min_strain"].min() > -1.0
    # fixed steps cannot retry: a clear failure naming time.dt
    with pytest.raises(SimulationError, match="time.dt"):
        rodjit.simulate(_cfg(integrator, {"initial.height": 0.001, "initial.velocity": -5.0,
                                          "time.dt": 0.05, "time.t_end": 0.3}))


@pytest.mark.parametrize("integrator", sorted(PAIRS))
def test_resume_is_bit_identical(integrator):
    cfg = _cfg(integrator, {"rod.N": 10, "rod.mu": 0.2, "time.t_end": 0.9, "time.rtol": 1e-7})
    # fewer than either pair takes (dop853 takes the fewest, about 260)
    assert_resume_is_bit_identical(cfg, max_steps=100)


def test_step_is_ok_and_fsal():
    """An accepted step leaves the new state's full acceleration in a2 (the next step's
    first stage), equal to a fresh evaluation at (u2, v2)."""
    cfg = _cfg("dp54", {"rod.mu": 0.3, "rod.gamma": 1e-3})
    run, trial, r = trial_step(cfg, erk.step, 1e-4)
    assert r.status == OK
    _, _, system, rod, floor, _ = run._args()
    a = np.zeros_like(trial[2])
    full_accel(system, rod, floor, trial[0], trial[1], a, run.arrays.work[0], run.arrays.work[1], False)
    np.testing.assert_array_equal(a, trial[2])


# ---- the pairs' step-size rules (control.RULES) ---------------------------------------

def _ctrl(integrator):
    cfg = _cfg(integrator, {})
    return control.build(cfg.time, registry.make_scheme(cfg.time))


def test_rules_are_per_scheme():
    """The pairs take Hairer's growth limits and land by stretching; the second-order
    schemes keep the gentle growth and the split remainder."""
    for name in ("verlet", "semi-implicit", "energy"):
        c = _ctrl(name)
        assert (c.growth, c.growth_reject, c.land, c.split) == (
            control.GROWTH, control.GROWTH, control.LAND_ADAPTIVE, control.SPLIT_BELOW)
    for name in PAIRS:
        c = _ctrl(name)
        assert c.growth == control.PAIR_GROWTH[name] and c.growth_reject == 1.0
        assert c.land == control.PAIR_STRETCH


def test_pair_lands_by_stretching_and_second_order_splits():
    pair, low = _ctrl("dop853"), _ctrl("energy")
    rem = 1.0 + 0.5 * control.PAIR_STRETCH          # a little more than one proposal
    assert control.step_to(pair, False, rem, 1.0) == (rem, True)
    assert control.step_to(low, False, rem, 1.0) == (0.5 * rem, False)
    # beyond the stretch both split, and a long remainder takes the proposal
    assert control.step_to(pair, False, 1.5, 1.0) == (0.75, False)
    assert control.step_to(pair, False, 3.0, 1.0) == (1.0, False)


def test_pair_growth_is_over_the_proposal_and_none_after_a_rejection():
    c = _ctrl("dp54")
    # a step cut short to land (error tiny): its suggestion is not clamped by the pair...
    assert erk._factor(1e-30, 4) > 1e5
    # ... the loop caps the growth over the previous proposal
    assert control.propose(c, np.inf, 2e-3) == 2e-3 * control.PAIR_GROWTH["dp54"]
    assert control.propose(c, np.inf, 2e-3, True) == 2e-3
    assert control.propose(c, 1e-3, 2e-3, True) == 1e-3
    low = _ctrl("energy")
    assert control.propose(low, np.inf, 2e-3, True) == 2e-3 * control.GROWTH


@pytest.mark.parametrize("integrator", sorted(PAIRS))
def test_bouncing_run_lands_on_every_output_time(integrator):
    """The paper's run through its first bounces with snapshots every 5 ms: every row at
    exactly t0 + kΔ (the loop's landing, stretched steps included), diagnostics with them."""
    dt_out = 0.005
    res = rodjit.simulate(_paper(integrator, **{"time.t_end": 0.6, "time.rtol": 1e-6,
                                                "time.atol": 1e-6,
                                                "output.snapshot_interval": dt_out,
                                                "output.diagnostics_interval": dt_out}))
    k = np.arange(res.t.size)
    np.testing.assert_array_equal(res.t, k * dt_out)
    np.testing.assert_array_equal(res.diagnostics["t"], res.t)
    assert res.n_bounces >= 1
    # the pair's rules take fewer steps than the second-order schemes' on the same run
    # (by 5-6 %: the floor crossings, which cost the gentle rules most, reject few trials)
    run = Run(res.config)
    run.ctrl = run.ctrl._replace(growth=control.GROWTH, growth_reject=control.GROWTH,
                                 land=control.LAND_ADAPTIVE)
    run.start(MemorySink())
    while run.advance(MemorySink()) != L.DONE:
        pass
    assert res.stats["steps"] + res.stats["rejected_steps"] < run.steps + run.rejected


@pytest.mark.parametrize("integrator", sorted(PAIRS))
def test_resume_through_bounces_and_outputs_is_bit_identical(integrator):
    """Cut into calls after rejections, landings and floor crossings: the same steps."""
    cfg = _paper(integrator, **{"time.t_end": 0.6, "time.rtol": 1e-6, "time.atol": 1e-6,
                                "output.snapshot_interval": 0.005,
                                "output.diagnostics_interval": 0.005})
    one = Run(cfg)
    one.start(MemorySink())
    while one.advance(MemorySink()) != L.DONE:
        pass
    assert one.rejected > 0
    run = Run(cfg)
    run.start(MemorySink())
    for n in (37, 61, 53):
        run.advance(MemorySink(), max_steps=n)
        run = Run.from_checkpoint(cfg, run.checkpoint())
    while run.advance(MemorySink()) != L.DONE:
        pass
    np.testing.assert_array_equal(run.arrays.state, one.arrays.state)
    assert run.steps == one.steps and run.rejected == one.rejected


def test_the_imaginary_stability_limit_is_where_the_amplification_passes_one():
    """``erk.imaginary_limit`` from the stability polynomial: |R(iy)| ≤ 1 up to it and > 1
    just beyond, R evaluated independently as 1 + z bᵀ(I − zA)⁻¹1; the cap is below it."""
    from rodjit.stepping.integrators import erk
    for params, t in erk.TABLEAUS.items():
        s = t.b.size
        a = np.zeros((s, s))
        a[:, :t.a.shape[1]] = t.a[:s]

        def amp(y):
            z = 1j * y
            return abs(1.0 + z * t.b @ np.linalg.solve(np.eye(s) - z * a, np.ones(s)))

        limit = erk.imaginary_limit(t.a, t.b)
        assert 0.5 < limit < 10.0
        assert max(amp(y) for y in np.linspace(1e-3, limit, 400)) <= 1.0 + 1e-12
        assert amp(limit * 1.01) > 1.0
        assert np.isclose(amp(limit), 1.0, atol=1e-9)
        assert erk.STABILITY_CAP[params] < limit
