"""The peers of benchmarks/bench_peers.py integrate the same system as rodjit.

benchmarks/peer_rhs.py is the right-hand side handed to CyRK, SUNDIALS CVODE and SciPy; it
must equal rodjit's plain-NumPy reference (rodjit.model.reference.rhs, MODEL.md §2) on
admissible states, in both state orderings, and through each peer's own calling
convention (CyRK's C callback, scikit-sundae's in-place callback) where the peer is
installed.
"""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import peer_rhs  # noqa: E402

from rodjit.model.reference import rhs as reference_rhs  # noqa: E402
from rodjit.model.system import build_system, check_admissible  # noqa: E402
from rodjit.presets import load_preset  # noqa: E402

CASES = [
    ("paper-mu0", {}),
    ("paper-mu100", {}),
    ("paper-mu0", {"rod.N": 40, "floor.kappa_b": 1e5, "floor.beta": 1e-3, "rod.mu": 0.1}),
    ("paper-mu100", {"rod.N": 7, "rod.gamma": 0.02}),       # the bending term too
]


def random_states(cfg, rng, count=20):
    """Admissible states: strains in (−0.6, 0.6), the bottom from −0.9β to above the
    floor (so both sides of σ_b's kink at 0), velocities O(5 m/s)."""
    n = cfg.rod.N
    beta = cfg.floor.beta
    _, rod, floor = build_system(cfg)
    for k in range(count):
        eps = rng.uniform(-0.6, 0.6, n)
        u0 = -0.9 * beta * rng.uniform() if k % 2 == 0 else rng.uniform(0.0, 0.5)
        u = u0 + np.concatenate([[0.0], np.cumsum((1.0 + eps) / n)])
        check_admissible(u, rod, floor)
        v = rng.normal(0.0, 5.0, n + 1)
        yield np.concatenate([u, v])


def _close(got, want):
    scale = np.abs(want).max()
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * scale)


@pytest.mark.parametrize("preset,over", CASES)
def test_peer_rhs_equals_reference(preset, over):
    cfg = load_preset(preset).override(over)
    system, rod, floor = build_system(cfg)
    p = peer_rhs.params(cfg)
    rng = np.random.default_rng(19)
    for y in random_states(cfg, rng):
        want = reference_rhs(0.0, y, system, rod, floor)
        dy = np.empty_like(y)
        peer_rhs.rhs_split(0.0, y, dy, p)
        _close(dy, want)
        yi = peer_rhs.interleave(y)
        dyi = np.empty_like(yi)
        peer_rhs.rhs_interleaved(0.0, yi, dyi, p)
        _close(peer_rhs.deinterleave(dyi), want)


def test_orderings_round_trip():
    y = np.arange(12.0)
    assert np.array_equal(peer_rhs.deinterleave(peer_rhs.interleave(y)), y)
    assert np.array_equal(peer_rhs.interleave(y)[:4], [0.0, 6.0, 1.0, 7.0])


def test_params_refuse_other_laws():
    """peer_rhs writes the Aiki–Kosugi laws out; a config with another law is refused."""
    cfg = load_preset("paper-mu0")

    class OtherRod:
        law = "a-user-law"

    class Cfg:
        rod = OtherRod()
        floor = cfg.floor

    with pytest.raises(ValueError, match="Aiki–Kosugi"):
        peer_rhs.params(Cfg())


@pytest.mark.skipif(importlib.util.find_spec("CyRK") is None,
                    reason="CyRK not installed (pip install rodjit[bench])")
def test_cyrk_callback_equals_reference():
    import ctypes

    import bench_peers

    cfg = load_preset("paper-mu100").override({"rod.N": 9})
    system, rod, floor = build_system(cfg)
    p = peer_rhs.params(cfg)
    addr = bench_peers._cyrk_address()
    fn = ctypes.CFUNCTYPE(None, ctypes.POINTER(ctypes.c_double), ctypes.c_double,
                          ctypes.POINTER(ctypes.c_double),
                          ctypes.POINTER(ctypes.c_double))(addr)
    dptr = ctypes.POINTER(ctypes.c_double)
    for y in random_states(cfg, np.random.default_rng(5), 6):
        dy = np.zeros_like(y)
        fn(dy.ctypes.data_as(dptr), 0.0, y.ctypes.data_as(dptr), p.ctypes.data_as(dptr))
        _close(dy, reference_rhs(0.0, y, system, rod, floor))


@pytest.mark.skipif(importlib.util.find_spec("sksundae") is None,
                    reason="scikit-sundae not installed (pip install rodjit[bench])")
def test_cvode_callback_equals_reference():
    import bench_peers

    cfg = load_preset("paper-mu0").override({"rod.N": 6})
    system, rod, floor = build_system(cfg)
    p = peer_rhs.params(cfg)
    for y in random_states(cfg, np.random.default_rng(6), 6):
        yi = peer_rhs.interleave(y)
        yi.setflags(write=False)            # CVODE hands the state read-only
        dyi = np.zeros_like(yi)
        bench_peers._cvode_rhs(0.0, yi, dyi, (p,))
        _close(peer_rhs.deinterleave(dyi), reference_rhs(0.0, y, system, rod, floor))


