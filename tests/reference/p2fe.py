"""An independent continuum solver for MODEL.md §1 with γ = 0: quadratic (P2) finite
elements in x, consistent mass matrix, SciPy Radau in time.

Weak form (test function φ, the free end and the floor condition γu_xxx − f − μu_tx = +σ_b
at x = 0 built in by integrating by parts: the floor pushes the bottom *up*):

    ∫u_tt φ + ∫f(u_x − 1) φ_x + μ∫u_tx φ_x = g∫φ + σ_b(u(t,0)) φ(0)

so  M ü = −F(u) − μ K u̇ + g b + σ_b(u_0) e_0  with M_jk = ∫φ_jφ_k, K_jk = ∫φ_j'φ_k',
F_j = ∫f(u_x − 1)φ_j' (4-point Gauss per element; u_x is linear on an element) and
b_j = ∫φ_j.  The discrete energy ½u̇ᵀMu̇ + ∫f̂ − σ̂_b(u_0) − g bᵀu (same quadrature) decays
by μ u̇ᵀKu̇, carried as a last component D.

γ > 0 (u_xxxx, u_xx = 0 at both ends) needs C¹ elements (Hermite cubics); not done here.
M is inverted densely (the systems are small), which makes the Jacobian dense.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from . import laws
from .laws import Params
from .trajectory import Probes, first_bounce

_XI, _WQ = np.polynomial.legendre.leggauss(4)
_XI = 0.5 * (_XI + 1.0)
_WQ = 0.5 * _WQ
# derivatives of φ0 = (1−ξ)(1−2ξ), φ1 = 4ξ(1−ξ), φ2 = ξ(2ξ−1) in ξ, at the Gauss points
_DPHI = np.stack([-3.0 + 4.0 * _XI, 4.0 - 8.0 * _XI, 4.0 * _XI - 1.0])       # (3, q)
_DPHI_ENDS = np.array([[-3.0, 1.0], [4.0, -4.0], [-1.0, 3.0]])               # ξ = 0, 1


class P2System:
    def __init__(self, n_elements: int, p: Params):
        if p.gamma != 0.0:
            raise ValueError("p2fe: gamma > 0 needs C1 elements (not implemented)")
        ne = self.ne = n_elements
        self.p = p
        self.h = h = 1.0 / ne
        self.nn = nn = 2 * ne + 1
        self.x = np.arange(nn) * (h / 2)
        self.conn = np.stack([2 * np.arange(ne), 2 * np.arange(ne) + 1, 2 * np.arange(ne) + 2], 1)
        Me = h / 30.0 * np.array([[4, 2, -1], [2, 16, 2], [-1, 2, 4]], float)
        Ke = 1.0 / (3.0 * h) * np.array([[7, -8, 1], [-8, 16, -8], [1, -8, 7]], float)
        be = h * np.array([1 / 6, 2 / 3, 1 / 6])
        M = np.zeros((nn, nn))
        K = np.zeros((nn, nn))
        self.b = np.zeros(nn)
        for c in self.conn:
            M[np.ix_(c, c)] += Me
            K[np.ix_(c, c)] += Ke
            self.b[c] += be
        self.M, self.K = M, K
        self.Minv = np.linalg.inv(M)
        self.MinvK = self.Minv @ K
        self.size = 2 * nn + 1

    def _ux(self, u):
        """u_x at the Gauss points, (ne, q)."""
        ue = u[self.conn]                      # (ne, 3)
        return ue @ _DPHI / self.h

    def strains(self, u):
        """u_x − 1 at both ends of every element (u_x is linear: these bound it)."""
        return (u[self.conn] @ _DPHI_ENDS / self.h - 1.0).ravel()

    def internal(self, u):
        s = laws.f(self._ux(u) - 1.0, self.p.kappa)          # (ne, q)
        Fe = (s * _WQ) @ _DPHI.T                              # (ne, 3): Σ_q w f φ_j'
        F = np.zeros(self.nn)
        np.add.at(F, self.conn, Fe)
        return F

    def rhs(self, t, y):
        p = self.p
        nn = self.nn
        u, v = y[:nn], y[nn:2 * nn]
        r = -self.internal(u) - p.mu * (self.K @ v) + p.g * self.b
        r[0] += laws.sigma_b(u[0], p.kappa_b, p.beta)
        out = np.empty_like(y)
        out[:nn] = v
        out[nn:2 * nn] = self.Minv @ r
        out[-1] = p.mu * v @ (self.K @ v)
        return out

    def jac(self, t, y):
        p = self.p
        nn = self.nn
        u, v = y[:nn], y[nn:2 * nn]
        d = laws.df(self._ux(u) - 1.0, p.kappa) * _WQ / self.h  # (ne, q)
        Ke = np.einsum("eq,jq,kq->ejk", d, _DPHI, _DPHI)
        Ju = np.zeros((nn, nn))
        for e, c in enumerate(self.conn):
            Ju[np.ix_(c, c)] -= Ke[e]
        Ju[0, 0] += laws.dsigma_b(u[0], p.kappa_b, p.beta)
        J = np.zeros((self.size, self.size))
        J[:nn, nn:2 * nn] = np.eye(nn)
        J[nn:2 * nn, :nn] = self.Minv @ Ju
        J[nn:2 * nn, nn:2 * nn] = -p.mu * self.MinvK
        J[-1, nn:2 * nn] = 2.0 * p.mu * (self.K @ v)
        return J

    def energy(self, y):
        p = self.p
        nn = self.nn
        u, v = y[:nn], y[nn:2 * nn]
        stretch = self.h * (laws.f_hat(self._ux(u) - 1.0, p.kappa) * _WQ).sum()
        E = (0.5 * v @ (self.M @ v) + stretch - laws.sigma_b_hat(u[0], p.kappa_b, p.beta)
             - p.g * self.b @ u)
        return E, y[-1]

    def initial(self, height=1.0, velocity=0.0, strain=0.0):
        y = np.zeros(self.size)
        y[: self.nn] = height + (1.0 + strain) * self.x
        y[self.nn: 2 * self.nn] = velocity
        return y

    def probes(self) -> Probes:
        nn = self.nn
        b = self.b
        return Probes(u0=lambda y: y[0], v0=lambda y: y[nn],
                      w=lambda y: float(b @ y[nn:2 * nn]),
                      strains=lambda y: self.strains(y[:nn]))


def continuum_first_bounce(n_elements, p: Params, height=1.0, t_end=5.0, rtol=1e-10, atol=None):
    s = P2System(n_elements, p)
    atol = rtol * 1e-2 if atol is None else atol
    return first_bounce(s.rhs, s.jac, s.initial(height), t_end, s.probes(), rtol=rtol, atol=atol)
