"""Episodes and bounces (MODEL.md §3): the bookkeeping fed synthetic steps, and the
records of a real run checked against their definitions."""
import numpy as np
import pytest

import rodjit
from rodjit.stepping import layout as L
from rodjit.stepping.events import open_contact, release, touchdown, track


class Tracker:
    """Feeds (t, u0, v0, w) samples to the compiled ``track`` as accepted steps."""

    def __init__(self, t0, u0, w0, flight_time=0.5):
        self.ev = np.zeros(L.EV_SIZE)
        self.ev[L.FLIGHT_TIME] = flight_time
        self.count = np.zeros(L.COUNT_SIZE, dtype=np.int64)
        self.episodes = np.zeros((16, 2))
        self.bounces = np.zeros((16, len(L.BOUNCE_ROW_COLUMNS)))
        self.prev = (t0, u0, 0.0, w0)
        if u0 < 0:
            open_contact(self.ev, t0, w0, u0, 0.0, 0.0, 0.0)

    def step(self, t, u0, w, ff=0.0, emin=0.0, g=-1e-12, evib=0.0):
        """A step along which u0 moves linearly (so crossings are at linear roots);
        ``evib``: the vibration energy at its start (read at a new bounce's impact); a
        tiny gravity: the centre of mass turns over only where ``w`` says so."""
        ta, ua, _, wa = self.prev
        slope = (u0 - ua) / (t - ta)
        track(self.ev, self.count, self.episodes, self.bounces, ta, t - ta, g, ua, slope, u0,
              slope, wa, w, ff, emin, evib, u0)
        self.prev = (t, u0, slope, w)

    @property
    def done(self):
        return self.bounces[: self.count[L.N_BOUNCE]]


def test_chattering_episodes_form_one_bounce_closed_by_the_apex():
    tr = Tracker(0.0, 1.0, -1.0)
    tr.step(1.0, 0.5, -2.0)                   # falling
    tr.step(2.0, -0.5, -1.0, ff=5.0, emin=-0.3)   # contact 1 starts at t = 1.5
    tr.step(3.0, 0.5, 0.5)                    # released at 2.5
    tr.step(4.0, -0.5, 0.2, ff=9.0, emin=-0.4)    # chatter: contact 2 (w never turned)
    tr.step(5.0, 0.5, 1.0)                    # released at 4.5
    tr.step(6.0, 1.0, 0.4)                    # flying up
    assert tr.count[L.N_EP] == 2 and tr.count[L.N_BOUNCE] == 0
    tr.step(7.0, 1.2, -0.2)                   # apex: closes the bounce
    (b,) = tr.done
    t_imp, t_rel, n_ep, w_imp, w_rel, e, min_u0, max_ff, min_eps, ev_i, e_energy, amb = b
    assert (t_imp, t_rel, n_ep) == (1.5, 4.5, 2)
    assert min_u0 == -0.5 and max_ff == 9.0 and min_eps == -0.4
    assert e == pytest.approx(-w_rel / w_imp)
    assert ev_i == 0.0 and e_energy == pytest.approx(e) and amb == 0.0
    assert np.allclose(tr.episodes[:2], [[1.5, 2.5], [3.5, 4.5]], atol=1e-12)


def test_an_apex_in_a_gap_shorter_than_the_flight_time_does_not_end_the_bounce():
    """The micro-gap of one impact: the centre of mass turns over while the bottom is off
    the floor for less than τ, so the next contact belongs to the same bounce; the bounce
    ends only once a release is followed by τ off the floor and a turn-over."""
    tr = Tracker(0.0, 1.0, -1.0, flight_time=2.5)
    tr.step(1.0, 0.5, -2.0, evib=0.3)
    tr.step(2.0, -0.5, -2.0, evib=0.3)        # impact at 1.5, E_vib = 0.3 then
    tr.step(3.0, 0.5, 0.1)                    # released at 2.5
    tr.step(4.0, 0.5, -0.1)                   # apex after 1.5 < τ off the floor
    assert tr.count[L.N_BOUNCE] == 0 and tr.ev[L.FLIGHT] == 1.0
    tr.step(4.5, -0.5, -0.2)                  # touches again at 4.25: the same bounce
    assert tr.count[L.N_BOUNCE] == 0 and tr.ev[L.B_NEP] == 2 and tr.ev[L.FLIGHT] == 0.0
    tr.step(5.0, 0.5, 1.5)                    # released at 4.75
    tr.step(6.0, 1.0, 0.5)
    tr.step(7.0, 1.2, -0.2)                   # apex, but only 2.25 < τ off the floor
    assert tr.count[L.N_BOUNCE] == 0
    tr.step(7.5, 1.1, -0.7)                   # 2.75 >= τ: the flight ends the bounce
    (b,) = tr.done
    assert b[L.BC_T_IMPACT] == 1.5 and b[L.BC_N_EPISODES] == 2
    assert b[L.BC_T_RELEASE] == pytest.approx(4.75)
    assert b[L.BC_RESTITUTION] == pytest.approx(1.5 / 2.0)
    assert b[L.BC_ENERGY_VIBRATION_IMPACT] == 0.3
    assert b[L.BC_RESTITUTION_ENERGY] == pytest.approx(1.5 / np.sqrt(4.0 + 0.6))
    assert b[L.BC_AMBIGUOUS] == 0.0


