"""Convergence ladders: the Richardson machinery on known answers (the free-free modes of
MODEL.md §4, the spring-wall impact), its statuses, and the convergence file."""
from __future__ import annotations

import importlib
import math

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.analysis.converge import converge, load_convergence
from rodjit.analysis.known import free_free_frequencies, spring_wall_impact
from rodjit.analysis.richardson import SAFETY_UNCHECKED, observed_order, study
from rodjit.model import reference
from rodjit.model.system import build_system, masses

E = 5 * 100.0 / 4


def _stiffness_eigenfrequencies(n: int) -> np.ndarray:
    """ω_k of the semi-discrete rod from the NumPy reference forces: the Jacobian of
    m_i u_i'' at the natural state (g = 0, far above the floor) by central differences
    against the lumped masses."""
    cfg = rodjit.Config().override({"rod.N": n, "gravity.g": 0.0})
    system, rod, floor = build_system(cfg)
    u = 1.0 + np.arange(n + 1) / n
    v = np.zeros(n + 1)
    d = 1e-6
    K = np.empty((n + 1, n + 1))
    for j in range(n + 1):
        up, um = u.copy(), u.copy()
        up[j] += d
        um[j] -= d
        K[:, j] = -(reference.forces(up, v, system, rod, floor)
                    - reference.forces(um, v, system, rod, floor)) / (2 * d)
    m = masses(n)
    s = 1 / np.sqrt(m)
    lam = np.sort(np.linalg.eigvalsh(s[:, None] * K * s[None, :]))
    return np.sqrt(np.clip(lam, 0, None))      # lam[0] = 0: the rigid motion


def test_semi_discrete_modes_converge_at_second_order_to_k_pi_sqrt_E():
    ns = [8, 16, 32, 64]
    for k in (1, 2, 3):
        om = [_stiffness_eigenfrequencies(n)[k] for n in ns]
        assert om == pytest.approx(free_free_frequencies(np.array(ns), E, k), rel=1e-6)
        s = study(f"omega_{k}", [1 / n for n in ns], om)
        assert s.status == "converged"
        assert s.orders == pytest.approx([2, 2], abs=0.05)
        assert s.extrapolated == pytest.approx(k * math.pi * math.sqrt(E), rel=2e-5)
        assert abs(s.extrapolated - k * math.pi * math.sqrt(E)) <= s.error


def test_observed_order_of_a_known_power_law_with_uneven_levels():
    h = [0.3, 0.17, 0.05]
    f = [2 + 3 * x ** 1.5 for x in h]
    assert observed_order(h, f) == pytest.approx(1.5, rel=1e-9)
    s = study("x", [0.4, 0.2, 0.1, 0.05], [2 + 3 * x ** 2 for x in [0.4, 0.2, 0.1, 0.05]])
    assert s.extrapolated == pytest.approx(2.0, abs=1e-12)


def test_statuses_say_what_the_ladder_does():
    h = [1 / 25, 1 / 50, 1 / 100, 1 / 200]
    assert study("a", h, [1.0, 2.0, 1.0, 2.0]).status == "not converging"
    s = study("b", h, [1.0, 1.5, 1.25, 1.375])
    # the last difference, times the safety factor of an order nothing checks
    assert s.status == "oscillating" and s.extrapolated == 1.375
    assert s.error == SAFETY_UNCHECKED * 0.125
    s = study("c", h, [1.0, 1.1, 1.101, 1.15])          # does not settle
    assert s.status == "not converging" and math.isnan(s.extrapolated)
    s = study("d", h, [1.0, 1.5, 1.6, 1.61])            # orders 2.3, 3.3: scatter
    assert s.status == "pre-asymptotic" and "asymptotic" in s.message
    assert study("e", h, [3.0] * 4).status == "exact"
    s = study("never ends", h, [math.inf] * 4)           # no lift-off at every level
    assert s.status == "exact" and s.extrapolated == math.inf and s.error == 0
    assert study("f", h, [1.0, math.nan, 1.0, 1.0]).status == "undefined"


