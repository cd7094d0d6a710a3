"""One bounce is one physical impact (MODEL.md §3): checked against an independent SciPy
reference of the definition, on the stiff floors where cutting bounces at every apex of the
centre of mass split one impact into two, and on files written before the definition."""
from __future__ import annotations

import math
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

import rodjit
from rodjit.output import hdf5
from rodjit.reports import info
from rodjit.sweeps import sweep_file

from reference import bounces as RB
from reference.laws import Params

FIXTURES = Path(__file__).parent / "fixtures"
APEX_RUN, APEX_PARTIAL, APEX_SWEEP = (FIXTURES / f"apex_{n}.h5"
                                      for n in ("run", "partial", "sweep"))

# the stiff floors of the definition's check: κ_b × β × N at μ = 0 (paper-mu0)
STIFF = [(kb, beta, n) for kb in (1e4, 1e6) for beta in (0.05, 1e-3) for n in (5, 50)]
T_CHECK = 3.0     # three bounces or more on each


def stiff(kb, beta, n, t_end=T_CHECK):
    return rodjit.load_preset("paper-mu0").override(
        {"floor.kappa_b": kb, "floor.beta": beta, "rod.N": n, "time.t_end": t_end})


def reference_first(kb, beta, n):
    """The first bounce of the SciPy reference (Radau at rtol 1e-9)."""
    p = Params(mu=0.0, kappa_b=kb, beta=beta)
    ev = RB.events(n, p, 2.0, rtol=1e-9, stop_after_bounces=1)
    return RB.group(ev, RB.flight_time(n, p))[0]


def _check_against_reference(kb, beta, n):
    b = rodjit.simulate(stiff(kb, beta, n, t_end=1.2)).bounces
    ref = reference_first(kb, beta, n)
    assert b["n_episodes"][0] == ref.n_episodes
    assert b["t_impact"][0] == pytest.approx(ref.t_impact, abs=1e-7)
    assert b["t_release"][0] == pytest.approx(ref.t_release, abs=1e-5)
    assert b["restitution"][0] == pytest.approx(ref.restitution, rel=1e-4)
    # a rigid fall brings no vibration in: the energy restitution is the restitution
    assert b["restitution_energy"][0] == pytest.approx(ref.restitution, rel=1e-4)
    assert not b["ambiguous"][0]


@pytest.mark.slow
@pytest.mark.parametrize("kb, beta", [(1e6, 0.05), (1e4, 1e-3)])
def test_first_bounce_matches_the_scipy_reference_n5(kb, beta):
    _check_against_reference(kb, beta, 5)


@pytest.mark.slow    # the reference takes about a minute and a half at N = 50
@pytest.mark.parametrize("kb, beta", [(1e6, 0.05), (1e4, 1e-3)])
def test_first_bounce_matches_the_scipy_reference_n50(kb, beta):
    """κ_b = 1e6, β = 0.05, N = 50: the impact cut at a spurious apex into 0.0011 and 360.9
    by the apex definition; one bounce of 0.85475, 76 episodes, by the reference."""
    _check_against_reference(kb, beta, 50)


@pytest.mark.slow
@pytest.mark.parametrize("kb, beta, n", STIFF)
def test_stiff_floor_bounces_are_impacts(kb, beta, n):
    """The first bounce is the first impact (the macroscopic contact of the observables,
    grouped again in Python from the diagnostics); every energy restitution lies in
    [0, 1.001]; no restitution above 1.5 on a bounce not marked ambiguous."""
    r = rodjit.simulate(stiff(kb, beta, n))
    b = r.bounces
    assert b["t_impact"].size >= 3
    assert b["restitution"][0] == pytest.approx(rodjit.observables(r)["restitution_first"],
                                                rel=1e-9)
    # the Python rule over the episodes groups them as the compiled tracker did
    c = rodjit.analysis.macroscopic_contacts(r.diagnostics, r.episodes, b,
                                             rodjit.analysis.physics_of(r))
    assert c["n_episodes"].tolist() == b["n_episodes"].tolist()
    e_energy = b["restitution_energy"][~np.isnan(b["restitution_energy"])]
    assert e_energy.size >= b["t_impact"].size - 1
    assert np.all((e_energy >= 0) & (e_energy <= 1.001))
    sure = ~b["ambiguous"]
    assert np.all(b["restitution"][sure] <= 1.5)
    assert np.all(b["w_impact"][sure] < 0) and np.all(b["w_release"][sure] > 0)
    assert b["ambiguous"][-1] or not b["open"][-1]


