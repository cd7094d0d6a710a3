"""An independent reference for the bounce definition (MODEL.md §3): the semi-discrete
system of ``fd_semidiscrete`` integrated by SciPy's Radau at tight tolerance, with the
contact episodes (sign changes of u_0) and the apexes of the centre of mass (w from + to −)
located by root finding on the dense output, and the episodes grouped into bounces by the
definition written out again here: a release ends a bounce iff the bottom then stays off
the floor for at least τ = π h/c and the centre of mass reaches an apex before the next
contact.  Nothing of rodjit is used.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import Radau
from scipy.optimize import brentq

from .fd_semidiscrete import FDSystem
from .laws import Params


@dataclass
class Bounce:
    t_impact: float
    w_impact: float
    t_release: float = math.nan
    w_release: float = math.nan
    n_episodes: int = 0

    @property
    def restitution(self) -> float:
        return -self.w_release / self.w_impact


@dataclass
class Events:
    episodes: list = field(default_factory=list)   # (t_start, w_start, t_end, w_end)
    apexes: list = field(default_factory=list)


def flight_time(n: int, p: Params) -> float:
    """π h/c with c = sqrt(f'(0)) = sqrt(5κ/4) of the Aiki–Kosugi rod, h = 1/n."""
    return math.pi / (n * math.sqrt(1.25 * p.kappa))


def _root(fun, a, b):
    return brentq(fun, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)


def events(n: int, p: Params, t_end: float, height=1.0, rtol=1e-10, samples=6,
           stop_after_bounces: int | None = None) -> Events:
    """The episodes and apexes of a drop from ``height`` up to ``t_end`` (or until
    ``stop_after_bounces`` bounces are closed by the definition)."""
    s = FDSystem(n, p)
    y0 = s.initial(height)
    n1 = n + 1
    u0 = lambda y: y[0]                                    # noqa: E731
    w = lambda y: float(np.dot(s.m, y[n1:2 * n1]))         # noqa: E731
    solver = Radau(s.rhs, 0.0, y0, t_end, rtol=rtol, atol=rtol * 1e-2, jac=s.jac)
    ev = Events()
    tau = flight_time(n, p)
    in_contact = False
    start = None
    tlast, ylast = 0.0, y0.copy()
    while solver.status == "running":
        solver.step()
        if solver.status == "failed":
            raise RuntimeError(f"reference integration failed at t = {solver.t}")
        sol = solver.dense_output()
        ts = np.linspace(tlast, solver.t, samples + 1)
        ys = [ylast] + [sol(t) for t in ts[1:-1]] + [solver.y]
        for j in range(samples):
            a, b, ya, yb = ts[j], ts[j + 1], ys[j], ys[j + 1]
            found = []
            if (u0(ya) < 0.0) != (u0(yb) < 0.0):
                found.append((_root(lambda t: u0(sol(t)), a, b), "u0"))
            if w(ya) > 0.0 and w(yb) <= 0.0:
                found.append((_root(lambda t: w(sol(t)), a, b), "apex"))
            for te, kind in sorted(found):
                if kind == "apex":
                    ev.apexes.append(te)
                elif not in_contact:
                    in_contact, start = True, (te, w(sol(te)))
                else:
                    in_contact = False
                    ev.episodes.append((start[0], start[1], te, w(sol(te))))
        tlast, ylast = solver.t, solver.y.copy()
        if stop_after_bounces is not None and not in_contact and ev.episodes:
            closed = len(group(ev, tau, tlast)) - (0 if _over(ev, tau, tlast) else 1)
            if closed >= stop_after_bounces:
                break
    return ev


def _over(ev: Events, tau: float, t_now: float) -> bool:
    """The last release is followed by a flight already (no contact since)."""
    t_rel = ev.episodes[-1][2]
    return t_now - t_rel >= tau and any(t_rel < a <= t_now for a in ev.apexes)


def group(ev: Events, tau: float, t_now: float = math.inf) -> list[Bounce]:
    """The bounces of the episodes: a gap is a flight iff it lasts at least ``tau`` and
    holds an apex of the centre of mass."""
    out: list[Bounce] = []
    eps = ev.episodes
    for k, (ts, ws, te, we) in enumerate(eps):
        if k == 0:
            out.append(Bounce(ts, ws))
        else:
            gap_lo, gap_hi = eps[k - 1][2], ts
            flight = gap_hi - gap_lo >= tau and any(gap_lo < a < gap_hi for a in ev.apexes)
            if flight:
                out.append(Bounce(ts, ws))
        b = out[-1]
        b.n_episodes += 1
        b.t_release, b.w_release = te, we
    return out