def _omega1(result) -> float:
    """Frequency of the first mode from the zero crossings of its modal coordinate: the
    displacement from the natural shape projected with the lumped masses on cos(πx_i),
    the first discrete mode shape of the free-free chain."""
    n = result.config.rod.N
    x = result.x
    m = masses(n)
    phi = np.cos(math.pi * x)
    d = result.u - x[None, :]
    q = (d - (d @ m)[:, None]) @ (m * phi)
    t = result.t
    idx = np.flatnonzero(np.sign(q[:-1]) != np.sign(q[1:]))
    tz = t[idx] - q[idx] * (t[idx + 1] - t[idx]) / (q[idx + 1] - q[idx])
    return math.pi * (len(tz) - 1) / (tz[-1] - tz[0])


def test_free_vibration_runs_converge_to_the_first_continuum_mode():
    # a small uniform pre-strain in free flight without gravity: odd modes, the first
    # dominating; its modal coordinate is harmonic in the linearised chain
    cfg = rodjit.Config().override({"gravity.g": 0.0, "initial.strain": 1e-6,
                                    "initial.height": 1.0, "time.t_end": 1.0,
                                    "output.snapshot_interval": 2e-4,
                                    "output.diagnostics_interval": 1e-3, "time.cfl": 0.02,
                                    "time.integrator": "verlet", "time.control": "cfl"})
    conv = converge(cfg, {"rod.N": [8, 16, 32]}, observables=["omega_1"],
                    extra={"omega_1": _omega1}, jobs=1)
    oc = conv["omega_1"]
    exact = math.pi * math.sqrt(E)
    assert oc.space.values == pytest.approx(free_free_frequencies(np.array([8, 16, 32]), E, 1),
                                            rel=2e-4)
    assert oc.space.order == pytest.approx(2, abs=0.2)
    assert oc.value == pytest.approx(exact, rel=1e-3)


def test_spring_wall_reference_limits():
    # a rigid-wall limit: contact time 2/c, restitution 1; a soft spring: the rigid bar on
    # a spring, c T = π/√α, restitution 1
    s, e = spring_wall_impact(1e4)
    assert s == pytest.approx(2.0, rel=1e-3) and e == pytest.approx(1.0, abs=1e-4)
    s, e = spring_wall_impact(1e-3, steps_per_transit=200)
    assert s == pytest.approx(math.pi / math.sqrt(1e-3), rel=2e-3)
    assert e == pytest.approx(1.0, abs=1e-3)
    # finer grids agree (second order)
    a, b = spring_wall_impact(5.0, 2000), spring_wall_impact(5.0, 8000)
    assert a == pytest.approx(b, rel=1e-7)


def _spring_wall_config(alpha: float, V: float = 1e-6) -> rodjit.Config:
    """The linear limit of MODEL.md's model: g = 0, impact speed V ≪ c (strain V/c), the
    floor linearised, σ_b ≈ 3κ_b/β·(−u_0): k = 3κ_b/β = α E."""
    beta = 0.05
    s, _ = spring_wall_impact(alpha)
    return rodjit.Config().override({
        "gravity.g": 0.0, "floor.kappa_b": alpha * E * beta / 3, "floor.beta": beta,
        "initial.height": V * 1e-3, "initial.velocity": -V,
        "time.t_end": 1e-3 + s / math.sqrt(E) + 0.02, "output.snapshot_interval": 0.0,
        "time.integrator": "verlet", "time.control": "cfl",
        "output.diagnostics_interval": 1e-4})


def test_spring_wall_impact_extrapolates_to_the_dalembert_solution():
    alpha = 5.0
    s, e = spring_wall_impact(alpha)
    conv = converge(_spring_wall_config(alpha), {"rod.N": [25, 50, 100, 200]},
                    observables=["contact_time_first", "restitution_first"], jobs=2)
    ct, rs = conv["contact_time_first"], conv["restitution_first"]
    assert ct.value * math.sqrt(E) == pytest.approx(s, rel=1e-3)
    assert rs.value == pytest.approx(e, rel=1e-3)
    assert ct.space.status == rs.space.status == "converged"
    assert ct.error * math.sqrt(E) < 1e-3 * s and rs.error < 1e-3 * e
    # the coarsest level is off by more than the extrapolated value
    assert abs(ct.space.values[0] * math.sqrt(E) - s) > 10 * abs(ct.value * math.sqrt(E) - s)


@pytest.mark.slow
@pytest.mark.parametrize("alpha, ladder", [(1.0, [25, 50, 100, 200, 400]),
                                           (10.0, [25, 50, 100, 200, 400]),
                                           (100.0, [400, 800, 1600, 3200])])
