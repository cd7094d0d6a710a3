"""rodjit against compiled ODE libraries at matched accuracy: CyRK (C++ solvers, Numba
right-hand side), SUNDIALS CVODE (scikit-sundae, banded Newton) and SciPy's solve_ivp.

Same system.  Every peer integrates the semi-discrete rod of MODEL.md §2 (lumped masses,
finite differences, the singular f and σ_b) through ``peer_rhs`` — a Numba right-hand side
written from MODEL.md independently of rodjit's kernels and checked against
``rodjit.model.reference.rhs`` by tests/test_bench_peers.py.  γ = 0 in every setting below
(the paper's, and the stiff floor's), so the bending term is not exercised here (peer_rhs
has it and the test covers it).  rodjit runs through its public API only
(``rodjit.simulate`` on a Config).

Settings (all run for T = 1 s, the accuracy window):
  paper-mu0     data/paper_mu0.toml   (N = 5, μ = 0)
  paper-mu100   data/paper_mu100.toml (N = 5, μ = 100)
  floor-N200    the stiff floor: N = 200, κ_b = 1e5, β = 1e-3, μ = 0.1 (otherwise paper-mu0)
  floor-N1000   the same with N = 1000

Output, like for like: every method delivers the state at the snapshot times 0, 0.005, …,
1 s (peers through ``t_eval``/output times, rodjit by landing its steps on them; rodjit
also writes its diagnostics row at each snapshot, ``output.diagnostics_interval`` set to
the snapshot interval, and tracks contacts and bounces).

Accuracy: the largest scaled state error over the snapshots, max(|u − u_ref|∞ / 1 m,
|v − v_ref|∞ / V), V = √(2|g|H) the impact speed, against a tight reference: CyRK DOP853
at rtol = atol = 1e-13 (SciPy DOP853 if CyRK is missing), checked against an independent
eighth-order method (CyRK Vern8 at 1e-13) and rodjit's ``energy`` at tol 1e-11; the
differences are printed, and an accuracy is reported only if it is ≥ 10× the first.  At
N = 1000 the explicit reference is stability-bound (minutes a run): DOP853 at 1e-12,
checked by rodjit's energy step only.

Cost: CPU time (``time.process_time``: the machine is shared, and CPU time is what load
from other processes disturbs least) of one solve call (a peer's call with its t_eval; ``rodjit.simulate``
including its configuration, setup and Result) after a warm-up call, so compile time is
excluded everywhere.  rodjit's ``stats['run_time']`` (the compiled loop alone) is stored
too.  Every method's accuracy knob (rtol = atol for the peers, ``time.cfl`` for verlet
and semi-implicit, ``time.rtol = time.atol`` for energy) is scanned on a half-decade grid,
coarse to fine, until the error is below 0.3 × the finest target or one run exceeds the
budget; then all scanned runs are repeated in interleaved rounds (round-robin over every
method and setting) and each keeps its best time.  A method's cost at accuracy E is
interpolated in log-log along its cost–error Pareto front (the cheapest measured cost
among settings with error ≤ E, interpolated towards the next cheaper, less accurate one);
the ratio printed is peer cost / rodjit's best cost (the cheapest rodjit integrator at E).
For that integrator a second table splits its call into the compiled loop (its front of
``stats['run_time']``) and the rest, and prints the peer's cost over the loop alone and
the rest a call could have and still meet the target: where the target is missed, it says
whether the steps or the call around them stand in the way.  A third table gives, for
rodjit's best and the fastest peer at each accuracy, the steps of the cheapest measured call
that reaches it and the cost of one (``work_at``): whether the steps are too many or too
dear.

    python benchmarks/bench_peers.py [--quick] [--repeat 3] [--settings paper-mu0,...] [--out NAME]
"""
from __future__ import annotations

import argparse
import importlib.metadata
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402
import peer_rhs  # noqa: E402

import rodjit  # noqa: E402
from rodjit.model.system import initial_state  # noqa: E402
from rodjit.presets import load_preset  # noqa: E402

