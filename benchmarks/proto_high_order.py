"""Prototype higher-order time steps for the short rod (N = 5), measured against rodjit's
integrators and CyRK at matched accuracy: which scheme should rodjit's loop get?

Candidates, each a plain Numba loop over the same right-hand side as the peers
(benchmarks/peer_rhs.py), landing every step exactly on the output times (rodjit's
contract: it never interpolates), admissibility checked at every stage (a stage or a step
outside ε > −1, u_0 > −β is rejected and retried with a quarter of the step):
  dp54     Dormand–Prince 5(4), FSAL, the classical step-size controller (SciPy's RK45
           coefficients and rules)
  dop853   Dormand–Prince 8(5,3), the same loop (SciPy's DOP853 coefficients and its
           combined 5th/3rd-order error estimate)
  yoshida4 / yoshida6   the kick–drift–kick step composed to order 4 (3 stages) and 6
           (Yoshida's solution A, 7 stages), μ = 0 only (a velocity-free force), with
           rodjit's stiffness-scaled step dt = cfl/√ω² (a fixed step is hopeless here: the
           floor stiffens the bottom node ~10⁴× in contact)
  verlet   the plain kick–drift–kick step in the same loop, the order-2 baseline.

Accuracy, reference and cost as in bench_peers.py (its Problem, scan, repeat rounds and
front interpolation), on paper-mu0 and paper-mu100, for T = 1 s.  Also printed: the steps
and right-hand-side evaluations each scheme needs at each accuracy.

    python benchmarks/proto_high_order.py [--repeat 3] [--settings paper-mu0,paper-mu100]
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numba
import numpy as np
from scipy.integrate._ivp import dop853_coefficients as dop
from scipy.integrate._ivp.rk import RK45

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _util  # noqa: E402
import bench_peers as bp  # noqa: E402
import peer_rhs  # noqa: E402
from peer_rhs import P_BETA, P_KAPPA, P_KAPPA_B, P_N, accel  # noqa: E402

TARGETS = (1e-3, 1e-4, 1e-5, 1e-6)


@numba.njit(cache=True)
def admissible(y, p):
    n = int(p[P_N])
    if not y[0] > -p[P_BETA]:
        return False
    for i in range(n):
        if not y[i + 1] > y[i]:            # ε = n (u_{i+1} − u_i) − 1 > −1
            return False
    for i in range(y.size):
        if not math.isfinite(y[i]):
            return False
    return True


@numba.njit(cache=True)
def _f(y, dy, p):
    n1 = int(p[P_N]) + 1
    dy[:n1] = y[n1:]
    accel(y[:n1], y[n1:], dy[n1:], p)


@numba.njit(cache=True)
def erk_attempt(y, hh, p, A, B, E, E5, dop853, rtol, atol, K, ys, ynew, sc):
    """One trial step of length hh from y (K[0] = f(y) given): the stages into K, the new
    state into ynew, K[ns] = f(ynew).  Returns (admissible, error norm, evaluations)."""
    m = y.size
    ns = B.size
    nfev = 0
    for s in range(1, ns):
        for i in range(m):
            acc_i = 0.0
            for j in range(s):
                acc_i += A[s, j] * K[j, i]
            ys[i] = y[i] + hh * acc_i
        if not admissible(ys, p):
            return False, np.inf, nfev
        _f(ys, K[s], p)
        nfev += 1
    for i in range(m):
        acc_i = 0.0
        for j in range(ns):
            acc_i += B[j] * K[j, i]
        ynew[i] = y[i] + hh * acc_i
    if not admissible(ynew, p):
        return False, np.inf, nfev
    _f(ynew, K[ns], p)
    nfev += 1
    for i in range(m):
        sc[i] = atol + rtol * max(abs(y[i]), abs(ynew[i]))
    if dop853:
        e5 = 0.0
        e3 = 0.0
        for i in range(m):
            a5 = 0.0
            a3 = 0.0
            for j in range(ns + 1):
                a5 += E5[j] * K[j, i]
                a3 += E[j] * K[j, i]
            e5 += (a5 / sc[i]) ** 2
            e3 += (a3 / sc[i]) ** 2
        den = e5 + 0.01 * e3
        err = hh * e5 / math.sqrt(den * m) if den > 0.0 else 0.0
    else:
        e = 0.0
        for i in range(m):
            a = 0.0
            for j in range(ns + 1):
                a += E[j] * K[j, i]
            e += (hh * a / sc[i]) ** 2
        err = math.sqrt(e / m)
    return True, err, nfev


@numba.njit(cache=True)
def _crosses(g0, g1, tol):
    """The bottom passes the floor's kink (u_0 = 0) within the step, not starting on it."""
    return abs(g0) > tol and (g0 > 0.0) != (g1 > 0.0)