def test_spring_wall_table(alpha, ladder):
    s, e = spring_wall_impact(alpha)
    conv = converge(_spring_wall_config(alpha), {"rod.N": ladder},
                    observables=["contact_time_first", "restitution_first"], jobs=2)
    assert conv["contact_time_first"].value * math.sqrt(E) == pytest.approx(s, rel=1e-3)
    assert conv["restitution_first"].value == pytest.approx(e, rel=1e-3)


@pytest.mark.slow
def test_shock_forming_ladder_is_reported_not_extrapolated():
    # μ = 0, γ = 0 on the paper's floor: without viscosity the impact's fronts stay sharp
    # and the first restitution does not settle (0.868, 0.854, 0.848, 0.840)
    cfg = rodjit.load_preset("paper-mu0").override({"time.t_end": 0.7,
                                                    "output.snapshot_interval": 0.0})
    conv = converge(cfg, {"rod.N": [25, 50, 100, 200]}, observables=["restitution_first"],
                    jobs=2)
    oc = conv["restitution_first"]
    assert oc.space.status == "not converging"
    assert math.isnan(oc.value) and oc.error == math.inf
    assert any("restitution_first" in w and "do not shrink" in w for w in conv.warnings)


def test_convergence_file_round_trip_and_repr(tmp_path):
    cfg = rodjit.load_preset("paper-mu100").override({"rod.mu": 1.0, "time.t_end": 0.7,
                                                      "output.snapshot_interval": 0.0})
    conv = converge(cfg.override({"time.integrator": "semi-implicit", "time.control": "cfl"}),
                    {"rod.N": "10,20,40"}, also={"time.cfl": [0.05, 0.0125]},
                    observables=["restitution_first", "contact_time_first"], jobs=2)
    text = repr(conv)
    assert "restitution_first" in text and "±" in text and text.count("\n") < 12
    path = tmp_path / "conv.h5"
    conv.save(path)
    with h5py.File(path) as f:
        assert f.attrs["rodjit_kind"] == "convergence"
        assert list(f["observables"]) == ["contact_time_first", "restitution_first"]
    back = load_convergence(path)
    oc = conv["restitution_first"]
    assert back["observables"]["restitution_first"]["values"] == pytest.approx(oc.space.values)
    assert back["observables"]["restitution_first"]["value"] == pytest.approx(oc.value)
    assert math.isfinite(oc.time_error)
    assert back["key"] == "rod.N" and back["time_key"] == "time.cfl"
    d = conv.to_dict()
    assert d["observables"]["restitution_first"]["space"]["values"] == oc.space.values
    with pytest.raises(ValueError, match="exists"):
        conv.save(path)


def test_bad_ladders_are_one_line_errors():
    cfg = rodjit.Config()
    with pytest.raises(ValueError, match="refine"):
        converge(cfg, {"rod.N": [50, 25, 100]})
    with pytest.raises(ValueError, match="rod.N"):
        converge(cfg, {"rod.N": [0, 25, 100]})
    with pytest.raises(ValueError, match="unknown observable"):
        converge(cfg, {"rod.N": [5, 10, 20]}, observables=["nope"])
    with pytest.raises(ValueError, match="time.cfl"):
        converge(cfg.override({"time.integrator": "verlet", "time.control": "cfl"}),
                 {"rod.N": [5, 10, 20]}, also={"time.rtol": [1e-6, 1e-7]})
    with pytest.raises(ValueError, match="time.rtol"):
        converge(cfg, {"rod.N": [5, 10, 20]}, also={"time.cfl": [0.05, 0.01]})


# ---- the time ladder from the registry: honest time errors, predictability ---------------
def _mu100(t_end=1.0, **over):
    return rodjit.load_preset("paper-mu100").override(
        {"time.t_end": t_end, "output.snapshot_interval": 0.01, **over})


def test_the_registry_facts_of_the_step_keys_hold_in_runs():
    """What the registry says sets the steps does: dp54 and radau5 take the same steps at
    any time.cfl under time.control = "cfl", verlet's change with it."""
    from rodjit.driver.simulate import simulate
    from rodjit.stepping import registry

    base = _mu100(0.3, **{"rod.N": 8, "output.snapshot_interval": 0.0,
                          "time.control": "cfl"})
    for name in ("dp54", "radau5", "verlet"):
        entry = registry.get(name)
        steps = [simulate(base.override({"time.integrator": name, "time.cfl": c})).stats["steps"]
                 for c in (0.5, 0.05)]
        ignores = steps[0] == steps[1]
        assert ignores is ("time.cfl" not in entry.step_keys("cfl")), (name, steps)
        assert entry.step_keys("cfl", fixed=True) == ("time.dt",)
        assert entry.step_keys("tolerance") == ("time.rtol", "time.atol")