TARGETS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
TARGET_RATIO = 2.0    # the goal: rodjit's best at least this much faster than the fastest peer
T_END = 1.0
SNAPSHOT = 0.005
TOLS = tuple(10.0 ** (-k / 2) for k in range(4, 27))       # 1e-2 … 1e-13
CFLS = tuple(float(f"{0.05 * 2 ** (-k / 2):.3g}") for k in range(-4, 30))
STIFF_FLOOR = {"floor.kappa_b": 1e5, "floor.beta": 1e-3, "rod.mu": 0.1}

EXPLICIT_CYRK = ("Tsit5", "DOP853", "Vern8")
_clock = time.process_time      # every solve call is timed in CPU time (module docstring)
SETTINGS = {
    "paper-mu0": {"preset": "paper-mu0", "over": {},
                  "peers": [("cyrk", m) for m in (*EXPLICIT_CYRK, "LSODA")]
                  + [("cvode", "Adams"), ("cvode", "BDF"),
                     ("scipy", "DOP853"), ("scipy", "LSODA")]},
    "paper-mu100": {"preset": "paper-mu100", "over": {},
                    "peers": [("cyrk", m) for m in ("Tsit5", "DOP853", "LSODA", "Radau", "BDF")]
                    + [("cvode", "BDF"), ("scipy", "Radau"), ("scipy", "LSODA"),
                       ("scipy", "BDF")]},
    # CyRK's implicit methods are left out on the long rods: their Jacobian is dense, by
    # finite differences (402 right-hand sides and a 402² LU each): CyRK LSODA took 1089 s
    # for its two loosest tolerances at N = 200 (errors 1 and more)
    "floor-N200": {"preset": "paper-mu0", "over": {"rod.N": 200, **STIFF_FLOOR},
                   "peers": [("cyrk", m) for m in ("Tsit5", "DOP853")]
                   + [("cvode", "BDF"), ("scipy", "Radau"), ("scipy", "LSODA")]},
    "floor-N1000": {"preset": "paper-mu0", "over": {"rod.N": 1000, **STIFF_FLOOR},
                    "peers": [("cyrk", "DOP853"), ("cvode", "BDF"), ("scipy", "LSODA")]},
}
RODJIT = ("verlet", "semi-implicit", "energy", "dp54", "dop853", "radau5")
CFL_DRIVEN = ("verlet", "semi-implicit")   # the others take rtol = atol = the scanned value
PEER_DISTRIBUTIONS = {"cyrk": "cyrk", "cvode": "scikit-sundae", "scipy": "scipy"}


def versions() -> dict:
    out = {}
    for dist in ("cyrk", "scikit-sundae", "scipy", "numba", "numpy"):
        try:
            out[dist] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            out[dist] = None
    try:
        import sksundae
        out["sundials"] = sksundae.SUNDIALS_VERSION
    except ImportError:
        pass
    out["rodjit"] = importlib.metadata.version("rodjit")
    return out


def available(lib: str) -> bool:
    try:
        importlib.metadata.version(PEER_DISTRIBUTIONS[lib])
        return True
    except importlib.metadata.PackageNotFoundError:
        return False


class Problem:
    """One setting: its Config, initial state, snapshot times and error measure."""

    def __init__(self, name, over=None):
        spec = SETTINGS[name]
        self.name = name
        cfg = load_preset(spec["preset"]).override({
            **spec["over"], **(over or {}), "time.t_end": T_END,
            "output.snapshot_interval": SNAPSHOT, "output.diagnostics_interval": SNAPSHOT})
        self.cfg = cfg
        self.p = peer_rhs.params(cfg)
        u0, v0 = initial_state(cfg)
        self.y0 = np.concatenate([u0, v0])
        self.y0i = peer_rhs.interleave(self.y0)
        self.n1 = cfg.rod.N + 1
        self.t_eval = SNAPSHOT * np.arange(int(round(T_END / SNAPSHOT)) + 1)
        self.v_scale = math.sqrt(2 * abs(cfg.gravity.g) * cfg.initial.height)
        self.band = cfg.rod.N >= 50        # banded / sparse Jacobians for the long rods

    def error(self, y, ref):
        n1 = self.n1
        eu = np.abs(y[:n1] - ref[:n1]).max()
        ev = np.abs(y[n1:] - ref[n1:]).max() / self.v_scale
        return float(max(eu, ev))


