"""The semi-discrete system of MODEL.md §2 as a peer's user would write it: one Numba
right-hand side, independent of rodjit's kernels, for the compiled ODE libraries that
bench_peers.py compares rodjit with (CyRK, SUNDIALS CVODE, SciPy) and for the prototype
integrators of proto_high_order.py.

The parameters travel in one float64 array ``p`` (``params``): CyRK's Numba interface passes
its extra arguments as a ``double*``, so every peer gets the same packed form.  Two state
orderings: ``split`` y = [u_0..u_N, v_0..v_N] (what explicit solvers and SciPy see) and
``interleaved`` y = [u_0, v_0, u_1, v_1, …], whose Jacobian is banded with half-bandwidth 3
(a_i depends on u, v at i−1, i, i+1), what a banded linear solver needs.

tests/test_bench_peers.py checks both orderings against rodjit.model.reference.rhs.
"""
from __future__ import annotations

import numba
import numpy as np

# positions in the parameter array
P_N, P_KAPPA, P_KAPPA_B, P_BETA, P_GAMMA, P_MU, P_G = range(7)


def params(config) -> np.ndarray:
    """The packed parameter array of a rodjit Config (Aiki–Kosugi laws only)."""
    if config.rod.law != "aiki-kosugi" or config.floor.law != "aiki-kosugi":
        raise ValueError("the peer right-hand side implements the Aiki–Kosugi laws only")
    return np.array([config.rod.N, config.rod.kappa, config.floor.kappa_b, config.floor.beta,
                     config.rod.gamma, config.rod.mu, config.gravity.g], dtype=np.float64)


@numba.njit(cache=True, fastmath=False)
def accel(u, v, a, p):
    """a_i = (m_i u_i'')/m_i of MODEL.md §2 for heights u and velocities v (length N+1)."""
    n = int(p[P_N])
    kappa = p[P_KAPPA]
    kb = p[P_KAPPA_B]
    beta = p[P_BETA]
    gamma = p[P_GAMMA]
    mu = p[P_MU]
    g = p[P_G]
    h = 1.0 / n
    ih = float(n)
    # segment stress f(ε) + viscous stress μ (v_{i+1} − v_i)/h: the force on node i from the
    # segment above it is +s, on node i+1 it is −s
    s_prev = 0.0
    for i in range(n + 1):
        if i < n:
            e = (u[i + 1] - u[i]) * ih - 1.0
            q = 1.0 + e
            q3 = q * q * q
            s = kappa * e * (2.0 * q3 + q * q + q + 1.0) / (4.0 * q3) \
                + mu * (v[i + 1] - v[i]) * ih
        else:
            s = 0.0
        a[i] = s - s_prev
        s_prev = s
    u0 = u[0]
    if u0 <= 0.0:
        r = beta / (u0 + beta)
        a[0] += kb * (r * r * r - 1.0)
    if gamma > 0.0:
        # −γ h (k_{i−1} − 2k_i + k_{i+1})/h², k_0 = k_N = 0, terms past the ends absent
        ih2 = ih * ih
        for i in range(n + 1):
            km = 0.0
            kc = 0.0
            kp = 0.0
            if 1 <= i - 1 <= n - 1:
                km = (u[i] - 2.0 * u[i - 1] + u[i - 2]) * ih2
            if 1 <= i <= n - 1:
                kc = (u[i + 1] - 2.0 * u[i] + u[i - 1]) * ih2
            if 1 <= i + 1 <= n - 1:
                kp = (u[i + 2] - 2.0 * u[i + 1] + u[i]) * ih2
            a[i] -= gamma * (km - 2.0 * kc + kp) * ih
    # divide by the lumped masses (h/2 at the ends, h inside), add gravity
    a[0] = a[0] * 2.0 * ih + g
    for i in range(1, n):
        a[i] = a[i] * ih + g
    a[n] = a[n] * 2.0 * ih + g


@numba.njit(cache=True)
def rhs_split(t, y, dy, p):
    """dy = d/dt [u, v] for y = [u, v] (in place)."""
    n1 = int(p[P_N]) + 1
    dy[:n1] = y[n1:]
    accel(y[:n1], y[n1:], dy[n1:], p)


@numba.njit(cache=True)
def rhs_interleaved(t, y, dy, p):
    """dy = d/dt y for y = [u_0, v_0, u_1, v_1, …] (in place)."""
    dy[0::2] = y[1::2]
    accel(y[0::2], y[1::2], dy[1::2], p)


def split_state(u, v) -> np.ndarray:
    return np.concatenate([u, v])


def interleave(y_split: np.ndarray) -> np.ndarray:
    """[u, v] (along axis 0) -> [u_0, v_0, u_1, …]."""
    n1 = y_split.shape[0] // 2
    out = np.empty_like(y_split)
    out[0::2] = y_split[:n1]
    out[1::2] = y_split[n1:]
    return out


def deinterleave(y_inter: np.ndarray) -> np.ndarray:
    """[u_0, v_0, u_1, …] (along axis 0) -> [u, v]."""
    return np.concatenate([y_inter[0::2], y_inter[1::2]])