@pytest.mark.parametrize("integrator", ["dp54", "radau5", "dop853"])
def test_a_time_ladder_over_a_key_that_sets_no_steps_names_the_one_that_does(integrator):
    cfg = _mu100(**{"time.integrator": integrator, "time.control": "cfl"})
    with pytest.raises(ValueError, match=r"time.cfl does not set the steps .* ladder "
                                         r"time.rtol instead") as exc:
        converge(cfg, {"rod.N": [10, 20, 40]}, also={"time.cfl": [0.05, 0.0125, 0.003125]})
    assert "\n" not in str(exc.value)
    with pytest.raises(ValueError, match="ladder time.rtol instead"):
        converge(cfg.override({"rod.N": 10}), {"time.cfl": [0.5, 0.1, 0.02]})
    with pytest.raises(ValueError, match="ladder time.dt instead"):
        converge(cfg.override({"time.dt": 1e-5}), {"rod.N": [10, 20]},
                 also={"time.rtol": [1e-6, 1e-7]})


def test_default_time_ladder_is_the_key_the_registry_names():
    from rodjit.analysis.converge import default_time_ladder

    cfg = rodjit.Config()
    assert list(default_time_ladder(cfg)) == ["time.rtol"]
    for name, key in (("verlet", "time.cfl"), ("semi-implicit", "time.cfl"),
                      ("dp54", "time.rtol"), ("dop853", "time.rtol"),
                      ("radau5", "time.rtol"), ("energy", "time.rtol")):
        c = cfg.override({"time.integrator": name, "time.control": "cfl"})
        assert list(default_time_ladder(c)) == [key], name
    assert list(default_time_ladder(cfg.override({"time.dt": 1e-5}))) == ["time.dt"]


def test_verlet_under_tolerance_control_above_its_viscous_limit_refuses_in_one_line():
    """verlet at μ = 100 under tolerance control takes the steps of its viscous cap
    (time.cfl·h²/(2μ)) at every rtol, so no tolerance bounds its error: the run and
    converge refuse in one line naming the knob that works, before anything runs; the
    configuration itself stays valid (a file holding it still reads)."""
    from rodjit.driver.simulate import simulate

    cfg = _mu100(1.0, **{"time.integrator": "verlet", "time.control": "tolerance"})
    for call in (lambda: converge(cfg, {"rod.N": [10, 20, 40]}),
                 lambda: converge(cfg, {"rod.mu": [400.0, 200.0, 100.0]}),
                 lambda: simulate(cfg)):
        with pytest.raises(ValueError, match="cannot honour time.rtol") as exc:
            call()
        assert "\n" not in str(exc.value) and "time.control = 'cfl' and refine time.cfl" in str(
            exc.value)
    assert cfg.warnings()                      # valid, with its warning
    cfg.override({"time.control": "cfl"}).check_runnable()
    cfg.override({"rod.mu": 1.0}).check_runnable()
    cfg.override({"time.dt": 1e-6}).check_runnable()


def test_a_ladder_that_does_not_change_the_steps_refines_the_cap_key():
    """verlet at μ = 1, N = 40 under tolerance control: its viscous cap binds at every
    rtol from 1e-1 to 2.5e-2 (38,402 steps each; from 1e-2 down its error per unit step
    takes a few more in contact), so converge refines time.cfl, which scales that cap, instead of
    reporting the zero spread of identical runs."""
    cfg = _mu100(0.6, **{"time.integrator": "verlet", "rod.mu": 1.0})
    conv = converge(cfg, {"rod.N": [10, 20, 40]}, also={"time.rtol": [1e-1, 5e-2, 2.5e-2]},
                    time_at=40, observables=["restitution_first"], jobs=1)
    assert conv.time_key == "time.cfl"
    assert conv.time_levels == pytest.approx([0.05, 0.025, 0.0125])
    assert conv.time_steps[0] < conv.time_steps[1] < conv.time_steps[2]
    assert any("time.rtol does not change the steps" in w and "38,402" in w
               for w in conv.warnings)
    oc = conv["restitution_first"]
    true = _true_time_error(cfg.override({"rod.N": 40}), "restitution_first")
    assert true > 1e-9 * abs(oc.value)
    assert true / 10 <= oc.time_error <= 10 * true, (oc.time_error, true)
    cv = importlib.import_module("rodjit.analysis.converge")
    assert cv.same_steps([{"steps": 7}, {"steps": 7}, {"steps": 7}])
    assert not cv.same_steps([{"steps": 7}, {"steps": 8}])
    assert not cv.same_steps([{"steps": -1}, {"steps": -1}])


