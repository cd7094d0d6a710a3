"""MODEL.md §2 written out again in NumPy: the semi-discretisation every rodjit integrator
shares, as a first-order system y = (u, v, D) for SciPy's implicit solvers.

Lumped masses, segment strains, curvatures with k_0 = k_N = 0, the floor force σ_b(u_0) at
node 0 (pushing up), gravity m_i g, the discrete viscous term μ((v_{i+1}−v_i)−(v_i−v_{i−1}))/h
and the dissipated energy D' = 2R(v) = μ Σ h ((v_{i+1}−v_i)/h)² as a last component, so the
balance E_h + D = E_h(0) can be checked.  The Jacobian is analytic and sparse (the solver
factors it with SuperLU).  Integrated at tight tolerance this is the *semi-discrete
reference* for a given N: what rodjit's integrators must reproduce.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from . import laws
from .laws import Params
from .trajectory import Probes, first_bounce


class FDSystem:
    def __init__(self, n: int, p: Params):
        self.n = n
        self.p = p
        self.h = h = 1.0 / n
        self.m = np.full(n + 1, h)
        self.m[0] = self.m[-1] = 0.5 * h
        # discrete −d²/dx² of R(v) = μ/2 vᵀ L v (L: graph Laplacian / h)
        main = np.full(n + 1, 2.0)
        main[0] = main[-1] = 1.0
        self.L = sp.diags([main, -np.ones(n), -np.ones(n)], [0, 1, -1], format="csr") / h
        # bending: force −γ h Bᵀ B u, B: u -> k_i (i = 1..n-1)
        if n >= 2:
            B = sp.diags([np.ones(n - 1), -2 * np.ones(n - 1), np.ones(n - 1)], [0, 1, 2],
                         shape=(n - 1, n + 1)) / h**2
            self.G = (p.gamma * h * (B.T @ B)).tocsr()
        else:
            self.G = sp.csr_matrix((n + 1, n + 1))
        self.D_eps = sp.diags([-np.ones(n), np.ones(n)], [0, 1], shape=(n, n + 1)) / h
        self.size = 2 * (n + 1) + 1

    # --- pieces -------------------------------------------------------------------------
    def strains(self, u):
        return np.diff(u) / self.h - 1.0

    def forces(self, u, v):
        """Σ of the right-hand sides of m_i u_i'' (MODEL.md §2, written out)."""
        p = self.p
        s = laws.f(self.strains(u), p.kappa)     # s_j = f(ε_{j+½})
        F = np.zeros_like(u)
        F[:-1] += s      # node i: + f(ε_{i+½})
        F[1:] -= s       #         − f(ε_{i−½})
        if p.gamma > 0.0:
            F -= self.G @ u
        dv = np.diff(v)                    # μ((v_{i+1}−v_i) − (v_i−v_{i−1}))/h
        F[:-1] += p.mu / self.h * dv
        F[1:] -= p.mu / self.h * dv
        F += self.m * p.g
        F[0] += laws.sigma_b(u[0], p.kappa_b, p.beta)
        return F

    def rhs(self, t, y):
        n1 = self.n + 1
        u, v = y[:n1], y[n1:2 * n1]
        out = np.empty_like(y)
        out[:n1] = v
        out[n1:2 * n1] = self.forces(u, v) / self.m
        dv = np.diff(v) / self.h
        out[-1] = self.p.mu * self.h * np.dot(dv, dv)
        return out

    def jac(self, t, y):
        p = self.p
        n1 = self.n + 1
        u, v = y[:n1], y[n1:2 * n1]
        # F = −h D_epsᵀ f(ε), ε = D_eps u − 1:  ∂F/∂u = −h D_epsᵀ diag(f'(ε)) D_eps
        d = laws.df(self.strains(u), p.kappa)
        K = self.h * (self.D_eps.T @ sp.diags(d) @ self.D_eps)
        Ju = -K - self.G
        Ju = Ju.tolil()
        Ju[0, 0] += laws.dsigma_b(u[0], p.kappa_b, p.beta)
        Ju = Ju.tocsr()
        Jv = -p.mu * self.L
        Minv = sp.diags(1.0 / self.m)
        dv = np.diff(v) / self.h
        # D' = μ h Σ dv²: ∂/∂v = 2 μ h D_epsᵀ dv
        dD = 2.0 * p.mu * self.h * (self.D_eps.T @ dv)
        Z = sp.csr_matrix((n1, n1))
        J = sp.bmat([[Z, sp.identity(n1), None],
                     [Minv @ Ju, Minv @ Jv, None],
                     [None, sp.csr_matrix(dD[None, :]), sp.csr_matrix((1, 1))]],
                    format="csc")
        return J

    def energy(self, y):
        """(E_h, D): MODEL.md §2's discrete energy and the dissipated energy so far."""
        p = self.p
        n1 = self.n + 1
        u, v = y[:n1], y[n1:2 * n1]
        eps = self.strains(u)
        k = (u[2:] - 2 * u[1:-1] + u[:-2]) / self.h**2
        E = (0.5 * np.dot(self.m, v * v) + self.h * laws.f_hat(eps, p.kappa).sum()
             + 0.5 * p.gamma * self.h * np.dot(k, k)
             - laws.sigma_b_hat(u[0], p.kappa_b, p.beta) - p.g * np.dot(self.m, u))
        return E, y[-1]

    def initial(self, height=1.0, velocity=0.0, strain=0.0):
        """Rod at rest shape u_i = height + (1 + strain) x_i, uniform velocity."""
        x = np.arange(self.n + 1) * self.h
        y = np.zeros(self.size)
        y[: self.n + 1] = height + (1.0 + strain) * x
        y[self.n + 1: 2 * (self.n + 1)] = velocity
        return y

    def probes(self) -> Probes:
        n1 = self.n + 1
        m = self.m
        return Probes(u0=lambda y: y[0], v0=lambda y: y[n1],
                      w=lambda y: float(np.dot(m, y[n1:2 * n1])),
                      strains=lambda y: self.strains(y[:n1]))


def reference_first_bounce(n, p: Params, height=1.0, t_end=5.0, rtol=1e-10, atol=None):
    sys_ = FDSystem(n, p)
    atol = rtol * 1e-2 if atol is None else atol
    return first_bounce(sys_.rhs, sys_.jac, sys_.initial(height), t_end, sys_.probes(),
                        rtol=rtol, atol=atol)
