"""Prototype one-step schemes on MODEL.md §2 (γ = 0) in NumPy, fixed dt, first bounce.

S0  V(dt/2) K(dt/2) D(dt) K(dt/2) V(dt/2), V = SDIRK2           (rodjit semi-implicit)
S0x the same with V exact (expm)                                  (splitting error alone)
S2  as S1 with the second half-kick backward Euler too (L-stable, damps v)
S1  IMEX Verlet: v½ = (M + dt/2 μK)⁻¹(M v + dt/2 F(u)), u+ = u + dt v½,
    v+ = v½ + dt/2 M⁻¹(F(u+) − μK v½)                             (viscosity with the kicks)
"""
import sys, time, json
import numpy as np
from scipy.linalg import solve_banded, expm
sys.path.insert(0, "tests")
from reference.fd_semidiscrete import FDSystem
from reference.laws import Params

def make(N, mu):
    s = FDSystem(N, Params(mu=mu)); m = s.m; h = s.h
    Kd = s.L.toarray()      # graph Laplacian / h  (viscous force −μ K v)
    def F(u):               # forces without viscosity
        return s.forces(u, np.zeros_like(u))
    def band(c):            # M + c K in banded form
        ab = np.zeros((3, N + 1)); ab[1] = m + c * np.diag(Kd); ab[0, 1:] = c * np.diag(Kd, 1); ab[2, :-1] = c * np.diag(Kd, -1)
        return ab
    return s, m, Kd, F, band

def run(scheme, N, mu, dt, t_end=1.2, est=False):
    s, m, Kd, F, band = make(N, mu)
    y = s.initial(1.0); n1 = N + 1
    u, v = y[:n1].copy(), y[n1:2*n1].copy()
    gs = 1 - 1 / np.sqrt(2)
    cache = {}
    def sdirk(v, tau):
        c = gs * tau * mu
        if ("sd", c) not in cache: cache[("sd", c)] = band(c)
        ab = cache[("sd", c)]
        y1 = solve_banded((1, 1), ab, m * v)
        return solve_banded((1, 1), ab, m * (v + (1 - gs) / gs * (y1 - v)))
    def vexact(v, tau):
        if ("ex", tau) not in cache:
            cache[("ex", tau)] = expm(-tau * mu * (Kd / m[:, None]))
        return cache[("ex", tau)] @ v
    def step(u, v, a, dt):
        if scheme in ("S0", "S0x"):
            V = sdirk if scheme == "S0" else vexact
            v1 = V(v, dt / 2) + dt / 2 * a
            u1 = u + dt * v1
            a1 = F(u1) / m
            v1 = V(v1 + dt / 2 * a1, dt / 2)
            return u1, v1, a1
        if scheme == "S1":
            c = dt / 2 * mu
            if ("be", c) not in cache: cache[("be", c)] = band(c)
            vh = solve_banded((1, 1), cache[("be", c)], m * v + dt / 2 * m * a)
            u1 = u + dt * vh
            a1 = F(u1) / m
            v1 = vh + dt / 2 * (a1 - mu * (Kd @ vh) / m)
            return u1, v1, a1
        if scheme == "S2":      # L-stable variant: backward Euler viscous half-kicks
            c = dt / 2 * mu
            if ("be", c) not in cache: cache[("be", c)] = band(c)
            vh = solve_banded((1, 1), cache[("be", c)], m * v + dt / 2 * m * a)
            u1 = u + dt * vh
            a1 = F(u1) / m
            v1 = solve_banded((1, 1), cache[("be", c)], m * vh + dt / 2 * m * a1)
            return u1, v1, a1
    a = F(u) / m
    t = 0.0; w = lambda v: float(m @ v)
    incontact = False; nep = 0; closed = False; ti = tr = wi = wr = np.nan; minu0 = np.inf; mineps = np.inf
    maxest = 0.0; maxestv = 0.0; nsteps = 0
    tic = time.perf_counter()
    while t < t_end and not closed:
        u1, v1, a1 = step(u, v, a, dt)
        if est:   # step doubling: two half steps vs one full step, on u (max norm / scale)
            uh, vh_, ah = step(u, v, a, dt / 2); uh, vh_, ah = step(uh, vh_, ah, dt / 2)
            maxest = max(maxest, np.max(np.abs(uh - u1)) / 3)
            maxestv = max(maxestv, np.max(np.abs(vh_ - v1)) / 3)
        nsteps += 1
        # events by linear interpolation
        if (u[0] < 0) != (u1[0] < 0):
            th = u[0] / (u[0] - u1[0]); te = t + th * dt; we = w(v) + th * (w(v1) - w(v))
            if not incontact:
                incontact = True
                if nep == 0: ti, wi = te, we
                nep += 1
            else:
                incontact = False; tr, wr = te, we
        if nep and w(v) > 0 and w(v1) <= 0 and not incontact: closed = True
        if nep and not closed:
            minu0 = min(minu0, u1[0]); mineps = min(mineps, s.strains(u1).min())
        u, v, a = u1, v1, a1; t += dt
    return dict(scheme=scheme, N=N, mu=mu, dt=dt, e=-wr / wi, tc=tr - ti, u0=minu0, eps=mineps, nep=nep,
                closed=closed, steps=nsteps, wall=time.perf_counter() - tic, est_u=maxest, est_v=maxestv)

if __name__ == "__main__":
    N = int(sys.argv[1]); mu = float(sys.argv[2]); schemes = sys.argv[3].split(","); dts = [float(x) for x in sys.argv[4].split(",")]
    est = len(sys.argv) > 5
    for sc in schemes:
        for dt in dts:
            print(json.dumps(run(sc, N, mu, dt, est=est)), flush=True)