# ---- the solvers: each returns (seconds, y in split order (2 n1, k), info) --------------
_CYRK_ADDR = None


def _cyrk_address():
    """The C address of the right-hand side for CyRK (a Numba cfunc over peer_rhs)."""
    global _CYRK_ADDR
    if _CYRK_ADDR is None:
        import numba
        from numba import carray
        from CyRK.nb.numba_solver import cyjit_sig

        rhs = peer_rhs.rhs_split

        @numba.cfunc(cyjit_sig)
        def cyrk_rhs(dy_ptr, t, y_ptr, p_ptr):
            p = carray(p_ptr, (7,))
            m = 2 * (int(p[0]) + 1)
            rhs(t, carray(y_ptr, (m,)), carray(dy_ptr, (m,)), p)

        _CYRK_ADDR = cyrk_rhs.address
    return _CYRK_ADDR


def run_cyrk(pb, method, tol, t_eval=None):
    from CyRK import nbsolve2_ivp
    addr = _cyrk_address()
    t_eval = pb.t_eval if t_eval is None else t_eval
    t0 = _clock()
    r = nbsolve2_ivp(addr, (0.0, float(t_eval[-1])), pb.y0, method=method, t_eval=t_eval,
                     args=pb.p, rtol=tol, atol=tol, max_num_steps=20_000_000)
    elapsed = _clock() - t0
    ok, steps, msg = r.success, int(r.steps_taken), r.message
    y = np.array(r.y) if ok else None
    r.free()
    if not ok:
        raise RuntimeError(msg)
    return elapsed, y, {"steps": steps}


def pool_init(ready, pb) -> None:
    """A process pool's initializer: the right-hand side's cfunc compiled and
    ``nbsolve2_ivp`` compiled by a first call on the problem ``pb`` (Numba compiles both in
    every process), then ``(pid, seconds)`` put on the queue ``ready``, so that the caller
    can time its pool from the moment every worker is ready."""
    import os
    t0 = time.perf_counter()
    run_cyrk(pb, "DOP853", 1e-6, t_eval=pb.t_eval[:3])
    ready.put((os.getpid(), time.perf_counter() - t0))


def pool_solve(task) -> tuple:
    """One point in a pool worker: ``task`` = (problem, method, tol) as ``run_cyrk`` takes
    them; returns the final state and the steps (not the whole output, which a sweep would
    reduce in the worker too)."""
    pb, method, tol = task
    _, y, info = run_cyrk(pb, method, tol)
    return y[:, -1].copy(), info["steps"]


def _cvode_rhs(t, y, yp, ud):
    peer_rhs.rhs_interleaved(t, y, yp, ud[0])


def run_cvode(pb, method, tol, t_eval=None):
    import sksundae
    t_eval = pb.t_eval if t_eval is None else t_eval
    t0 = _clock()
    # interleaved unknowns: the Jacobian is banded, half-bandwidth 3 (a difference-quotient
    # banded Jacobian, 7 right-hand sides per evaluation)
    solver = sksundae.cvode.CVODE(_cvode_rhs, userdata=(pb.p,), method=method, rtol=tol,
                                  atol=tol, linsolver="band", lband=3, uband=3,
                                  max_num_steps=1_000_000)
    sol = solver.solve(t_eval, pb.y0i)
    elapsed = _clock() - t0
    if not sol.success:
        raise RuntimeError(sol.message)
    return elapsed, peer_rhs.deinterleave(sol.y.T), {"nfev": int(sol.nfev)}