@numba.njit(cache=True)
def _illinois(ha, ga, hb, gb, side, hs, g):
    """One Illinois update of the bracket [ha, hb] of a crossing (``g``: the crossing
    function at the trial ``hs``): the end on g's side moves to hs, and the other end's
    value is halved when the same end moved twice in a row."""
    if (g > 0.0) == (ga > 0.0):
        if side == -1:
            gb *= 0.5
        return hs, g, hb, gb, -1
    if side == 1:
        ga *= 0.5
    return ha, ga, hs, g, 1


@numba.njit(cache=True)
def erk_run(y0, p, t_out, rtol, atol, A, B, C, E, E5, dop853, order, events, out):
    """Adaptive embedded RK over the output times ``t_out`` (steps land on them; with
    ``events`` also on every crossing of u_0 = 0, σ_b's kink, found by Illinois regula
    falsi on the step length); the state at each output time into ``out`` (k, m).
    Returns (accepted, rejected, nfev)."""
    m = y0.size
    ns = B.size
    K = np.empty((ns + 1, m))
    y = y0.copy()
    ynew = np.empty(m)
    ys = np.empty(m)
    sc = np.empty(m)
    out[0] = y
    _f(y, K[0], p)
    nfev = 1
    t = t_out[0]
    d0 = 0.0
    d1 = 0.0
    for i in range(m):
        s = atol + rtol * abs(y[i])
        d0 += (y[i] / s) ** 2
        d1 += (K[0, i] / s) ** 2
    d0 = math.sqrt(d0 / m)
    d1 = math.sqrt(d1 / m)
    h = 0.01 * d0 / d1 if d0 > 1e-5 and d1 > 1e-5 else 1e-6
    expo = -1.0 / (order + 1.0)
    acc = 0
    rej = 0
    just_rejected = False
    ktol = 1e-13
    for k in range(1, t_out.size):
        tk = t_out[k]
        while t < tk:
            land = t + h >= tk
            hh = tk - t if land else h
            ok, err, nf = erk_attempt(y, hh, p, A, B, E, E5, dop853, rtol, atol, K, ys,
                                      ynew, sc)
            nfev += nf
            if not ok:
                h = 0.25 * hh
                rej += 1
                just_rejected = True
                continue
            if err <= 1.0 and events and _crosses(y[0], ynew[0], ktol):
                ha = 0.0
                ga = y[0]
                hb = hh
                gb = ynew[0]
                side = 0
                for _ in range(30):
                    hs = ha - ga * (hb - ha) / (gb - ga)
                    ok, err2, nf = erk_attempt(y, hs, p, A, B, E, E5, dop853, rtol, atol,
                                               K, ys, ynew, sc)
                    nfev += nf
                    g = ynew[0]
                    if not ok:
                        break
                    if abs(g) <= ktol:
                        break
                    ha, ga, hb, gb, side = _illinois(ha, ga, hb, gb, side, hs, g)
                if not ok:
                    h = 0.25 * hh
                    rej += 1
                    continue
                land = False
                hh = hs
                err = min(err, err2)
            if err <= 1.0:
                fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** expo)
                if just_rejected:
                    fac = min(fac, 1.0)
                just_rejected = False
                t = tk if land else t + hh
                y[:] = ynew
                K[0] = K[ns]
                acc += 1
                # after a step shortened to land, keep the step the controller wanted
                h = max(h, hh * fac) if land else hh * fac
            else:
                h = hh * max(0.2, 0.9 * err ** expo)
                rej += 1
                just_rejected = True
        out[k] = y
    return acc, rej, nfev