# ---- the prototype integrators of benchmarks/proto_high_order.py ------------------------
def _flight_problem():
    """The rod in free flight with a stretched start (it vibrates; no contact before
    t = 0.3 s), snapshots every 5 ms."""
    import bench_peers
    from scipy.integrate import solve_ivp

    pb = bench_peers.Problem("paper-mu0")
    cfg = pb.cfg.override({"initial.strain": 0.05})
    pb.p = peer_rhs.params(cfg)
    from rodjit.model.system import initial_state
    pb.y0 = np.concatenate(initial_state(cfg))
    pb.t_eval = pb.t_eval[:61]                       # t ≤ 0.3 s

    def fun(t, y):
        dy = np.empty_like(y)
        peer_rhs.rhs_split(t, y, dy, pb.p)
        return dy

    ref = solve_ivp(fun, (0.0, pb.t_eval[-1]), pb.y0, method="DOP853", rtol=1e-13,
                    atol=1e-13, t_eval=pb.t_eval).y
    return pb, ref


@pytest.mark.parametrize("name,order", [("verlet", 2), ("yoshida4", 4), ("yoshida6", 6)])
def test_prototype_compositions_reach_their_order(name, order):
    import proto_high_order as proto

    pb, ref = _flight_problem()
    assert ref[0].min() > 0.0                        # no contact in the window
    method = proto.Proto(name)
    cfl = {2: 0.05, 4: 0.1, 6: 0.1}[order]      # in the asymptotic range
    errs = [pb.error(method.run(pb, c)[1], ref) for c in (cfl, cfl / 2)]
    measured = np.log2(errs[0] / errs[1])
    assert abs(measured - order) < 0.3, (errs, measured)


@pytest.mark.parametrize("name", ["dp54", "dop853"])
def test_prototype_pairs_meet_tolerance_and_land_on_outputs(name):
    import proto_high_order as proto

    pb, ref = _flight_problem()
    method = proto.Proto(name)
    for tol in (1e-3, 1e-6, 1e-9):
        _, y, info = method.run(pb, tol)
        assert pb.error(y, ref) < 30 * tol, (tol, pb.error(y, ref))
    assert info["steps"] >= pb.t_eval.size - 1          # at least one step per output


# ---- the benchmark's bookkeeping -------------------------------------------------------
def test_breakdown_splits_a_call_into_its_loop_and_the_rest():
    """``breakdown`` interpolates the whole calls and the loops on their own fronts: at a
    measured accuracy it returns that point's call and loop, between two points the
    log-log interpolation of each, and None where no point is accurate enough; a dominated
    point (slower and less accurate) is not on either front."""
    import bench_peers

    def point(error, best, loop):
        return {"error": error, "times": [best], "best": best, "run_time": loop}

    pts = [point(1e-3, 4e-4, 2e-4), point(1e-2, 3e-4, 1e-4),
           point(2e-2, 5e-4, 3e-4)]                       # dominated by the 1e-2 point
    assert bench_peers.breakdown(pts, 1e-2) == pytest.approx((3e-4, 1e-4), rel=1e-12)
    assert bench_peers.breakdown(pts, 1e-3) == pytest.approx((4e-4, 2e-4), rel=1e-12)
    # beyond the least accurate point on the front: that point, never the dominated one
    assert bench_peers.breakdown(pts, 5e-2) == pytest.approx((3e-4, 1e-4), rel=1e-12)
    call, loop = bench_peers.breakdown(pts, 10 ** -2.5)  # halfway in log error
    assert call == pytest.approx(np.sqrt(4e-4 * 3e-4), rel=1e-12)
    assert loop == pytest.approx(np.sqrt(2e-4 * 1e-4), rel=1e-12)
    assert bench_peers.breakdown(pts, 1e-4) == (None, None)
    # a point timed without its loop (a peer's) leaves the loop front empty
    call, loop = bench_peers.breakdown([point(1e-3, 4e-4, None)], 1e-2)
    assert call == pytest.approx(4e-4, rel=1e-12) and loop is None


def test_work_at_takes_the_cheapest_accurate_call_and_its_cost_per_step():
    """``work_at`` picks the cheapest measured call whose error meets the accuracy, counts
    rodjit's rejected trials with its accepted steps and divides its loop time by them; a
    peer's whole call is divided by its steps; None where no call is accurate enough."""
    import bench_peers

    rodjit_pts = [
        {"error": 1e-3, "times": [5e-4], "best": 5e-4, "steps": 80, "rejected": 20,
         "run_time": 4e-4},
        {"error": 1e-4, "times": [9e-4], "best": 9e-4, "steps": 150, "rejected": 50,
         "run_time": 8e-4},
        {"error": 2e-3, "times": [3e-4], "best": 3e-4, "steps": 40, "rejected": 0,
         "run_time": 2e-4},
    ]
    w = bench_peers.work_at(rodjit_pts, 1e-3)
    assert w["trials"] == 100 and w["best"] == 5e-4
    assert w["per_trial"] == pytest.approx(4e-6, rel=1e-12)
    w = bench_peers.work_at(rodjit_pts, 1e-4)
    assert w["trials"] == 200 and w["per_trial"] == pytest.approx(4e-6, rel=1e-12)
    assert bench_peers.work_at(rodjit_pts, 1e-5) is None
    peer_pts = [{"error": 5e-4, "times": [6e-4], "best": 6e-4, "steps": 120},
                {"error": 1e-2, "times": [], "best": None}]       # a failed setting
    w = bench_peers.work_at(peer_pts, 1e-3)
    assert w["trials"] == 120 and w["per_trial"] == pytest.approx(5e-6, rel=1e-12)
    # a library that reports no step count (SciPy, CVODE give right-hand sides) is skipped
    assert bench_peers.work_at([{"error": 1e-4, "times": [1e-3], "best": 1e-3,
                                 "nfev": 900}], 1e-3) is None