def run_scipy(pb, method, tol, t_eval=None):
    from scipy.integrate import solve_ivp
    from scipy.sparse import SparseEfficiencyWarning, diags
    t_eval = pb.t_eval if t_eval is None else t_eval
    p = pb.p
    rhs = peer_rhs.rhs_interleaved

    def fun(t, y):
        dy = np.empty_like(y)
        rhs(t, y, dy, p)
        return dy

    kw = {}
    if pb.band and method in ("Radau", "BDF"):
        m = pb.y0.size
        kw["jac_sparsity"] = diags([np.ones(m - abs(k)) for k in range(-3, 4)],
                                   list(range(-3, 4)), format="csc")
    if pb.band and method == "LSODA":
        kw.update(lband=3, uband=3)
    t0 = _clock()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SparseEfficiencyWarning)
        sol = solve_ivp(fun, (0.0, float(t_eval[-1])), pb.y0i, method=method, rtol=tol,
                        atol=tol, t_eval=t_eval, **kw)
    elapsed = _clock() - t0
    if sol.status != 0:
        raise RuntimeError(sol.message)
    return elapsed, peer_rhs.deinterleave(sol.y), {"nfev": int(sol.nfev)}


def run_rodjit(pb, integrator, value):
    over = {"time.integrator": integrator}
    if integrator not in CFL_DRIVEN:
        over.update({"time.rtol": value, "time.atol": value})
    else:
        over["time.cfl"] = value
        over["time.control"] = "cfl"
    cfg = pb.cfg.override(over)
    t0 = _clock()
    res = rodjit.simulate(cfg)
    elapsed = _clock() - t0
    if not np.allclose(res.t, pb.t_eval, rtol=0, atol=1e-12):
        raise RuntimeError("rodjit's snapshot times differ from the peers'")
    return elapsed, np.vstack([res.u.T, res.v.T]), {
        "steps": int(res.stats["steps"]), "rejected": int(res.stats["rejected_steps"]),
        "run_time": float(res.stats["run_time"])}


RUNNERS = {"cyrk": run_cyrk, "cvode": run_cvode, "scipy": run_scipy}


class Method:
    def __init__(self, lib, name):
        self.lib, self.name = lib, name
        self.label = f"rodjit {name}" if lib == "rodjit" else f"{lib} {name}"
        self.knob = ("cfl" if name in CFL_DRIVEN else "tol") \
            if lib == "rodjit" else "rtol=atol"
        self.grid = (CFLS if self.knob == "cfl" else TOLS)
        self.points = []

    def run(self, pb, value):
        if self.lib == "rodjit":
            return run_rodjit(pb, self.name, value)
        return RUNNERS[self.lib](pb, self.name, value)


def reference(pb):
    """The reference solution and its check (module docstring)."""
    # on the longest rod the explicit reference is stability-bound (minutes per run): one
    # tolerance looser, and rodjit's energy step is the only check
    tol = 1e-12 if pb.n1 > 500 else 1e-13
    if available("cyrk"):
        _, ref, _ = run_cyrk(pb, "DOP853", tol)
        ref_name = f"CyRK DOP853 rtol=atol={tol:.0e}"
    else:
        _, ref, _ = run_scipy(pb, "DOP853", tol)
        ref_name = f"SciPy DOP853 rtol=atol={tol:.0e}"
    checks = {}
    if available("cyrk") and pb.n1 <= 500:
        _, chk, _ = run_cyrk(pb, "Vern8", 1e-13)
        checks["CyRK Vern8 rtol=atol=1e-13"] = pb.error(chk, ref)
    _, chk, _ = run_rodjit(pb, "energy", 1e-11)
    checks["rodjit energy tol=1e-11"] = pb.error(chk, ref)
    return ref, ref_name, checks