@numba.njit(cache=True)
def omega2(u, p):
    """The Gershgorin bound of rodjit's explicit steps: 4 max f'/h² + 2|σ_b'(u_0)|/h."""
    n = int(p[P_N])
    emin = np.inf
    for i in range(n):
        emin = min(emin, (u[i + 1] - u[i]) * n - 1.0)
    q2 = (1.0 + emin) ** 2
    fp = 0.5 * p[P_KAPPA] * (1.0 + 1.5 / (q2 * q2))
    w2 = 4.0 * fp * n * n
    if u[0] <= 0.0:
        b = p[P_BETA]
        r = b / (u[0] + b)
        w2 += 2.0 * n * 3.0 * p[P_KAPPA_B] * r * r * r / (u[0] + b)
    return w2


@numba.njit(cache=True)
def comp_step(u, v, a, u2, v2, a2, zero, dt, w, p):
    """One composed kick–drift–kick step of length dt from (u, v, a) into (u2, v2, a2)."""
    n1 = u.size
    u2[:] = u
    v2[:] = v
    a2[:] = a
    for wi in w:
        tau = wi * dt
        for i in range(n1):
            v2[i] += 0.5 * tau * a2[i]
            u2[i] += tau * v2[i]
        accel(u2, zero, a2, p)
        for i in range(n1):
            v2[i] += 0.5 * tau * a2[i]
    return w.size


@numba.njit(cache=True)
def kdk_run(y0, p, cfl, t_out, w, events, out):
    """The kick–drift–kick step composed with weights ``w`` (μ = 0), step dt =
    cfl·2/√ω²(u) (rodjit's stiffness-scaled step: the floor stiffens the bottom ~10⁴× in
    contact), shortened to land on the output times and, with ``events``, on every
    crossing of u_0 = 0 (regula falsi on dt).  Returns (steps, force evaluations)."""
    n1 = int(p[P_N]) + 1
    u = y0[:n1].copy()
    v = y0[n1:].copy()
    a = np.empty(n1)
    u2 = np.empty(n1)
    v2 = np.empty(n1)
    a2 = np.empty(n1)
    zero = np.zeros(n1)
    accel(u, zero, a, p)
    nfev = 1
    steps = 0
    out[0, :n1] = u
    out[0, n1:] = v
    t = t_out[0]
    ktol = 1e-13
    for k in range(1, t_out.size):
        tk = t_out[k]
        while t < tk:
            dt = cfl * 2.0 / math.sqrt(omega2(u, p))
            land = t + dt >= tk
            if land:
                dt = tk - t
            nfev += comp_step(u, v, a, u2, v2, a2, zero, dt, w, p)
            if events and _crosses(u[0], u2[0], ktol):
                ha = 0.0
                ga = u[0]
                hb = dt
                gb = u2[0]
                side = 0
                for _ in range(30):
                    hs = ha - ga * (hb - ha) / (gb - ga)
                    nfev += comp_step(u, v, a, u2, v2, a2, zero, hs, w, p)
                    g = u2[0]
                    if abs(g) <= ktol:
                        break
                    ha, ga, hb, gb, side = _illinois(ha, ga, hb, gb, side, hs, g)
                dt = hs
                land = False
            u[:] = u2
            v[:] = v2
            a[:] = a2
            t = tk if land else t + dt
            steps += 1
        out[k, :n1] = u
        out[k, n1:] = v
    return steps, nfev


_C3 = 2.0 ** (1.0 / 3.0)
Y4 = np.array([1 / (2 - _C3), -_C3 / (2 - _C3), 1 / (2 - _C3)])
_w = [-1.17767998417887, 0.235573213359357, 0.784513610477560]
Y6 = np.array([_w[2], _w[1], _w[0], 1 - 2 * sum(_w), _w[0], _w[1], _w[2]])
V2 = np.array([1.0])

TABLEAUS = {
    "dp54": (RK45.A, RK45.B, RK45.C, RK45.E, RK45.E, False, 4),
    "dop853": (dop.A[:dop.N_STAGES, :dop.N_STAGES], dop.B, dop.C[:dop.N_STAGES],
               dop.E3, dop.E5, True, 7),
}
COMPOSITIONS = {"verlet": V2, "yoshida4": Y4, "yoshida6": Y6}
# cfl of the compositions: per stage the step is w_i·dt, so the usable range is wider
COMP_CFLS = tuple(float(f"{1.0 * 2 ** (-k / 2):.3g}") for k in range(0, 30))