def test_unchanged_steps_print_not_measured_never_zero(monkeypatch):
    """The same ladder with the cap's key closed: "not measured", never 0 or exact."""
    cv = importlib.import_module("rodjit.analysis.converge")
    cfg = _mu100(0.6, **{"time.integrator": "verlet", "rod.mu": 1.0, "rod.N": 40})
    monkeypatch.setattr(cv, "cap_key", lambda base, key: None)
    conv = converge(cfg, {"rod.N": [20, 40]}, also={"time.rtol": [1e-1, 5e-2, 2.5e-2]},
                    time_at=40, observables=["restitution_first", "max_floor_force"], jobs=1)
    assert len(set(conv.time_steps)) == 1
    for oc in conv.observables.values():
        assert oc.time_status == cv.NOT_MEASURED and math.isnan(oc.time_error)
        assert oc.time.status == cv.NOT_MEASURED
    text = repr(conv)
    assert "(time not measured)" in text and "(time 0)" not in text
    assert "exact" not in text.split("warning")[0]
    assert "predictability_time: not measured" in text
    assert any("time error not measured" in w for w in conv.warnings)


def _true_time_error(cfg, name):
    """|f(cfg) − f(the same semi-discrete system by dop853 at rtol 1e-12)|."""
    from rodjit.analysis.observables import observables
    from rodjit.driver.simulate import simulate

    ref = cfg.override({"time.integrator": "dop853", "time.control": "tolerance",
                        "time.rtol": 1e-12, "time.atol": 1e-15})
    return abs(observables(simulate(cfg))[name] - observables(simulate(ref))[name])


def _check_time_error(cfg, ladder, also=None, tiny_ok=False,
                      names=("restitution_first", "max_floor_force"), never_zero=()):
    """converge's time error within 10x of the true one; with ``tiny_ok`` a true error
    below 1e-9 relative may be reported as anything up to 1e-8 relative, and a value the
    ladder does not move as "not measured" (an accurate integrator's steps in contact,
    capped by its stability, do not move along the ladder), never as 0."""
    conv = converge(cfg, {"rod.N": ladder}, also=also, observables=[*names, *never_zero],
                    jobs=1)
    at = cfg.override({"rod.N": conv.time_at})
    for name in never_zero:        # at least: no zero where the true error is not tiny
        oc = conv[name]
        true = _true_time_error(at, name)
        if true > 1e-9 * abs(oc.value):
            assert math.isnan(oc.time_error) or oc.time_error >= true / 10, (name, true)
    for name in names:
        oc = conv[name]
        true = _true_time_error(at, name)
        if tiny_ok and oc.time_status == "not measured":
            assert math.isnan(oc.time_error) and "(time not measured)" in repr(conv)
            continue
        if tiny_ok and true <= 1e-9 * abs(oc.value):
            assert oc.time_error <= 1e-8 * abs(oc.value), (name, oc.time_error, true)
            continue
        assert true > 1e-9 * abs(oc.value), (name, true)
        assert true / 10 <= oc.time_error <= 10 * true, (name, oc.time_error, true)
    return conv


def test_the_knobs_named_in_the_refusals_measure_the_time_error_within_10x():
    """What the refusals name works: verlet under cfl control with a time.cfl ladder, and
    dp54 and radau5 with the rtol ladder, give a time error within 10x of the true one."""
    cfg = _mu100(0.6)
    conv = _check_time_error(cfg.override({"time.integrator": "verlet",
                                           "time.control": "cfl"}), [5, 10, 20])
    assert conv.time_key == "time.cfl"
    for name in ("dp54", "radau5"):
        c = cfg.override({"time.integrator": name, "time.control": "cfl",
                          "time.rtol": 1e-3, "time.atol": 1e-6})
        # max_floor_force from the dense output between the steps (stepping.extremes):
        # from the step points alone radau5's spread along the ladder was their sampling
        # error (0.55 against a true time error of 0.027)
        conv = _check_time_error(c, [5, 10, 20], tiny_ok=True,
                                 names=("restitution_first", "contact_time_first",
                                        "max_floor_force"))
        assert conv.time_key == "time.rtol"