def test_a_pending_bounce_is_ambiguous_and_the_means_skip_it():
    """A run stopped in the flight time after a release: the bounce is not over."""
    full = rodjit.simulate(stiff(1e6, 0.05, 50, t_end=1.2)).bounces
    t_stop = full["t_release"][0] + 0.5 * math.pi / (50 * math.sqrt(125.0))
    b = rodjit.simulate(stiff(1e6, 0.05, 50, t_end=t_stop)).bounces
    assert b["t_impact"].size == 1 and b["ambiguous"][0] and not b["open"][0]
    assert np.isnan(b["restitution_energy"][0])
    table = rodjit.sweep(stiff(1e6, 0.05, 5, t_end=1.2), {"floor.beta": [0.05]}, jobs=1,
                         scheduler="inline", handle_signals=False)
    got = table.bounces(0)
    sure = ~got["ambiguous"]
    assert table["restitution_mean"][0] == pytest.approx(got["restitution"][sure].mean())
    assert table["restitution_energy_mean"][0] == pytest.approx(
        got["restitution_energy"][sure].mean())
    # the first-impact observer and the bounce table take w at release from the same step
    # by two sums: they agree to round-off (2e-12 under dop853)
    assert table["restitution_first"][0] == pytest.approx(got["restitution"][0], rel=1e-10)


# ---- files of the apex definition (run-file and sweep-file format 2) ------------------------
def test_apex_run_file_reads_with_its_rows_ambiguous():
    r = rodjit.load_file(APEX_RUN)
    b = r.bounces
    assert list(b) == list(rodjit.simulate(stiff(1e6, 0.05, 5, t_end=0.01)).bounces)
    assert b["n_episodes"].tolist() == [41, 35]          # one impact cut at a spurious apex
    assert b["ambiguous"].dtype == bool and b["ambiguous"].all()
    assert np.isnan(b["restitution_energy"]).all()
    assert np.isnan(b["energy_vibration_impact"]).all()
    # the observables group its episodes by today's rule: one impact
    assert rodjit.observables(r)["restitution_first"] == pytest.approx(0.854752, abs=2e-6)
    assert "format 2" in info(APEX_RUN)
    ds = rodjit.open_run(APEX_RUN)
    assert ds["bounce_ambiguous"].values.all()


def test_apex_run_file_is_rebuilt_to_continue(tmp_path):
    path = tmp_path / APEX_PARTIAL.name
    shutil.copyfile(APEX_PARTIAL, path)
    rodjit.resume_file(path, t_end=1.0, handle_signals=False)
    with h5py.File(path, "r") as f:
        assert int(f.attrs["format_version"]) == hdf5.FORMAT_VERSION
        assert "ambiguous" in f["bounces"]
    a = rodjit.load_file(path)
    fresh = rodjit.simulate(a.config.override({"time.t_end": 1.0}))
    # the file's first 0.5 s were stepped by the energy step's controller of its time (error
    # per step), the rest by today's (per unit step): the same run to its tolerance, not bit
    # for bit (resuming today's files is bit for bit: tests/test_golden.py)
    np.testing.assert_allclose(a.u_final, fresh.u_final, rtol=0, atol=1e-4)
    # the first impact was running at the checkpoint: one bounce, as a fresh run has it
    assert a.bounces["n_episodes"].tolist() == fresh.bounces["n_episodes"].tolist()
    assert a.bounces["restitution"][0] == pytest.approx(fresh.bounces["restitution"][0],
                                                        rel=1e-4)
    assert np.isnan(a.bounces["energy_vibration_impact"][0])    # not in that checkpoint


def test_apex_sweep_file_reads_with_todays_names_and_refuses_to_continue(tmp_path):
    t = rodjit.load_sweep(APEX_SWEEP)
    with h5py.File(APEX_SWEEP, "r") as f:
        old = {k: f["summary"][k][()] for k in ("restitution_impact", "restitution_first")}
    assert np.array_equal(t["restitution_first"], old["restitution_impact"])
    assert np.array_equal(t["restitution_first_apex_bounces"], old["restitution_first"])
    assert np.isnan(t["restitution_energy_mean"]).all()
    b = t.bounces(0)
    assert b["ambiguous"].all() and np.isnan(b["restitution_energy"]).all()
    path = tmp_path / APEX_SWEEP.name
    shutil.copyfile(APEX_SWEEP, path)
    with pytest.raises(ValueError, match="format 2.*start a new sweep"):
        rodjit.sweep(output=path, resume=True, jobs=1, scheduler="inline",
                     handle_signals=False)
    assert sweep_file.FORMAT_VERSION not in (1, 2)


def test_a_point_without_diagnostics_takes_the_first_bounce_from_its_table():
    from rodjit.sweeps.point import PointTask, run_point

    cfg = stiff(1e6, 0.05, 5, t_end=1.2).override({"output.diagnostics_interval": 0.0})
    got = run_point(PointTask(0, cfg, None, ()))
    b = got.bounces
    assert got.values["impact_status"] == "undefined"
    assert got.values["restitution_first"] == b["restitution"][0]
    assert got.values["contact_time_first"] == b["t_release"][0] - b["t_impact"][0]
