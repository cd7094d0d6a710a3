"""Step a SciPy implicit solver and extract the first bounce of MODEL.md §3 on the fly.

The solver (``scipy.integrate.Radau`` by default) is stepped by hand so that each step's
dense output is inspected once and then dropped (memory stays O(N) at any number of steps):

* u_0 = 0 crossings (episode ends) and w = 0 crossings from + to − (apexes of the centre of
  mass) are located with ``brentq`` on the step's interpolant, as ``solve_ivp`` would;
* the deepest penetration is located where v_0 crosses 0 from − to + inside contact;
* the smallest strain is tracked by sampling each step's interpolant and polishing the
  smallest sample with a bounded scalar minimisation.

A *bounce* is every episode between two apexes (the start of the run counts as an apex);
an apex only counts while no contact is active.  The first bounce closes at the first apex
after its first episode; if the run ends before, the bounce is *open* (the rod rests).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import Radau
from scipy.optimize import brentq, minimize_scalar


@dataclass
class Probes:
    """How to read the observables from a state vector y."""

    u0: callable          # height of the bottom node
    v0: callable          # its velocity
    w: callable           # centre-of-mass velocity
    strains: callable     # all strains sampled by the discretisation (array)


@dataclass
class FirstBounce:
    t_impact: float = np.nan
    t_release: float = np.nan
    w_impact: float = np.nan
    w_release: float = np.nan
    restitution: float = np.nan
    contact_time: float = np.nan
    min_u0: float = np.inf
    min_strain: float = np.inf
    n_episodes: int = 0
    closed: bool = False          # an apex after release was reached
    released: bool = False        # the last episode ended before the run stopped
    t_apex: float = np.nan
    steps: int = 0
    nfev: int = 0
    njev: int = 0
    nlu: int = 0
    wall: float = 0.0
    episodes: list = field(default_factory=list)

    def as_dict(self) -> dict:
        d = {k: getattr(self, k) for k in (
            "t_impact", "t_release", "w_impact", "w_release", "restitution", "contact_time",
            "min_u0", "min_strain", "n_episodes", "closed", "released", "t_apex", "steps",
            "nfev", "njev", "nlu", "wall")}
        return {k: (v.item() if hasattr(v, "item") else v) for k, v in d.items()}


def _root(fun, a, b):
    return brentq(fun, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)


def first_bounce(fun, jac, y0, t_end, probes: Probes, rtol=1e-10, atol=1e-12,
                 method=Radau, samples=6, max_step=np.inf, jac_sparsity=None) -> FirstBounce:
    """Integrate y' = fun(t, y) from 0 until the first bounce closes (or ``t_end``)."""
    tic = time.perf_counter()
    kw = dict(rtol=rtol, atol=atol, max_step=max_step)
    if jac is not None:
        kw["jac"] = jac
    solver = method(fun, 0.0, y0, t_end, **kw)
    fb = FirstBounce()
    u0 = probes.u0(y0)
    in_contact = u0 < 0.0
    if in_contact:
        raise ValueError("the reference starts out of contact")
    ep_start = np.nan
    tlast = 0.0
    ylast = y0.copy()
    steps = 0
    best = (np.inf, 0.0, 0.0, None)   # smallest sampled strain, its bracket, interpolant
    while solver.status == "running":
        solver.step()
        steps += 1
        if solver.status == "failed":
            raise RuntimeError(f"reference integration failed at t = {solver.t}: "
                               f"{solver.t}")
        t0, t1 = tlast, solver.t
        sol = solver.dense_output()
        y1 = solver.y
        # sample the step: strains, and sign changes of u0 / w / v0 between samples
        ts = np.linspace(t0, t1, samples + 1)
        ys = [ylast] + [sol(t) for t in ts[1:-1]] + [y1]
        # smallest strain (only while the first bounce is active or before it closes)
        if fb.n_episodes > 0 and not fb.closed:
            mins = np.array([probes.strains(y).min() for y in ys])
            k = int(np.argmin(mins))
            if mins[k] < best[0]:
                best = (mins[k], ts[max(k - 1, 0)], ts[min(k + 1, samples)], sol)
        for j in range(samples):
            a, b = ts[j], ts[j + 1]
            ya, yb = ys[j], ys[j + 1]
            # events inside [a, b] in time order: at most one of each per sub-interval is
            # assumed (the sub-intervals are a fraction of an accurate step)
            events = []
            ua, ub = probes.u0(ya), probes.u0(yb)
            if (ua < 0.0) != (ub < 0.0):
                events.append((_root(lambda t: probes.u0(sol(t)), a, b), "u0"))
            wa, wb = probes.w(ya), probes.w(yb)
            if wa > 0.0 and wb <= 0.0:
                events.append((_root(lambda t: probes.w(sol(t)), a, b), "apex"))
            va, vb = probes.v0(ya), probes.v0(yb)
            if va < 0.0 and vb >= 0.0 and fb.n_episodes > 0 and not fb.closed:
                events.append((_root(lambda t: probes.v0(sol(t)), a, b), "deepest"))
            for te, kind in sorted(events):
                ye = sol(te)
                if kind == "u0":
                    if not in_contact:          # touchdown
                        in_contact = True
                        ep_start = te
                        if not fb.closed:
                            if fb.n_episodes == 0:
                                fb.t_impact = te
                                fb.w_impact = probes.w(ye)
                            fb.n_episodes += 1
                    else:                       # release
                        in_contact = False
                        if not fb.closed:
                            fb.episodes.append((ep_start, te))
                            fb.t_release = te
                            fb.w_release = probes.w(ye)
                elif kind == "apex":
                    if not in_contact and fb.n_episodes > 0 and not fb.closed:
                        fb.closed = True
                        fb.t_apex = te
                elif kind == "deepest" and in_contact:
                    fb.min_u0 = min(fb.min_u0, probes.u0(ye))
            if in_contact and fb.n_episodes > 0 and not fb.closed:
                fb.min_u0 = min(fb.min_u0, probes.u0(yb))
        tlast, ylast = t1, y1.copy()
        if fb.closed:
            break
    if best[3] is not None:           # polish the smallest sample once
        m0, lo, hi, bsol = best
        r = minimize_scalar(lambda t: probes.strains(bsol(t)).min(), bounds=(lo, hi),
                            method="bounded", options={"xatol": 1e-14 * max(1.0, hi)})
        fb.min_strain = min(m0, float(r.fun))
    fb.released = not in_contact and fb.n_episodes > 0
    if fb.closed:
        fb.restitution = -fb.w_release / fb.w_impact
        fb.contact_time = fb.t_release - fb.t_impact
    fb.steps = steps
    fb.nfev, fb.njev, fb.nlu = solver.nfev, solver.njev, solver.nlu
    fb.wall = time.perf_counter() - tic
    return fb


def integrate_to(fun, jac, y0, t_out, rtol=1e-10, atol=1e-12, method=Radau):
    """States at the times ``t_out`` (increasing, > 0), stepping with dense output."""
    kw = dict(rtol=rtol, atol=atol)
    if jac is not None:
        kw["jac"] = jac
    solver = method(fun, 0.0, y0, float(t_out[-1]), **kw)
    out = np.empty((len(t_out), len(y0)))
    k = 0
    tlast = 0.0
    while solver.status == "running" and k < len(t_out):
        solver.step()
        if solver.status == "failed":
            raise RuntimeError(f"integration failed at t = {solver.t}")
        sol = solver.dense_output()
        while k < len(t_out) and t_out[k] <= solver.t:
            out[k] = sol(t_out[k]) if t_out[k] > tlast else solver.y
            k += 1
        tlast = solver.t
    return out