@pytest.mark.slow   # verlet at N = 20 on its time.cfl ladder: 25.6 million steps
def test_verlet_time_error_on_the_paper_mu100_ladder():
    cfg = _mu100(1.0, **{"time.integrator": "verlet", "time.control": "cfl"})
    _check_time_error(cfg, [10, 20, 40])


def test_predictability_time_of_synthetic_histories():
    """The runs' own error bar: a ladder whose differences shrink by 4 per refinement keeps
    the trajectory however large they grow; one whose differences saturate (chaos) loses
    it when the finest pair's difference reaches half the coarsest pair's."""
    from rodjit.analysis.converge import predictability_time

    t = np.linspace(0, 5, 5001)
    u = np.stack([np.sin(t), 1 + np.sin(t)], axis=1)
    grow = np.exp(3 * t)[:, None]
    # converging: differences 16, 4, 1 × 1e-4·e^{3t} (up to 3e2 m: no fixed fraction of the
    # range would call that agreement, the ladder's convergence does)
    conv = [(t, u + 16e-4 * grow), (t, u + 4e-4 * grow), (t, u + 1e-4 * grow)]
    assert predictability_time(conv, 5.0) == math.inf
    # chaotic: the same growth, saturating at 1 (unrelated trajectories); the coarse pair
    # peaks at 0.75 when the coarsest saturates, the fine pair's 3e-6·e^{3t} reaches half
    # of it at t = ln(1.25e5)/3 = 3.91 (a fixed 1 % of the range, 0.03, would say 3.07)
    sat = [(t, u + np.minimum(d * grow, 1.0)) for d in (16e-6, 4e-6, 1e-6)]
    assert predictability_time(sat, 5.0) == pytest.approx(math.log(1.25e5) / 3, abs=0.002)
    same = [(t, u), (t, u + 1e-12), (t, u + 2e-12)]
    assert predictability_time(same, 5.0) == math.inf       # below the noise floor
    assert math.isnan(predictability_time([(t, u), None, (t, u)], 5.0))
    assert math.isnan(predictability_time([(t, u), (t, u)], 5.0))   # two runs: no error bar
    assert math.isnan(predictability_time([(t[:0], u[:0])] * 3, 5.0))


def test_predictability_time_of_the_chaotic_and_the_damped_paper_runs():
    """paper-mu0 is chaotic: its default time ladder from rtol 1e-4 (/4, /16) loses the
    trajectory before t = 5 s (from the default rtol 1e-6, which "auto" divides by the
    run's length, it keeps it); paper-mu100 settles and keeps it."""
    mu0 = rodjit.load_preset("paper-mu0").override({"time.rtol": 1e-4})
    conv = converge(mu0, {"rod.N": [5, 10]}, time_at=5, observables=["restitution_first"],
                    jobs=1)
    assert conv.time_key == "time.rtol"
    assert 0 < conv.predictability_time < 5.0
    assert "predictability_time: " in repr(conv)
    mu100 = rodjit.load_preset("paper-mu100")
    conv = converge(mu100, {"rod.N": [5, 10]}, time_at=5,
                    observables=["restitution_first"], jobs=1)
    assert conv.predictability_time == math.inf
    assert "none before t_end" in repr(conv)


def test_tolerance_ladder_bars_contain_the_error_against_a_tight_reference():
    """A three-level dp54 tolerance ladder (its differences alternate: no order) prints
    bars that contain the error measured against dop853 at rtol 1e-12 (another scheme, far
    tighter): the bare last difference (5.6e-7) was short of the contact time's error
    (6.7e-7)."""
    cfg = rodjit.load_preset("paper-mu0").override({
        "time.t_end": 1.0, "time.integrator": "dp54", "output.snapshot_interval": 0.0})
    names = ["restitution_first", "contact_time_first"]
    conv = converge(cfg, {"time.rtol": [1e-4, 2.5e-5, 6.25e-6]}, also=False,
                    observables=names, jobs=1)
    tight = cfg.override({"time.integrator": "dop853", "time.rtol": 1e-12,
                          "time.atol": 1e-14})
    ref = rodjit.analysis.observables(rodjit.simulate(tight))
    for name in names:
        oc = conv[name]
        assert math.isfinite(oc.value) and math.isfinite(oc.error), name
        assert abs(oc.value - ref[name]) <= oc.error, (name, oc.value, ref[name], oc.error)