def test_a_bounce_whose_approach_is_slow_against_the_vibration_is_ambiguous():
    # |w_impact| = 0.1 below 0.2 sqrt(2 E_vib) = 0.2: ambiguous
    tr = Tracker(0.0, 1.0, -0.1, flight_time=0.1)
    tr.step(1.0, -1.0, -0.1, evib=0.5)
    tr.step(2.0, 1.0, 0.4)
    tr.step(3.0, 1.5, -0.1)
    (b,) = tr.done
    assert b[L.BC_AMBIGUOUS] == 1.0 and b[L.BC_RESTITUTION] == pytest.approx(4.0)
    assert b[L.BC_RESTITUTION_ENERGY] == pytest.approx(0.4 / np.sqrt(0.01 + 1.0))


def test_an_apex_without_contact_is_not_a_bounce_and_open_contact_stays_open():
    tr = Tracker(0.0, 1.0, 1.0)
    tr.step(1.0, 2.0, -1.0)                   # apex in flight: nothing to close
    assert tr.count[L.N_BOUNCE] == 0
    tr.step(2.0, -0.1, -2.0)                  # lands and stays
    tr.step(3.0, -0.2, 0.5)
    tr.step(4.0, -0.1, -0.5)                  # w turns while in contact: not an apex
    assert tr.count[L.N_BOUNCE] == 0 and tr.ev[L.IN_CONTACT] == 1.0 and tr.ev[L.B_NEP] == 1


def test_crossing_fractions_are_exact_for_free_fall():
    # u(t) = 1 − t²/2 (g = −1) from t = 0 over dt = 2: crosses 0 at t = √2
    s = touchdown(1.0, 0.0, 1.0 - 2.0, 2.0)
    assert s * 2.0 == pytest.approx(np.sqrt(2.0), rel=1e-15)
    # and backwards: u(t) = −1 + 2t − t²/2 over [0, 1]... released where it climbs past 0
    ua, ub, vb = -0.3, -0.3 + 1.0 - 0.5, 1.0 - 1.0
    s = release(ua, ub, vb, 1.0)
    assert -0.3 + s - 0.5 * s * s == pytest.approx(0.0, abs=1e-15)


def test_records_of_a_run_match_their_definitions():
    res = rodjit.simulate(rodjit.Config().override({"time.t_end": 8.0}))
    ep, b = res.episodes, res.bounces
    assert np.all(ep["t_start"] < ep["t_end"]) and np.all(ep["t_end"][:-1] < ep["t_start"][1:])
    assert b["n_episodes"].sum() == ep["t_start"].size + int(b["open"].sum())
    first = np.cumsum(np.concatenate([[0], b["n_episodes"][:-1]]))
    assert np.array_equal(b["t_impact"], ep["t_start"][first])
    done = ~b["open"]
    last = first + b["n_episodes"] - 1
    assert np.array_equal(b["t_release"][done], ep["t_end"][last[done]])
    assert np.allclose(b["restitution"][done], -b["w_release"][done] / b["w_impact"][done])
    # a bounce the run stopped in lists its release as provisional (docs/output.md: its
    # restitution_energy NaN); every bounce that ended was released rising
    ended = done & np.isfinite(b["restitution_energy"])
    assert ended.sum() >= done.sum() - 1
    assert np.all(b["w_impact"] < 0) and np.all(b["w_release"][ended] > 0)
    assert np.all((b["min_u0"] < 0) & (b["min_u0"] > -0.05))
    assert np.all(b["max_floor_force"] > 0) and np.all(b["min_strain"] > -1)
    # each gap between bounces is a flight: at least τ = π h/c long, w turns from + to −
    d = res.diagnostics
    tau = np.pi / (res.config.rod.N * np.sqrt(1.25 * res.config.rod.kappa))
    for t1, t2 in zip(b["t_release"][:-1], b["t_impact"][1:]):
        w = d["cm_velocity"][(d["t"] > t1) & (d["t"] < t2)]
        assert w.max() > 0 and w.min() < 0 and t2 - t1 >= tau
    # and no gap inside a bounce is: shorter than τ, or the centre of mass does not turn
    inner = np.ones(ep["t_start"].size - 1, bool)
    inner[first[1:] - 1] = False
    for k in np.flatnonzero(inner):
        t1, t2 = ep["t_end"][k], ep["t_start"][k + 1]
        w = d["cm_velocity"][(d["t"] > t1) & (d["t"] < t2)]
        assert t2 - t1 < tau or not (w.size and w.max() > 0 and w.min() < 0)
    ev = rodjit.analysis.energy_vibration(d)
    assert np.all(b["energy_vibration_impact"] >= -1e-12)
    assert np.allclose(b["energy_vibration_impact"][0], ev[0], atol=1e-12)   # a rigid fall
    over = done.copy()
    over[-1] = False              # the last may not be over: its restitution_energy is NaN
    assert np.allclose(b["restitution_energy"][over], b["w_release"][over] / np.sqrt(
        b["w_impact"][over] ** 2 + 2 * b["energy_vibration_impact"][over]))
    # extremes agree with the diagnostics sampled inside each bounce
    for i in np.flatnonzero(done):
        inside = (d["t"] >= b["t_impact"][i]) & (d["t"] <= b["t_release"][i])
        assert b["min_u0"][i] <= d["u_bottom"][inside].min() + 1e-15
        assert b["max_floor_force"][i] >= d["floor_force"][inside].max() - 1e-9
