"""The always-defined observables: macroscopic contacts, first-impact restitution, the
vibration energy, and the two situations where per-bounce values mislead."""
from __future__ import annotations

import math

import numpy as np
import pytest

import rodjit
from rodjit.analysis import (energy_vibration, first_impact, lift_energy,
                             macroscopic_contacts, merge_episodes, observables, physics_of,
                             wave_speed)

PAPER = rodjit.load_preset("paper-mu100")
STIFF = rodjit.Config().override({"floor.kappa_b": 1e5, "floor.beta": 1e-3, "rod.N": 5,
                                  "time.t_end": 10.0, "rod.mu": 0.0,
                                  "output.snapshot_interval": 0.0,
                                  "time.integrator": "verlet", "time.control": "cfl"})


@pytest.fixture(scope="module")
def stiff_run():
    return rodjit.simulate(STIFF)


def test_merge_episodes_groups_gaps_shorter_than_the_merge_time():
    t_s = np.array([0.0, 0.10, 0.21, 1.0, 1.05])
    t_e = np.array([0.05, 0.15, 0.30, 1.01, 1.2])
    assert merge_episodes(t_s, t_e, 0.08) == [(0, 2), (3, 4)]
    assert merge_episodes(t_s, t_e, 0.03) == [(0, 0), (1, 1), (2, 2), (3, 3), (4, 4)]
    assert merge_episodes([], [], 0.1) == []


def test_wave_speed_and_lift_energy_of_the_aiki_kosugi_rod():
    assert wave_speed(PAPER) == pytest.approx(math.sqrt(5 * 100.0 / 4))
    # standing on the floor under its weight: a little below the undeformed rod's −g/2
    e = lift_energy(PAPER)
    assert 0.5 * 9.81 - 0.2 < e < 0.5 * 9.81
    # linear elasticity: strain g(1 - x)/E, energy |g|/2 - g²/(6E); the stiffening of f
    # under compression and N = 5 take a few per cent off the difference
    E = 5 * 100.0 / 4
    assert 0.5 * 9.81 - e == pytest.approx(9.81 ** 2 / (6 * E), rel=0.1)
    fine = lift_energy(PAPER.override({"rod.N": 400, "rod.kappa": 1e4}))
    assert 0.5 * 9.81 - fine == pytest.approx(9.81 ** 2 / (6 * 1.25e4), rel=1e-2)
    assert lift_energy(PAPER.override({"gravity.g": 0.0})) == 0.0
    assert lift_energy(PAPER.override({"gravity.g": 1.0})) == -math.inf


def test_energy_vibration_is_kinetic_energy_about_the_centre_of_mass_plus_elastic():
    diag = {"cm_velocity": np.array([2.0]), "energy_kinetic": np.array([2.5]),
            "energy_stretch": np.array([0.25]), "energy_bend": np.array([0.125])}
    assert energy_vibration(diag)[0] == pytest.approx(2.5 - 2.0 + 0.25 + 0.125)


def test_energy_vibration_is_conserved_in_free_flight_at_mu_0():
    # a pre-strained rod falling without touching the floor: rigid motion and vibration
    # decouple under uniform gravity
    cfg = rodjit.Config().override({"initial.strain": 0.05, "time.t_end": 0.3,
                                    "output.snapshot_interval": 0.0})
    r = rodjit.simulate(cfg)
    ev = energy_vibration(r.diagnostics)
    assert ev[0] > 0.05
    # to the integrator's energy error (its total energy wobbles as much)
    assert np.ptp(ev) < 1e-3 * ev[0]
    assert np.ptp(ev) < 2 * np.ptp(r.diagnostics["energy_total"]) + 1e-12


def test_paper_setting_first_impact_agrees_with_the_bounce_table():
    r = rodjit.simulate(PAPER)
    fi = first_impact(r.diagnostics, r.episodes, r.bounces, physics_of(r))
    assert fi.status == "lift-off" and fi.reason == ""
    # one episode, bounded by apexes: the event tracking's values, here carried from the
    # samples along the exact free-flight parabola
    assert fi.restitution == pytest.approx(r.bounces["restitution"][0], rel=1e-9)
    assert fi.w_release == pytest.approx(r.bounces["w_release"][0], rel=1e-9)
    assert fi.contact_time == pytest.approx(r.bounces["t_release"][0] - r.bounces["t_impact"][0])
    assert fi.min_u0 == pytest.approx(r.bounces["min_u0"][0])
    # dropped from rest at height 1: w_impact = -sqrt(2|g|·1)
    assert fi.w_impact == pytest.approx(-math.sqrt(2 * 9.81), rel=1e-9)
    assert 0 <= fi.restitution_apex <= fi.restitution


def test_mu_10_on_the_paper_setting_reports_no_lift_off_with_the_rebound_speed():
    r = rodjit.simulate(PAPER.override({"rod.mu": 10.0, "time.t_end": 3.0}))
    assert r.bounces["open"][-1] and math.isnan(r.bounces["restitution"][0])  # the symptom
    obs = observables(r)
    assert obs["status"] == "no lift-off"
    assert obs["restitution_first"] == 0.0 and obs["restitution_apex_first"] == 0.0
    assert obs["contact_time_first"] == math.inf
    # the centre of mass rises while the bottom stays pressed: 0.17 of the impact speed
    assert 0.1 * math.sqrt(2 * 9.81) < obs["rebound_speed_first"] < 0.25 * math.sqrt(2 * 9.81)
    assert "never leaves the floor" in obs["reason"] and "of the impact speed" in obs["reason"]
    # a contact that never ends leaves no second one
    assert not any(isinstance(v, float) and math.isnan(v) for k, v in obs.items()
                   if k not in ("vibration_share_first", "restitution_second",
                                "contact_time_second"))
    assert math.isnan(obs["restitution_second"]) and math.isnan(obs["contact_time_second"])