class Proto:
    """A prototype with the interface of bench_peers.Method."""

    def __init__(self, name, events=True):
        self.lib, self.name, self.events = "proto", name, events
        self.label = f"proto {name}" + ("" if events else " (no events)")
        self.composition = name in COMPOSITIONS
        self.knob = "cfl" if self.composition else "rtol=atol"
        self.grid = COMP_CFLS if self.composition else bp.TOLS
        self.points = []

    def run(self, pb, value):
        m = pb.y0.size
        out = np.empty((pb.t_eval.size, m))
        t0 = time.perf_counter()
        if self.composition:
            steps, nfev = kdk_run(pb.y0, pb.p, value, pb.t_eval, COMPOSITIONS[self.name],
                                  self.events, out)
            info = {"steps": int(steps), "nfev": int(nfev)}
        else:
            A, B, C, E, E5, is_dop, order = TABLEAUS[self.name]
            acc, rej, nfev = erk_run(pb.y0, pb.p, pb.t_eval, value, value, A, B, C, E, E5,
                                     is_dop, order, self.events, out)
            info = {"steps": int(acc), "rejected": int(rej), "nfev": int(nfev)}
        elapsed = time.perf_counter() - t0
        return elapsed, out.T.copy(), info


def study(name, rounds):
    pb = bp.Problem(name)
    _util.header(f"prototypes on {name} (N = {pb.cfg.rod.N}, μ = {pb.cfg.rod.mu}, T = "
                 f"{bp.T_END} s)")
    ref, ref_name, checks = bp.reference(pb)
    print(f"   reference {ref_name}; " + ", ".join(f"{k} {v:.1e}" for k, v in checks.items()))
    protos = [Proto("dp54"), Proto("dop853")]
    if pb.cfg.rod.mu == 0.0 and pb.cfg.rod.gamma == 0.0:
        protos += [Proto(c) for c in COMPOSITIONS]
    others = [bp.Method("rodjit", i) for i in bp.RODJIT]
    if bp.available("cyrk"):
        others += [bp.Method("cyrk", m) for m in ("Tsit5", "DOP853", "Vern8")]
    methods = protos + others
    finest = min(TARGETS)
    for m in methods:
        bp.scan(pb, m, ref, 5.0, False, finest)
    bp.repeat_rounds(pb, methods, rounds, 5.0)
    for m in methods:
        for pt in m.points:
            pt["best"] = min(pt["times"]) if pt["times"] else None
    rows = []
    result = {}
    for m in methods:
        fr = bp.front(m.points)
        cost = {e: bp.cost_at(fr, e) for e in TARGETS}
        # steps and evaluations of the cheapest setting reaching each accuracy
        work = {}
        for e in TARGETS:
            ok = [pt for pt in m.points if pt["times"] and pt["error"] <= e]
            best = min(ok, key=lambda pt: pt["best"]) if ok else None
            work[e] = best and (best.get("steps"), best.get("nfev"))
        result[m.label] = {"cost_at": {f"{e:.0e}": cost[e] for e in TARGETS},
                           "work_at": {f"{e:.0e}": work[e] for e in TARGETS},
                           "points": m.points}
        rows.append([m.label] + [("—" if cost[e] is None else cost[e] * 1e3) for e in TARGETS]
                    + [("—" if work[e] is None else f"{work[e][0]}/{work[e][1]}")
                       for e in TARGETS])
    heads = ["method"] + [f"ms@{e:.0e}" for e in TARGETS] + [f"steps/nfev@{e:.0e}"
                                                            for e in TARGETS]
    print("   " + _util.table(rows, heads).replace("\n", "\n   "))
    return {"reference": ref_name, "reference_checks": checks, "methods": result}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--settings", default="paper-mu0,paper-mu100")
    args = ap.parse_args(argv)
    res = {n: study(n, max(args.repeat - 1, 0)) for n in args.settings.split(",")}
    path = _util.save("proto_high_order", {"versions": bp.versions(), "settings": res})
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