def scan(pb, method, ref, budget, quick, finest):
    """Warm up, then error and time of each setting, coarse to fine."""
    grid = method.grid[::2] if quick else method.grid
    try:
        method.run(pb, grid[0])                     # warm-up: compile, caches
    except Exception:
        pass
    for value in grid:
        try:
            elapsed, y, info = method.run(pb, value)
            err = pb.error(y, ref)
        except (rodjit.SimulationError, RuntimeError) as exc:
            method.points.append({"value": value, "error": math.inf, "times": [],
                                  "failed": str(exc).splitlines()[0][:120]})
            continue
        method.points.append({"value": value, "error": err, "times": [elapsed], **info})
        if err < 0.3 * finest or elapsed > budget:
            break


def repeat_rounds(pb, methods, rounds, budget):
    """Every scanned run again, round-robin over the methods, ``rounds`` times."""
    jobs = [(m, pt) for m in methods for pt in m.points
            if pt["times"] and pt["error"] <= 3 * max(TARGETS) and pt["times"][0] <= budget]
    for r in range(rounds):
        order = jobs if r % 2 == 0 else jobs[::-1]
        for m, pt in order:
            elapsed, _, info = m.run(pb, pt["value"])
            pt["times"].append(elapsed)
            if "run_time" in info:
                pt["run_time"] = min(pt.get("run_time", math.inf), info["run_time"])


def front(points, key="best"):
    """The cost–error Pareto front: errors increasing, costs decreasing."""
    pts = sorted((p["error"], p[key]) for p in points
                 if p["times"] and math.isfinite(p["error"]) and p.get(key) is not None)
    out = []
    for e, t in pts:
        if not out or t < out[-1][1]:
            out.append((e, t))
    return out


def cost_at(fr, target):
    """Cost at error ``target`` interpolated in log-log along a front; None if not reached."""
    if not fr or target < fr[0][0]:
        return None
    for (e0, t0), (e1, t1) in zip(fr, fr[1:]):
        if e0 <= target < e1:
            w = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0)))
    return fr[-1][1]


def breakdown(points, target):
    """``(call, loop)``: a rodjit method's cost at accuracy ``target`` interpolated along
    its front of whole ``simulate`` calls and along the front of its compiled loop alone
    (``stats['run_time']``); None where the method does not reach ``target``.  Their
    difference is what a call costs besides stepping: the run's setup and checks, the
    glue around the compiled calls and the Result."""
    return cost_at(front(points), target), cost_at(front(points, "run_time"), target)


def work_at(points, target):
    """The measured point a method's cost at accuracy ``target`` comes from: the cheapest
    whole call with error ≤ ``target`` (None if none is that accurate), as
    ``{"error", "best", "trials", "per_trial"}``: the step trials of the call (accepted and
    rejected where the method reports both; a peer's step count as its library gives it)
    and the cost of one, the compiled loop over its trials for rodjit (``run_time``), the
    whole call over its steps for a peer.  It tells whether a miss comes from the number
    of steps or from what each costs."""
    ok = [p for p in points if p["times"] and p.get("best") is not None
          and p["error"] <= target and p.get("steps")]
    if not ok:
        return None
    p = min(ok, key=lambda q: q["best"])
    trials = p["steps"] + p.get("rejected", 0)
    per = p.get("run_time", p["best"]) / trials
    return {"error": p["error"], "best": p["best"], "trials": trials, "per_trial": per}