def test_the_second_contact_observables_are_the_second_row_of_the_bounce_table():
    """paper-mu0 lifts off twice in 2 s: the second contact's restitution and contact time
    are those of the bounce table's second row; paper-mu100 lands a second time and never
    leaves the floor again (0 and inf, as for a first contact); before a second impact
    there is none (NaN, "no impact" with its reason)."""
    r = rodjit.simulate(rodjit.load_preset("paper-mu0").override({"time.t_end": 2.0}))
    obs = observables(r)
    b = r.bounces
    assert obs["restitution_second"] == pytest.approx(b["restitution"][1], rel=1e-12)
    assert obs["contact_time_second"] == pytest.approx(b["t_release"][1] - b["t_impact"][1],
                                                       rel=1e-12)
    assert obs["restitution_second"] != obs["restitution_first"]
    r = rodjit.simulate(PAPER.override({"time.t_end": 2.0}))
    obs = observables(r)
    assert obs["restitution_first"] > 0 and obs["status"] == "lift-off"
    assert obs["restitution_second"] == 0.0 and obs["contact_time_second"] == math.inf
    r = rodjit.simulate(PAPER.override({"time.t_end": 0.5}))
    obs = observables(r)
    assert math.isnan(obs["restitution_second"]) and math.isnan(obs["contact_time_second"])
    second = first_impact(r.diagnostics, r.episodes, r.bounces, physics_of(r), 1)
    assert second.status == "no impact"
    assert second.reason == "1 macroscopic contact(s), not 2, before t = 0.5"


def test_a_contact_open_with_energy_to_spare_is_reported_open_with_the_reason():
    r = rodjit.simulate(PAPER.override({"rod.mu": 10.0, "time.t_end": 0.47}))
    fi = first_impact(r.diagnostics, r.episodes, r.bounces, physics_of(r))
    assert fi.status == "open" and math.isnan(fi.restitution)
    assert "run longer" in fi.reason


def test_no_impact_is_reported_as_such():
    r = rodjit.simulate(PAPER.override({"time.t_end": 0.2}))
    fi = first_impact(r.diagnostics, r.episodes, r.bounces, physics_of(r))
    assert fi.status == "no impact" and "never touched" in fi.reason


def test_without_diagnostics_the_observables_say_what_they_need():
    r = rodjit.simulate(PAPER.override({"output.diagnostics_interval": 0.0, "time.t_end": 1.0}))
    with pytest.raises(ValueError, match="diagnostics_interval"):
        observables(r)


def test_gaps_shorter_than_the_sample_spacing_merge():
    # N = 200: π h/c = 1.4 ms, samples every 1 ms and every 5 ms give the same first contact
    fine = rodjit.simulate(PAPER.override({"rod.N": 200, "time.t_end": 1.0}))
    coarse = rodjit.simulate(PAPER.override({"rod.N": 200, "time.t_end": 1.0,
                                             "output.diagnostics_interval": 0.005}))
    a, b = observables(fine), observables(coarse)
    assert a["status"] == b["status"] == "lift-off"
    # (steps land on the output times, so the runs differ by the time-stepping error)
    assert a["restitution_first"] == pytest.approx(b["restitution_first"], rel=1e-3)


def test_stiff_floor_macroscopic_restitutions_are_explained_by_the_energies(stiff_run):
    r = stiff_run
    e_table = r.bounces["restitution"][~r.bounces["open"]]
    assert np.nanmax(e_table) > 5          # the bookkeeping artefact of the bounce table
    phys = physics_of(r)
    mc = macroscopic_contacts(r.diagnostics, r.episodes, r.bounces, phys)
    done = ~mc["open"]
    assert done.sum() >= 10
    e, w_i = mc["restitution"][done], mc["w_impact"][done]
    ev_i, ev_r = mc["ev_impact"][done], mc["ev_release"][done]
    dz = mc["z_release"][done] - mc["z_impact"][done]
    assert np.all(w_i < 0) and np.all(np.isfinite(e))
    # energy at the two ends (floor energy 0, μ = 0):
    # e² = 1 + 2(E_vib,impact − E_vib,release + g Δz)/w_impact²
    explained = 1 + 2 * (ev_i - ev_r + phys.g * dz) / w_i ** 2
    assert np.allclose(e ** 2, explained, rtol=1e-3, atol=2e-3)
    # and the bound: rigid-body kinetic energy gained at most the vibration energy brought in
    bound = 1 + 2 * (ev_i + phys.g * dz) / w_i ** 2
    assert np.all(e ** 2 <= bound * (1 + 1e-3) + 2e-3)
    # a restitution above 1 only where vibration energy came into the impact
    ratio = mc["vibration_ratio"][done]
    assert np.all(ratio[e > 1] > 0.1)
    # the micro-contacts of the first impacts are merged (the bounce table's split is gone)
    assert np.all(mc["n_episodes"][:5] > 1) and np.all(e[:5] < 1)


def test_stiff_floor_first_impact_merges_its_micro_contacts(stiff_run):
    r = stiff_run
    fi = first_impact(r.diagnostics, r.episodes, r.bounces, physics_of(r))
    assert fi.status == "lift-off" and fi.n_episodes > 1
    # the Saint-Venant contact time of a rod on a rigid floor is 2/c
    assert fi.contact_time == pytest.approx(2 / wave_speed(STIFF), rel=0.5)
    assert 0.5 < fi.restitution <= 1.0 + 1e-9