def test_a_shock_forming_rod_ladder_prints_no_limit_not_a_bar():
    """μ = γ = 0 on a three-level rod.N ladder: the model has no continuum limit, so the
    first-bounce observables print their values along the ladder and "no limit" (no
    extrapolation, no ±), where an extrapolation printed 0.13606 ± 0.00051 for a contact
    time that finer rods put at 0.1379."""
    cfg = rodjit.load_preset("paper-mu0").override({
        "time.t_end": 0.7, "output.snapshot_interval": 0.0, "time.integrator": "dop853"})
    names = ["contact_time_first", "restitution_first"]
    conv = converge(cfg, {"rod.N": [20, 40, 80]}, also=False, observables=names, jobs=1)
    for name in names:
        oc = conv[name]
        assert oc.space.status == "no limit", name
        assert math.isnan(oc.value) and math.isnan(oc.error)
        line = [ln for ln in repr(conv).splitlines() if name in ln][0]
        assert "no limit" in line and "±" not in line
        assert all(f"{v:.6g}" in line for v in oc.space.values)


def test_a_bounce_past_the_predictability_time_gets_the_spread_of_the_ladder_not_a_bar():
    """N = 80 on a stiff floor at μ = 0: the first restitution converges along a tolerance
    ladder, the second does not (its release, near 1.47 s, lies past the predictability
    time that the ladder's heights give), so converge prints no bar for it, says why,
    and a tight run of another integrator lands on no value the ladder settles to."""
    cfg = rodjit.load_preset("paper-mu0").override({
        "rod.N": 80, "floor.kappa_b": 1e7, "floor.beta": 0.1, "time.t_end": 2.0})
    names = ["restitution_first", "restitution_second"]
    conv = converge(cfg, {"time.rtol": [1e-6, 1e-7, 1e-8]}, observables=names, jobs=1)
    assert conv.time_key is None and conv.key == "time.rtol"
    first, second = conv["restitution_first"], conv["restitution_second"]
    assert first.space.status == "converged" and first.error < 1e-5
    tight = rodjit.simulate(cfg.override({"time.integrator": "radau5", "time.rtol": 1e-10,
                                          "time.atol": 1e-12}))
    ref = rodjit.analysis.observables(tight)
    assert abs(first.value - ref["restitution_first"]) <= first.error
    # the second bounce: no settled value, and the ladder's heights part before it ends
    assert second.space.status in ("not converging", "oscillating")
    values = second.space.values
    assert max(values) - min(values) > 1e-3
    release = (rodjit.analysis.macroscopic_contacts(
        tight.diagnostics, tight.episodes, tight.bounces,
        rodjit.analysis.physics_of(tight))["t_release"][1])
    assert 0 < conv.predictability_time < release
    text = repr(conv)
    assert f"predictability_time: {conv.predictability_time:.4g} s" in text
    assert ("restitution_second: the runs along the time.rtol ladder disagree after "
            f"t = {conv.predictability_time:.4g} s") in text
    assert not math.isfinite(second.error) or abs(second.value - ref["restitution_second"]) \
        <= second.error


def test_an_oscillating_time_ladder_adds_its_own_spread_to_the_time_error():
    """Where the time ladder does not settle (its differences alternate), its finest value
    is no reference: the time error is the base value's distance to it plus the ladder's
    own error, so it covers the spread along the ladder."""
    cfg = rodjit.load_preset("paper-mu0").override({
        "rod.N": 80, "floor.kappa_b": 1e7, "floor.beta": 0.1, "time.t_end": 2.0})
    conv = converge(cfg, {"rod.N": [40, 80]}, also={"time.rtol": [1e-6, 1e-8, 1e-10]},
                    time_at=80, observables=["restitution_second"], jobs=1)
    oc = conv["restitution_second"]
    assert oc.time.status == "oscillating"
    here = oc.space.values[-1]
    assert oc.time_error == pytest.approx(abs(here - oc.time.values[-1]) + oc.time.error)
    assert all(abs(here - v) <= oc.time_error for v in oc.time.values)