def run_setting(name, quick, rounds, budget):
    pb = Problem(name)
    _util.header(f"{name}: N = {pb.cfg.rod.N}, μ = {pb.cfg.rod.mu}, κ_b = "
                 f"{pb.cfg.floor.kappa_b}, β = {pb.cfg.floor.beta}, T = {T_END} s")
    t0 = time.perf_counter()
    ref, ref_name, checks = reference(pb)
    # the gate: the tightest independent high-order check (the first one), else rodjit's
    ref_diff = next(iter(checks.values()))
    print(f"   reference {ref_name}; differences: " + ", ".join(
        f"{k} {v:.2e}" for k, v in checks.items()) + f" ({time.perf_counter() - t0:.1f} s)")
    targets = [e for e in TARGETS if e >= 10 * ref_diff]
    finest = min(targets) if targets else max(TARGETS)
    methods = [Method("rodjit", i) for i in RODJIT]
    skipped = []
    for lib, m in SETTINGS[name]["peers"]:
        if available(lib):
            methods.append(Method(lib, m))
        else:
            skipped.append(f"{lib} {m} ({PEER_DISTRIBUTIONS[lib]} not installed)")
    for m in methods:
        t1 = time.perf_counter()
        scan(pb, m, ref, budget, quick, finest)
        ok = [p for p in m.points if p["times"]]
        best_err = min((p["error"] for p in ok), default=math.inf)
        print(f"   scanned {m.label:22s} {len(m.points):2d} settings, finest error "
              f"{best_err:.1e} ({time.perf_counter() - t1:.1f} s)")
        sys.stdout.flush()
    repeat_rounds(pb, methods, rounds, budget)
    for m in methods:
        for p in m.points:
            p["best"] = min(p["times"]) if p["times"] else None
            if p["times"]:
                p["spread"] = max(p["times"]) / min(p["times"])

    costs = {m.label: {e: cost_at(front(m.points), e) for e in targets} for m in methods}
    rod_labels = [m.label for m in methods if m.lib == "rodjit"]
    peer_labels = [m.label for m in methods if m.lib != "rodjit"]
    rows, summary = [], {}
    for label in rod_labels + peer_labels:
        rows.append([label] + [("—" if costs[label][e] is None else costs[label][e] * 1e3)
                               for e in targets])
    print("\n   cost (ms) at accuracy, interpolated along each method's front:")
    print("   " + _util.table(rows, ["method"] + [f"{e:.0e}" for e in targets])
          .replace("\n", "\n   "))
    ratio_rows, parts_rows, work_rows = [], [], []
    points = {m.label: m.points for m in methods}
    for e in targets:
        rj = [(costs[l][e], l) for l in rod_labels if costs[l][e] is not None]
        pe = [(costs[l][e], l) for l in peer_labels if costs[l][e] is not None]
        best_rj = min(rj) if rj else None
        best_pe = min(pe) if pe else None
        ratio = best_pe[0] / best_rj[0] if best_rj and best_pe else None
        per_peer = {l: (c / best_rj[0] if best_rj else None) for c, l in pe}
        summary[f"{e:.0e}"] = {"rodjit_best": best_rj and {"method": best_rj[1],
                                                            "seconds": best_rj[0]},
                               "fastest_peer": best_pe and {"method": best_pe[1],
                                                            "seconds": best_pe[0]},
                               "ratio_fastest_peer_over_rodjit": ratio,
                               "ratio_per_peer": per_peer}
        ratio_rows.append([f"{e:.0e}", best_rj[1] if best_rj else "—",
                           best_pe[1] if best_pe else "—",
                           "—" if ratio is None else ratio])
        if best_rj and best_pe:
            call, loop = breakdown(points[best_rj[1]], e)
            if loop is not None:
                rest_allowed = best_pe[0] / TARGET_RATIO - loop
                summary[f"{e:.0e}"].update({
                    "rodjit_loop_seconds": loop, "rodjit_rest_seconds": call - loop,
                    "ratio_fastest_peer_over_rodjit_loop": best_pe[0] / loop,
                    "rest_allowed_for_target_seconds": rest_allowed})
                parts_rows.append([f"{e:.0e}", best_rj[1], call * 1e3, loop * 1e3,
                                   (call - loop) * 1e3, best_pe[0] / loop,
                                   rest_allowed * 1e3])
            w_rj, w_pe = work_at(points[best_rj[1]], e), work_at(points[best_pe[1]], e)
            if w_rj and w_pe:
                summary[f"{e:.0e}"].update({"rodjit_work": w_rj, "fastest_peer_work": w_pe})
                work_rows.append([f"{e:.0e}", best_rj[1], w_rj["trials"],
                                  w_rj["per_trial"] * 1e6, best_pe[1], w_pe["trials"],
                                  w_pe["per_trial"] * 1e6])
    print(f"\n   peer / rodjit-best (< 1: the peer is faster; target ≥ {TARGET_RATIO:g}):")
    print("   " + _util.table(ratio_rows, ["accuracy", "rodjit best", "fastest peer",
                                           "ratio"]).replace("\n", "\n   "))
    if parts_rows:
        print(f"\n   where rodjit's best call goes (ms): its compiled loop and the rest of the "
              f"call; the fastest peer's\n   whole call over the loop alone; the rest a call "
              f"could have and still be {TARGET_RATIO:g}× the peer (< 0: the loop alone "
              f"misses):")
        print("   " + _util.table(parts_rows, ["accuracy", "rodjit best", "call", "loop",
                                               "rest", "peer / loop",
                                               "rest allowed"]).replace("\n", "\n   "))
    if work_rows:
        print("\n   the steps behind it (each method's cheapest measured call at the accuracy):"
              " rodjit's step trials\n   (accepted + rejected) and its loop per trial, the "
              "peer's steps and its whole call per step (µs):")
        print("   " + _util.table(work_rows, ["accuracy", "rodjit best", "trials",
                                              "µs/trial", "fastest peer", "steps",
                                              "µs/step"]).replace("\n", "\n   "))
    for s in skipped:
        print(f"   skipped: {s}")
    spreads = [p["spread"] for m in methods for p in m.points if p.get("spread")
               and len(p["times"]) > 1]
    if spreads:
        print(f"   timing spread (max/min over repeats): median {np.median(spreads):.2f}, "
              f"max {max(spreads):.2f}")
    return {"N": pb.cfg.rod.N, "mu": pb.cfg.rod.mu, "kappa_b": pb.cfg.floor.kappa_b,
            "beta": pb.cfg.floor.beta, "gamma": pb.cfg.rod.gamma, "t_end": T_END,
            "reference": ref_name, "reference_checks": checks,
            "targets": targets, "skipped": skipped,
            "methods": {m.label: {"knob": m.knob, "points": m.points,
                                  "front": front(m.points),
                                  "cost_at": {f"{e:.0e}": costs[m.label][e] for e in targets}}
                        for m in methods},
            "summary": summary}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: the two N = 5 settings, coarse grids, no repeats")
    ap.add_argument("--repeat", type=int, default=3, help="interleaved timing rounds")
    ap.add_argument("--budget", type=float, default=None,
                    help="seconds: a scan stops refining once one run takes longer")
    ap.add_argument("--settings", default=None, help="comma-separated subset of "
                    + ", ".join(SETTINGS))
    ap.add_argument("--out", default=None,
                    help="name of the results file (results/<out>.json; default peers, or "
                         "peers_quick with --quick)")
    args = ap.parse_args(argv)
    names = args.settings.split(",") if args.settings else (
        ["paper-mu0", "paper-mu100"] if args.quick else list(SETTINGS))
    for n in names:
        if n not in SETTINGS:
            ap.error(f"--settings: unknown setting {n!r} (allowed: {', '.join(SETTINGS)})")
    rounds = 0 if args.quick else max(args.repeat - 1, 0)
    budget = args.budget if args.budget is not None else (0.5 if args.quick else 20.0)
    vers = versions()
    print("versions: " + ", ".join(f"{k} {v}" for k, v in vers.items()))
    results = {}
    for n in names:
        results[n] = run_setting(n, args.quick, rounds, budget)
        # written after every setting (a long run interrupted keeps what it measured)
        path = _util.save(args.out or ("peers_quick" if args.quick else "peers"),
                          {"versions": vers, "quick": args.quick, "repeat": args.repeat,
                           "budget_seconds": budget, "complete": len(results) == len(names),
                           "settings": results})
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
